"""ocp's certificate and switching-time refinement on the landing (moved from tests/ocp,
which runs without softlanding: the ocp-only job of .ci/run).

The certificate: the landing certified bang-bang, its altered schedules refuted, the
constrained tail of the transcription alone certified as a state boundary arc, the CLI's
``--pmp --json``. The refinement: one NLP for every impact velocity, the Newton fast path
agreeing with Ipopt, and the compiled Newton with the Python loop.
"""

import dataclasses
import json

import numpy as np
import pytest

from ocp import certify
from ocp.certificate.certify import CERTIFIED, NOT_BANG_BANG
from ocp.structure.switching import clear_cache, detect_arcs, refine_structure, refine_switching
from softlanding.optimal.landing import solve_landing


@pytest.mark.parametrize("v0", [-0.5, -3.0, -7.0, -10.0])
def test_soft_landing_is_certified_bang_bang(v0):
    r = solve_landing(v0, replay=False)
    c = certify(r.transcribed, r.refined)
    assert c.verdict == CERTIFIED, c.reasons
    assert len(r.switch_times) == 1 and r.arcs == ["max", "min"]
    assert c.H_expected == 0.0 and c.H_max_abs < 1e-9
    assert c.switch_sigma_gap < 1e-9
    assert c.sigma_sign_agreement == 1.0
    assert c.costate_estimates_gap < 1e-2


@pytest.mark.parametrize("how", ["late switch", "early switch", "swapped arcs"])
def test_non_optimal_landing_is_refuted(how):
    r = solve_landing(-3.0, replay=False)
    ref = r.refined
    if how == "late switch":
        bad = dataclasses.replace(ref, durations=ref.durations * np.array([1.05, 0.96]))
    elif how == "early switch":
        bad = dataclasses.replace(ref, durations=ref.durations * np.array([0.9, 1.07]))
    else:
        bad = dataclasses.replace(ref, values=list(reversed(ref.values)))
    c = certify(r.transcribed, bad)
    assert c.verdict == NOT_BANG_BANG
    assert c.reasons


def test_transcription_alone_certifies_the_constrained_tail():
    # at v0 = -10 the transcription ends with an arc on which v_f <= 0 is active. This test
    # asserted the old limitation ("inconclusive": a state constraint active, left out of
    # the checks); the tail is now checked as a state boundary arc of order 1 (on the
    # constraint, the boundary control law, the multiplier's sign, the costate equation).
    r = solve_landing(-10.0, replay=False)
    c = certify(r.transcribed)
    assert c.verdict == "certified (bang, state boundary order 1)", c.reasons
    assert c.state_constraint_active_intervals
    (arc,) = [a for a in c.arcs if a.kind == "state boundary"]
    assert arc.control == "foot descending v_f <= 0" and arc.order == 1
    assert arc.end == pytest.approx(r.transcribed.T)
    assert arc.residuals["boundary control |u - u_b|"] < 1e-6


def test_cli_pmp_json(tmp_path, cli):
    png = tmp_path / "bb.png"
    code, out, err = cli("solve", "--v0", "-2", "--pmp", "--json", "--plot", png)
    assert code == 0, err
    d = json.loads(out)["pmp"]
    for k in ("verdict", "H_max_abs", "H_variation", "sigma_sign_agreement", "switch_sigma_gap",
              "singular_intervals", "state_constraint_active_intervals",
              "costate_estimates_gap"):
        assert k in d
    assert d["verdict"] == CERTIFIED
    assert (tmp_path / "bb-pmp.png").stat().st_size > 10_000


def test_parametric_landing_refinement_is_reused_and_fast_path_agrees():
    sols = [solve_landing(v, replay=False, refine=False).transcribed for v in (-2.0, -4.0, -6.0)]
    sts = [detect_arcs(s).without_trailing_constrained() for s in sols]
    ipopt = [refine_switching(s, st, fast=False) for s, st in zip(sols, sts, strict=True)]
    newton = [refine_switching(s, st, fast=True) for s, st in zip(sols, sts, strict=True)]
    assert len({id(r.nlp) for r in ipopt + newton}) == 1  # one NLP for every v0
    assert [r.path for r in ipopt] == ["ipopt"] * 3
    assert [r.path for r in newton] == ["newton"] * 3
    for a, b in zip(ipopt, newton, strict=True):
        assert abs(a.xT[2] - b.xT[2]) <= 1e-12
        np.testing.assert_allclose(a.durations, b.durations, atol=1e-12)


def test_compiled_newton_agrees_with_the_python_loop_and_is_built_once():
    sol = solve_landing(-3.0, replay=False, refine=False).transcribed
    st = detect_arcs(sol).without_trailing_constrained()
    clear_cache(sol.problem)
    first = refine_switching(sol, st, fast=False)
    nlp, pv = first.nlp, np.array([first.params[k] for k in sol.problem.param_names])
    pv[sol.problem.param_names.index("v0")] = -3.2
    r = nlp.newton(pv, first.w)
    assert r is not None and r["path"] == "newton" and r["primal"] <= 1e-12
    assert len(nlp._newton_cache) == 1
    rows, _, cols, _ = nlp.active_set()
    target = np.where(nlp.active_set()[1] > 0, nlp.bounds(pv)["ubg"][rows],
                      nlp.bounds(pv)["lbg"][rows])
    w = first.w.copy()
    assert nlp._newton_iterate(w, pv, rows, target, cols, 12) > 0
    np.testing.assert_allclose(r["w"], w, rtol=0, atol=1e-13)
    assert nlp.newton(pv, first.w) is not None and len(nlp._newton_cache) == 1
    # the re-solve reports what a fresh Ipopt solve at the new velocity reports
    fresh = refine_structure(sol.problem, first.modes, first.durations, r["w"][nlp.K:],
                             {**first.params, "v0": -3.2}, fast=False)
    np.testing.assert_allclose(fresh.durations, r["w"][:nlp.K], rtol=0, atol=1e-12)
    assert fresh.end_path_violation == pytest.approx(
        nlp.summary(r["w"], pv)["end_violation"], abs=1e-12)
