"""ocp's own errors for misuse: None bounds mean unbounded; a start from another problem is a
GuessError naming the mismatch, not a CasADi shape error."""

import casadi as ca
import numpy as np
import pytest

import ocp
from ocp.definition.errors import GuessError


def _problem(two_states: bool) -> ocp.OptimalControlProblem:
    p = ocp.OptimalControlProblem()
    x = p.state("x", lower=None, upper=None)  # None: unbounded, like scipy's Bounds
    u = p.control("u", -1.0, None)
    if two_states:
        y = p.state("y")
        p.set_dynamics(ca.vertcat(y, u))
        p.initial_constraint(y, 0.0)
        p.terminal_constraint(y, 0.0)
    else:
        p.set_dynamics(u)
    p.initial_constraint(x, 1.0)
    p.terminal_constraint(x, 0.0)
    p.fixed_final_time(3.0)
    p.minimize_integral(u ** 2)
    return p


def test_none_bounds_are_unbounded():
    p = ocp.OptimalControlProblem()
    p.state("x", lower=None)
    p.variable("v", None, 2.0)
    lo, hi = (float(b) for b in p.state_bounds["x"])
    assert lo == -np.inf and hi == np.inf
    sol = ocp.MultipleShooting(_problem(False), 10).solve()
    assert sol.success and abs(sol.x[-1, 0]) < 1e-8


@pytest.mark.parametrize("how", ["guess", "warm_start"])
def test_start_from_another_problem_is_a_guess_error(how):
    other = ocp.MultipleShooting(_problem(True), 10).solve()
    with pytest.raises(GuessError, match="not this problem's"):
        ocp.MultipleShooting(_problem(False), 10).solve(**{how: other})


@pytest.mark.parametrize("bad", ["x", 3.0, {"w": [1.0]}])
def test_a_warm_start_that_is_not_a_solution_is_a_type_error_naming_it(bad):
    """Issue 47, defect 10: solve(warm_start='x') raised AttributeError from inside."""
    with pytest.raises(TypeError, match="warm_start must be an ocp.Solution"):
        ocp.MultipleShooting(_problem(False), 4).solve(warm_start=bad)
