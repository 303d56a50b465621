"""The suite's bang-bang problems refined and certified with default settings; its singular
problems, from a multiple-shooting transcription alone, are "inconclusive" (never refuted)."""

import pytest

from ocp import MultipleShooting, certify
from ocp.certificate.certify import CERTIFIED, INCONCLUSIVE
from ocp.structure.switching import detect_structure, refine_switching
from tests.oracles.ocp_suite import problems as P


def test_moon_lander_refines_to_the_closed_form_and_is_certified(moon_lander_shooting):
    # 60 nodes, refine_switching(sol) (its structure: detect_structure(sol)), certify(sol, r)
    sol, r, c = moon_lander_shooting  # (tests/ocp/conftest.py)
    assert r.kinds == ["min", "max"]  # free fall, then full thrust (Meditch 1964)
    assert r.objective == pytest.approx(P.moon_lander_exact(), rel=1e-9)
    assert c.verdict == CERTIFIED, c.reasons


@pytest.mark.slow
def test_robot_arm_three_controls_refined_and_certified():
    sol = MultipleShooting(P.robot_arm(), nodes=80).solve({})
    r = refine_switching(sol, detect_structure(sol))
    # COPS 'robot' publishes 9.14138 from a discretised NLP; the refinement's exact
    # switching times give 9.1409117 (collocation with mesh refinement: 9.1409143)
    assert r.objective == pytest.approx(9.14091, abs=2e-5)
    assert r.objective < sol.objective
    c = certify(sol, r)
    assert c.verdict == CERTIFIED, c.reasons
    assert len(r.controls) == 3


@pytest.mark.parametrize("name", ["catalyst_mixing", "goddard"])
def test_singular_optima_from_a_transcription_are_inconclusive_never_refuted(name):
    # the transcription's control on the singular arc is off the singular control by the
    # grid's error (0.13-0.17 here): that names the arc and refutes nothing (these are the
    # published optima); refine_switching flies the arc exactly (test_singular_arcs.py)
    sol = MultipleShooting(getattr(P, name)(), nodes=100).solve({})
    st = detect_structure(sol)
    assert not st.refinable  # a bang, an interior (singular) arc, a bang
    c = certify(sol)
    assert c.verdict == INCONCLUSIVE, c.reasons
    assert any(r.kind == "singular" and r.order == 1 for r in c.arcs)
    assert any("refine_switching" in r for r in c.reasons)
