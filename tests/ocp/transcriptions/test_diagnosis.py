"""Failures that name their cause (issue 45, item 3).

On the tree before: a rotation whose norm is fixed at both ends failed with
``InfeasibleError: Infeasible_Problem_Detected after 2985 iterations`` and nothing
else (no ``diagnosis``, no ``drop_dependent``); an end condition outside its state's
bounds, a condition posed at an extremum of its expression (``sin(psi) = -1``) and an
unbounded heading entering only through ``cos``/``sin`` were not named either, and mesh
refinement that stopped short said nothing. Every test below fails there.

Independent references: the rotation's optimum is ``angle^2 / T`` in closed form (a
constant rate is optimal for ``min int w^2``), and its conserved quantity
``x^2 + y^2`` is conserved by ``x' = -w y, y' = w x`` by inspection.
"""

from __future__ import annotations

import math
import warnings

import casadi as ca
import numpy as np
import pytest

from ocp import (
    Collocation,
    ConvergenceWarning,
    DroppedConditionWarning,
    InfeasibleError,
    MultipleShooting,
    OptimalControlProblem,
    SolveError,
)
from ocp.transcriptions.diagnosis import periodic_states

ANGLE = 3.0


def rotation() -> OptimalControlProblem:
    """``x' = -w y, y' = w x`` from (1, 0) to the point at ``ANGLE``, ``min int w^2``: the
    dynamics conserve ``x^2 + y^2``, which the four end conditions fix twice."""
    p = OptimalControlProblem("rotation")
    x, y = p.state("x"), p.state("y")
    w = p.control("w")
    p.set_dynamics({"x": -w * y, "y": w * x})
    p.initial_constraint(x, 1.0)
    p.initial_constraint(y, 0.0)
    p.terminal_constraint(x, math.cos(ANGLE))
    p.terminal_constraint(y, math.sin(ANGLE))
    p.fixed_final_time(1.0)
    p.minimize_integral(w**2)
    return p


@pytest.fixture(scope="module")
def rotation_failure():
    # RK4 on 10 nodes drifts the norm by ~1e-3: the discrete end conditions conflict
    # (with Ipopt's 3000 iterations: Infeasible_Problem_Detected after 2985; 100 here)
    tr = MultipleShooting(rotation(), nodes=10, ipopt_options={"max_iter": 100})
    with pytest.raises(SolveError) as info:
        tr.solve()
    return tr, info.value


def test_conserved_norm_names_the_dependent_end_conditions(rotation_failure):
    _, err = rotation_failure
    msg = str(err)
    assert "\n" not in msg  # one line
    assert msg.startswith("Ipopt failed: Maximum_Iterations_Exceeded after 100 iterations: ")
    d = err.diagnosis
    assert d.n_equalities == 4 and d.rank == 3  # x(0), y(0), x(T), y(T): one dependence
    # y(0) = 0 has weight 0 in the norm's gradient (2y = 0 there): not part of it
    assert d.dependent == ["initial 'x(t0) = 1'", f"terminal 'x(tf) = {math.cos(ANGLE):g}'",
                           f"terminal 'y(tf) = {math.sin(ANGLE):g}'"]
    assert d.conserved == "x^2 + y^2"
    assert "x^2 + y^2 is conserved by the dynamics and fixed at both ends" in msg
    assert "drop_dependent=True" in msg
    # the null combination is the norm's gradient at the ends (rows of unit gradient):
    # x(0) at one end against -(x(T), y(T)) at the other, to the discretisation's drift
    w = np.array(list(d.weights.values()))
    assert np.allclose(w / w[0], [1.0, 0.0, -math.cos(ANGLE), -math.sin(ANGLE)], atol=2e-3)


def test_dropping_the_dependent_condition_solves(rotation_failure):
    tr, _ = rotation_failure
    with pytest.warns(DroppedConditionWarning, match="terminal 'x"):
        sol = tr.solve(drop_dependent=True)
    assert sol.success
    assert sol.dropped == [f"terminal 'x(tf) = {math.cos(ANGLE):g}'"]  # the largest weight
    assert sol.dropped_residual < 1e-6  # met anyway, to the drift; on its branch
    assert sol.objective == pytest.approx(ANGLE**2, rel=1e-5)  # angle^2 / T
    xT = sol.x[-1]
    assert xT[0] == pytest.approx(math.cos(ANGLE), abs=1e-6)
    assert xT[1] == pytest.approx(math.sin(ANGLE), abs=1e-9)


def test_end_condition_outside_the_bounds_is_named():
    p = OptimalControlProblem("box")
    x = p.state("x", lower=0.0, upper=3.0)
    v = p.state("v")
    u = p.control("u", lower=-1.0, upper=1.0)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x, 5.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.1, 20.0)
    p.minimize_terminal(p.T)
    with pytest.raises(InfeasibleError, match=r"cannot be met together: terminal 'x\(tf\) = 5' "
                                              r"with its variable within \[0, 3\]"):
        Collocation(p, intervals=10).solve()


def dubins(bounded: bool = False, target: tuple[float, float] = (-1.0, 0.5),
           heading: bool = False) -> OptimalControlProblem:
    """A car turning at most at rate 1 to a point, in minimum time; its heading enters
    only through cos and sin. ``heading``: also point it down at the end, posed as
    ``cos(psi) = 0, sin(psi) = -1`` (the second at its minimum: a vanishing gradient)."""
    p = OptimalControlProblem("dubins")
    x, y = p.state("x"), p.state("y")
    psi = p.state("psi", **({"lower": -2 * math.pi, "upper": 2 * math.pi} if bounded else {}))
    u = p.control("u", lower=-1.0, upper=1.0)
    p.set_dynamics({"x": ca.cos(psi), "y": ca.sin(psi), "psi": u})
    for s in (x, y, psi):
        p.initial_constraint(s, 0.0)
    p.terminal_constraint(x, target[0])
    p.terminal_constraint(y, target[1])
    if heading:
        p.terminal_constraint(ca.cos(psi), 0.0)
        p.terminal_constraint(ca.sin(psi), -1.0)
    p.free_final_time(0.1, 20.0, guess=3.0)
    p.minimize_terminal(p.T)
    return p


def test_periodic_unbounded_heading_is_found_by_its_period():
    assert periodic_states(dubins()) == ["psi"]
    assert periodic_states(dubins(bounded=True)) == []  # bounded: nothing to chase
    assert periodic_states(rotation()) == []  # x, y enter polynomially


def test_periodic_heading_named_on_failure_and_when_refinement_stops():
    with pytest.raises(SolveError, match=r"state 'psi' enters only through 2\*pi-periodic "
                                         r"functions and is unbounded: bound it"):
        Collocation(dubins(), intervals=10).solve()
    # refinement stopped short (no rounds allowed): a warning names the heading...
    with pytest.warns(ConvergenceWarning, match="state 'psi' enters only through"):
        sol = Collocation(dubins(target=(2.0, 1.0)), intervals=10).refine(tol=1e-9,
                                                                          max_rounds=0)
    assert not sol.mesh_converged
    # ... and says nothing where the heading is bounded
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        sol = Collocation(dubins(True, (2.0, 1.0)), intervals=10).refine(tol=1e-9,
                                                                         max_rounds=0)
    assert not sol.mesh_converged


def test_condition_at_an_extremum_of_its_expression_is_named():
    with pytest.raises(SolveError, match=r"the gradient of terminal 'sin\(psi\(tf\)\) = -1' "
                                         r"vanishes at the last iterate"):
        Collocation(dubins(target=(0.5, 0.0), heading=True)).solve()
