"""Singular arcs refined by the default route (issue 44 item 3): ``refine_switching`` and
``refine_phases`` make every interior arc of a control that enters H linearly with a
singular order a singular arc, flown with its singular feedback, and refine the junctions.

Independent references: ``min int x^2``, ``x' = u``, ``|u| <= 1``, ``x(0) = 1``, ``T = 2``
has ``u = -1`` until ``t = 1`` then ``u = 0``, ``J = 1/3``; COPS 3.0 (Dolan, More, Munson
2004) publishes ``J = -4.80556e-2`` for 'catmix' (Gunn and Thomas 1965) and ``h(T) = 1.01283``
for 'rocket' (Goddard), both from discretised NLPs; multiple shooting on finer grids
converges to the refined values from the feasible side.
"""

from __future__ import annotations

import pytest

from ocp import MultiPhaseProblem, MultipleShooting, certify, refine_phases, refine_switching
from tests.oracles.ocp_suite import problems as P


def _two_phase_singular() -> MultiPhaseProblem:
    """``min int x^2``, ``x' = u``, ``|u| <= 1`` over [0, 2] in two phases, the second (from
    ``t = 0.5``) holding the bang-singular junction ``t = 1``: ``J = 1/3``."""
    mp = MultiPhaseProblem("singular_two_phases")
    a, b = mp.phase("a"), mp.phase("b")
    for ph in (a, b):
        x = ph.state("x")
        ph.control("u", -1, 1)
        ph.set_dynamics({"x": ph.u[0]})
        ph.minimize_integral(x**2)
    a.initial_constraint(a.x[0], 1.0)
    a.fixed_final_time(0.5)
    b.fixed_duration(1.5)
    mp.link(a, b)
    return mp


@pytest.fixture(scope="module")
def catalyst():
    sol = MultipleShooting(P.catalyst_mixing(), nodes=100).solve({})
    return sol, refine_switching(sol)


def test_catalyst_mixing_refined_and_certified(catalyst):
    sol, r = catalyst
    assert r.kinds == ["max", "singular", "min"]
    # COPS' six digits (a discretisation's); the transcription is below the refinement
    assert r.objective == pytest.approx(-4.80556e-2, abs=2e-7)
    assert r.objective < sol.objective
    assert r.success and r.integration_error <= 1e-10
    c = certify(sol, r)
    assert c.verdict == "certified (bang, singular order 1)", c.reasons
    (arc,) = [a for a in c.arcs if a.kind == "singular"]
    assert arc.order == 1 and arc.status == "holds"
    assert arc.start == pytest.approx(r.switch_times[0]) and arc.end == pytest.approx(
        r.switch_times[1])


def test_refine_phases_refines_a_singular_arc():
    sol = MultipleShooting(_two_phase_singular(), nodes=[10, 30]).solve({})
    r = refine_phases(sol)
    assert r.kinds == [["min"], ["min", "singular"]]
    assert r.objective == pytest.approx(1 / 3, abs=1e-12)
    assert r.t0[1] + r.phases[1].switch_times[0] == pytest.approx(1.0, abs=1e-12)
    c = certify(sol, r)
    assert c.verdict == "certified (bang, singular order 1)", c.reasons


@pytest.mark.slow
def test_catalyst_refinement_above_finer_transcriptions(catalyst):
    """Every shooting transcription is a feasible candidate: its objective is above the
    refined optimum's and converges to it."""
    _, r = catalyst
    gaps = [MultipleShooting(P.catalyst_mixing(), nodes=n).solve({}).objective - r.objective
            for n in (200, 400)]
    assert all(g > 0 for g in gaps) and gaps[1] < gaps[0] < 1e-7


@pytest.mark.slow
def test_goddard_refined_and_never_refuted():
    """COPS 'rocket': full thrust, a singular arc, a coast on which the mass sits at its
    bound ``m >= m_f`` to the end (redundant with ``m(T) = m_f``, ``m' <= 0``): the refined
    altitude agrees with COPS' five digits and is above every shooting transcription's;
    the certificate cannot sweep an unconstrained costate and says so (it refuted the
    optimum before: a path row's multiplier left the coast's costate wrong)."""
    sol = MultipleShooting(P.goddard(), nodes=100).solve({})
    r = refine_switching(sol)
    assert r.kinds == ["max", "singular", "min"]
    h = -r.objective
    assert h == pytest.approx(1.01283, abs=1e-5)
    finer = -MultipleShooting(P.goddard(), nodes=400).solve({}).objective
    assert 0 <= h - finer < 1e-7
    c = certify(sol, r)
    assert c.verdict == "inconclusive" and "up to the final time" in c.reasons[0]
