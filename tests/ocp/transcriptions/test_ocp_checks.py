"""No silent wrong answers: definition errors, non-finite guesses, constraints between nodes."""

import math
import warnings

import numpy as np
import pytest

from ocp import (
    Collocation,
    GuessError,
    MultiPhaseProblem,
    MultipleShooting,
    OptimalControlProblem,
    PathViolationError,
    PathViolationWarning,
    ProblemDefinitionError,
    transcribe,
)
from tests.oracles.problems import min_time_double_integrator


def _band_problem():
    """Rest to rest in unit time, min int u^2, with the position above a narrow bump
    ``1 - ((t - 0.55) / 0.05)^2`` centred between the nodes of a 10-interval grid."""
    p = OptimalControlProblem("band")
    x, v = p.state("x"), p.state("v")
    u = p.control("u")
    p.set_dynamics({"x": v, "v": u})
    for s in (x, v):
        p.initial_constraint(s, 0.0)
        p.terminal_constraint(s, 0.0)
    p.path_constraint(x - (1 - ((p.t - 0.55) / 0.05) ** 2), lower=0, name="above the bump")
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    return p


def test_success_never_hides_a_constraint_violated_between_nodes():
    ms = MultipleShooting(_band_problem(), nodes=10)
    with pytest.warns(PathViolationWarning, match="above the bump"):
        sol = ms.solve()
    # Ipopt is happy: the nodes at 0.5 and 0.6 only see x >= 0 and it stays at rest ...
    assert sol.success and sol.objective < 1e-8
    # ... but the solution is flagged, with where and by how much
    assert sol.verified is False
    assert sol.path_violation == pytest.approx(1.0, abs=1e-5)
    assert sol.violations["above the bump"][1] == pytest.approx(0.55, abs=1e-9)
    strict = MultipleShooting(_band_problem(), nodes=10, verify="raise")
    with pytest.raises(PathViolationError) as err:
        strict.solve()
    assert err.value.status == "Path_Violated_Between_Nodes" and err.value.iterate is not None


def test_inner_constraints_and_collocation_refinement_close_the_gap():
    """Imposed at the inner RK4 steps (h/4 apart), the bump is held there, and the
    trajectory dips below it between them: by 2.4e-4 where it was 1.0, and the check
    (the maximum along the trajectory, issue 45) says so where a sampled check did not."""
    with pytest.warns(PathViolationWarning, match="above the bump"):
        inner = MultipleShooting(_band_problem(), nodes=10, inner_constraints=True).solve()
    with warnings.catch_warnings():
        warnings.simplefilter("error", PathViolationWarning)
        refined = Collocation(_band_problem(), intervals=10).refine(tol=1e-8)
    assert not inner.verified and 1e-4 < inner.path_violation < 1e-3
    assert refined.verified and refined.mesh_converged
    assert inner.multipliers["path_inner"].shape == (10 * 3, 1)
    # the bump costs a lot: far from the silent answer 0; the coarse inner-step
    # grid (h/4) is more restrictive than the refined collocation
    assert 190 < refined.objective < inner.objective
    x_bump, _ = refined.at(np.linspace(0.5, 0.6, 101))
    bump = 1 - ((np.linspace(0.5, 0.6, 101) - 0.55) / 0.05) ** 2
    assert np.all(x_bump[:, 0] - bump >= -1e-6)


def _mixed_arc():
    """``x' = u``, ``u + x^2 <= 1`` active on the whole horizon (``x = tanh t``): a
    constraint on a state and a control, held at the collocation points only."""
    p = OptimalControlProblem("mixed")
    x = p.state("x")
    u = p.control("u", -2, 2)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.path_constraint(u + x**2, upper=1.0, name="u + x^2")
    p.fixed_final_time(2.0)
    p.minimize_terminal(-x)
    return p


def test_collocation_checks_mixed_constraints_between_the_points():
    """Issue 31 item 6: between its collocation points the method's control is the
    Lagrange polynomial through them; with it ``u + x^2`` exceeds 1 there (by 7e-4 on 5
    intervals) while Ipopt reports success and the constraint holds at every collocation
    point. On the tree before, a constraint with a control was checked at the collocation
    points only, and this solution said ``verified``; refinement now also closes the gap."""
    with pytest.warns(PathViolationWarning, match=r"u \+ x\^2"):
        sol = Collocation(_mixed_arc(), intervals=5).solve()
    assert sol.success and sol.verified is False and sol.unchecked == []
    viol, t = sol.violations["u + x^2"]
    assert 1e-4 < viol < 1e-2
    tc = sol.transcription.phases[0].tau_c * 2.0  # the collocation points (T = 2)
    inner = tc.reshape(5, -1)[:, :-1].ravel()  # those inside the intervals (not mesh points)
    x, u = sol.at(inner)
    assert np.all(u[:, 0] + x[:, 0] ** 2 <= 1.0 + 1e-7)  # held where it is imposed ...
    assert np.min(np.abs(tc - t)) > 1e-3 and 0.0 < t < 2.0  # ... violated between
    with warnings.catch_warnings():
        warnings.simplefilter("error", PathViolationWarning)
        fine = Collocation(_mixed_arc(), intervals=5).refine(tol=1e-6)
    assert fine.verified and fine.path_violation <= 1e-6
    assert fine.x[-1, 0] == pytest.approx(math.tanh(2.0), abs=1e-6)  # x' = 1 - x^2


def test_control_only_constraints_are_named_as_checked_at_the_points_only():
    """A constraint on the controls alone bounds the control set: between the points the
    interpolant swings across it at a switch, so the verdict leaves it out -- and says so."""
    p = OptimalControlProblem("pair")
    x = p.state("x")
    a, b = p.control("a", 0, 1), p.control("b", 0, 1)
    p.set_dynamics({"x": a - b})
    p.initial_constraint(x, 0.0)
    p.path_constraint(a + b, upper=1.0, name="one at a time")
    p.fixed_final_time(1.0)
    p.minimize_integral((x - 0.5) ** 2 + 1e-3 * (a + b))
    sol = Collocation(p, intervals=4).solve()
    assert sol.unchecked == ["one at a time"] and sol.to_dict()["unchecked"] == sol.unchecked
    assert MultipleShooting(p, nodes=4).solve().unchecked == []  # constant per interval


def test_non_finite_guess_is_named_before_the_solve():
    p = OptimalControlProblem("rocket")
    h, v = p.state("h"), p.state("v")
    # no fixed value and bounds that allow only 0: no other point can make u/m finite
    # (with room in the bounds, the default guess would move m away from 0: see
    # tests/test_scaling_ocp.py)
    m = p.state("m", lower=0.0, upper=0.0)
    u = p.control("u", 0, 1)
    p.set_dynamics({"h": v, "v": u / m - 1, "m": -u})
    p.initial_constraint(h, 0.0)
    p.initial_constraint(v, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_terminal(-h)
    with pytest.raises(GuessError, match=r"dynamics of state 'v'.*\(u/m\).*m=0"):
        MultipleShooting(p, nodes=5).solve()
    # with the mass fixed at the start the default guess interpolates it: fine
    p.initial_constraint(m, 1.0)
    p.bound_state("m", 0.2, 1.0)
    sol = MultipleShooting(p, nodes=10).solve()
    assert sol.success and np.all(sol.x[:, 2] > 0.19)


def test_definition_errors_name_the_argument():
    p = OptimalControlProblem()
    x = p.state("x")
    with pytest.raises(ProblemDefinitionError, match="control 'u'.*lower bound 2 exceeds"):
        p.control("u", lower=2, upper=1)
    u = p.control("w", -1, 1)
    with pytest.raises(ProblemDefinitionError, match="path constraint 'c'.*exceeds"):
        p.path_constraint(x, lower=1, upper=0, name="c")
    with pytest.raises(ProblemDefinitionError, match="state 'x'.*exceeds"):
        p.bound_state("x", 3, 2)
    with pytest.raises(ProblemDefinitionError, match=r"unknown state\(s\) \['y'\]"):
        p.set_dynamics({"x": u, "y": u})
    with pytest.raises(ProblemDefinitionError, match="fixed_final_time"):
        p.fixed_final_time(-1)
    with pytest.raises(ProblemDefinitionError, match="fixed_final_time.*finite"):
        p.fixed_final_time(float("nan"))
    with pytest.raises(ProblemDefinitionError, match="free_final_time"):
        p.free_final_time(2, 1)
    with pytest.raises(ProblemDefinitionError, match="ambiguous"):
        p.boundary_constraint(x, 0.0)
    with pytest.raises(ProblemDefinitionError, match="depends on"):
        p.path_constraint(p.at_tf(x), upper=1)
    p.set_dynamics({"x": u})
    for kwargs in ({"nodes": 2.5}, {"nodes": 0}, {"substeps": 1.5}, {"integrator": "euler"}):
        with pytest.raises(ProblemDefinitionError):
            MultipleShooting(p, **kwargs)
    with pytest.raises(ProblemDefinitionError, match="degree"):
        Collocation(p, degree=0)
    with pytest.raises(ProblemDefinitionError, match="mesh"):
        Collocation(p, mesh=[0.0, 0.6, 0.5, 1.0])
    with pytest.raises(ProblemDefinitionError, match="method"):
        transcribe(p, "pseudospectral")
    with pytest.raises(ProblemDefinitionError, match="verify"):
        MultipleShooting(p, verify="maybe")


def test_parameter_dependent_bounds_in_the_wrong_order_fail_at_solve():
    p = OptimalControlProblem()
    x = p.state("x")
    a = p.parameter("a")
    u = p.control("u", lower=a, upper=1)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.minimize_terminal(x)
    tr = MultipleShooting(p, nodes=4)
    assert tr.solve({"a": 0.5}).x[-1, 0] == pytest.approx(0.5, abs=1e-8)
    with pytest.raises(ProblemDefinitionError, match="lower bound exceeds"):
        tr.solve({"a": 2.0})


def test_multiphase_definition_errors():
    mp = MultiPhaseProblem()
    a, b = mp.phase("a"), mp.phase("b")
    a.state("x")
    b.state("y")
    with pytest.raises(ProblemDefinitionError, match="not in both phases"):
        mp.link(a, b, states=["x"])
    with pytest.raises(ProblemDefinitionError, match="does not belong"):
        mp.link(a, OptimalControlProblem())
    mp.parameter("k")
    with pytest.raises(ProblemDefinitionError, match="already used"):
        b.parameter("k")
    with pytest.raises(ProblemDefinitionError, match="already used"):
        mp.variable("x")


def test_legacy_functions_refuse_what_they_cannot_represent():
    p = OptimalControlProblem()
    x = p.state("x")
    p.control("u")
    p.set_dynamics({"x": p.t})
    assert not p.is_autonomous()
    with pytest.raises(ProblemDefinitionError, match="depend on t"):
        p.dynamics_function()
    p.set_dynamics({"x": -x})
    assert p.is_autonomous() and p.dynamics_function()(1.0, 0.0, []) == -1.0


@pytest.mark.parametrize("name", ["double integrator", "2 phases: a -> b", "!!!", "été"])
def test_a_problem_named_with_any_label_solves(name):
    """The name is a label: CasADi's function names (identifiers) are derived from it."""
    p = min_time_double_integrator(name=name)
    for tr in (MultipleShooting(p, nodes=10), Collocation(p, intervals=5)):
        assert tr.solve({"d": 1.0}).T == pytest.approx(2.0, abs=0.01)  # bang-bang: 2
