"""Refinement and certificate at the edges an adversarial review of ``ocp`` found: a circle's
end condition, a touch point, a single arc, and arguments that used to be ignored.

Independent references (closed forms): ``x' = u1, y' = u2`` from (3, 4) to the unit circle in
time 1 with cost ``int |u|^2 / 2``: the straight path to (0.6, 0.8), ``J = 4^2 / 2 = 8``.
Bryson-Denham with ``x <= l = 1/6``: ``J = 4 / (9 l) = 8/3``, the constraint touched at one
point (a boundary arc of length ``1 - 6 l = 0``). Minimum time from (2, -2) to the origin under
``x'' = u``, ``|u| <= 1``: the start lies on the switching curve, one arc ``u = +1``, ``T = 2``.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from ocp import (
    InfeasibleError,
    MultipleShooting,
    OptimalControlProblem,
    ProblemDefinitionError,
    SolveError,
    certify,
    refine_switching,
)
from ocp.certificate.checks import CERTIFIED, INCONCLUSIVE
from ocp.structure.switching import note_above_transcription
from tests.oracles.ocp_suite.problems import bryson_denham


def _to_circle() -> OptimalControlProblem:
    p = OptimalControlProblem("to the circle")
    x, y = p.state("x"), p.state("y")
    u1, u2 = p.control("u1"), p.control("u2")
    p.set_dynamics({"x": u1, "y": u2})
    p.initial_constraint(x, 3.0)
    p.initial_constraint(y, 4.0)
    p.terminal_constraint(x**2 + y**2, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(0.5 * (u1**2 + u2**2))
    return p


def test_a_second_refinement_with_a_circles_end_condition_re_solves():
    # the Newton re-solve's rootfinder cannot be built on this active set (CasADi: the
    # Jacobian is structurally rank-deficient): the second refinement raised that
    # RuntimeError instead of falling back to Ipopt
    p = _to_circle()
    for _ in range(2):
        ref = refine_switching(MultipleShooting(p, 20).solve())
        assert ref.objective == pytest.approx(8.0, rel=1e-13)


def test_a_touch_point_refined_as_a_tiny_boundary_arc_is_inconclusive_at_once():
    # the refinement keeps a 5e-6 boundary arc where the optimum touches x = 1/6 once; the
    # certificate sampled the horizon at 400 / 5e-6 points (minutes) and, sampled on the
    # arc only, would refute it by about its length: neither is a touch point's verdict
    sol = MultipleShooting(bryson_denham(1 / 6), 60).solve()
    ref = refine_switching(sol)
    assert ref.objective == pytest.approx(8 / 3, rel=1e-12)
    cert = certify(sol, ref)
    assert cert.verdict == INCONCLUSIVE
    [arc] = [a for a in cert.arcs if a.kind == "state boundary"]
    assert arc.status == "uncertain" and "cannot be told from a touch point" in arc.notes[-1]
    # a longer arc is still held to a boundary arc's conditions, and certified
    sol = MultipleShooting(bryson_denham(0.166), 60).solve()
    assert certify(sol, refine_switching(sol)).verdict.startswith("certified (")


def test_a_single_arc_fixed_by_its_end_conditions_says_so():
    p = OptimalControlProblem("minimum time")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 2.0)
    p.initial_constraint(v, -2.0)
    p.terminal_constraint(x, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.01, 100.0)
    p.minimize_terminal(p.T)
    sol = MultipleShooting(p, 40).solve()
    assert sol.T == pytest.approx(2.0, abs=1e-6) and certify(sol).verdict == CERTIFIED
    with pytest.raises(SolveError, match="leave 3 unknowns .* to 4 equality conditions, so its "
                                         "end conditions fix it"):
        refine_switching(sol)


@pytest.mark.parametrize("call, message", [
    (lambda s: certify(s, tol_H=-1.0), r"certify\(tol_H\) must be > 0"),
    (lambda s: certify(s, tol_sigma=float("nan")), r"certify\(tol_sigma\) must be finite"),
    (lambda s: certify(s, n=0), r"certify\(n\) must be >= 10"),
    (lambda s: refine_switching(s, tol=-1.0), r"refine_switching\(tol\) must be a relative"),
    (lambda s: refine_switching(s, interior_samples=0), r"interior_samples\) must be >= 1"),
    (lambda s: refine_switching(s, extra_arcs=-1), r"extra_arcs\) must be >= 0"),
    (lambda s: refine_switching(s, params={"zz": 1.0}), r"\['zz'\] are not parameters"),
])
def test_arguments_that_check_nothing_are_refused(call, message):
    # each was accepted: a negative tolerance, no samples (certified from nothing), an
    # unknown parameter name (ignored)
    sol = MultipleShooting(_to_circle(), 10).solve()
    with pytest.raises(ProblemDefinitionError, match=message):
        call(sol)


def test_expand_with_cvodes_is_refused_not_ignored():
    with pytest.raises(ProblemDefinitionError, match="expand=True applies to integrator='rk4'"):
        MultipleShooting(_to_circle(), 10, integrator="cvodes", expand=True)


def test_extra_arcs_without_a_bang_arc_say_why():
    p = OptimalControlProblem("LQ")
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(x**2 + u**2)
    sol = MultipleShooting(p, 20).solve()
    with pytest.raises(ValueError, match="no bang arc to insert them beside"):
        refine_switching(sol, extra_arcs=2)


def test_a_refinement_above_its_transcription_says_so():
    # an oscillator's minimum time from (4.5, 0): the transcription's structure missed a
    # short first arc and the refinement landed at 7.4502 above the grid's 7.4102, unnoted
    out = SimpleNamespace(objective=7.4502451529302585, notes=[])
    note_above_transcription(out, 7.410208323410161)
    assert out.notes == ["the refined objective 7.450245153 is above the transcription's "
                         "7.410208323 (by 0.04): the detected structure may lack an arc the "
                         "grid resolves (compare a finer grid, or extra_arcs)"]
    below = SimpleNamespace(objective=7.40, notes=[])
    note_above_transcription(below, 7.41)  # the usual case: at or below the grid's
    assert below.notes == []


def test_an_infeasibility_verdict_says_it_is_local():
    p = OptimalControlProblem("contradiction")
    x = p.state("x")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.terminal_constraint(x, 0.0)
    p.terminal_constraint(x, 1.0)
    p.fixed_final_time(2.0)
    p.minimize_integral(u**2)
    with pytest.raises(InfeasibleError, match=r"a local verdict: from another guess a "
                                              r"feasible problem may solve\): end conditions"):
        MultipleShooting(p, 10).solve()
