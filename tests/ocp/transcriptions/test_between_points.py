"""'verified' that cannot miss a violation between the points (issue 45 item 1).

The check locates each constraint's maximum along the solution's own interpolant (the one
``sol.at`` returns), where a sampled check stepped over narrow peaks; ``inner_constraints``
imposes the constraints between the collocation points, at the state polynomials' control
points, so that the optimum does not land below the true one; a state bound converges in
mesh refinement as the same limit written as a path constraint does.

On the tree before (4695ed7): the speed limit's refined solution said ``verified`` with the
state 3.2e-5 above its limit at t = 2.4975; written as a state bound, refinement never
converged; the check's maxima fell short of the interpolant's; ``Collocation`` had no
``inner_constraints``; ``sol.at`` extrapolated the control where the check interpolated.
"""

import warnings

import numpy as np
import pytest

from ocp import Collocation, PathViolationWarning
from ocp.transcriptions.collocation import bernstein_points, radau_points
from ocp.transcriptions.discretization import lagrange_basis
from ocp.transcriptions.extrema import lobatto, series_max
from tests.oracles.accuracy_problems import (
    SPEED_EXACT,
    THIRD_ORDER_REFERENCE,
    speed_limit,
    third_order,
)


def dense_max(sol, row, per_interval=4000):
    """Brute force: the largest ``row(t, x, u)`` on ``per_interval`` samples per mesh
    interval of ``sol.at`` (a lower bound of the maximum along the interpolant)."""
    m = sol.mesh
    frac = np.linspace(0.0, 1.0, per_interval)
    t = (m[:-1, None] + np.diff(m)[:, None] * frac[None, :]).ravel()
    x, u = sol.at(t)
    vals = row(t, x, u)
    j = int(np.argmax(vals))
    return float(vals[j]), float(t[j])


@pytest.fixture(scope="module")
def refined_speed():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {form: Collocation(speed_limit(form), intervals=20).refine(tol=1e-6)
                for form in ("path", "bound")}


def test_refined_speed_limit_is_verified_only_where_it_holds(refined_speed):
    """Both forms: what ``verified`` says is what the interpolant does (on the tree
    before, the path form said verified with v 3.2e-5 above 0.8 near t = 2.4975)."""
    for sol in refined_speed.values():
        excess, t = dense_max(sol, lambda t, x, u: x[:, 1] - 0.8)
        assert sol.verified and excess <= sol.path_violation + 1e-12
        assert sol.path_violation <= 1e-6


def test_the_state_bound_converges_as_the_path_constraint_does(refined_speed):
    """Written as a state bound, the refinement converged on neither tree before (10 rounds,
    ``mesh_converged=False``); both forms now converge to the same optimum, within their
    error estimates of T = 3.3."""
    path, bound = refined_speed["path"], refined_speed["bound"]
    for sol in (path, bound):
        assert sol.mesh_converged and sol.convergence.startswith("converged (mesh")
        assert abs(sol.objective - SPEED_EXACT) <= sol.objective_error <= 1e-6 * SPEED_EXACT
    assert bound.objective == pytest.approx(path.objective, abs=1e-8)


@pytest.mark.parametrize("form", ["path", "bound"])
def test_the_check_finds_the_maximum_along_the_interpolant(form):
    """A coarse solve (the speed limit crossed inside intervals): the reported violation
    is the interpolant's maximum (to rounding), not a sample's (2.41e-3 against 2.51e-3
    on the tree before)."""
    with pytest.warns(PathViolationWarning):
        sol = Collocation(speed_limit(form), intervals=20).solve()
    excess, t = dense_max(sol, lambda t, x, u: x[:, 1] - 0.8)
    assert excess <= sol.path_violation <= excess + 1e-9
    name = next(iter(sol.violations))
    assert sol.violations[name][1] == pytest.approx(t, abs=1e-3)


def test_inner_constraints_keep_the_optimum_above_the_true_one():
    """Imposed at the collocation points only, the limit is crossed between them and the
    minimum time lands below 3.3 (on 40 intervals: 3.29988); imposed at the control
    points, it holds along the whole polynomial and T stays above 3.3."""
    with pytest.warns(PathViolationWarning):
        points = Collocation(speed_limit("bound"), intervals=40).solve()
    inner = Collocation(speed_limit("bound"), intervals=40, inner_constraints=True).solve()
    assert points.objective < SPEED_EXACT - 1e-5 and not points.verified
    assert inner.verified and inner.objective >= SPEED_EXACT - 1e-9
    excess, _ = dense_max(inner, lambda t, x, u: x[:, 1] - 0.8)
    assert excess <= 2e-8  # Ipopt's relaxation of the bound (1e-8)
    blocks = inner.multipliers["path_inner"]
    assert blocks.shape == (40 * bernstein_points(3)[0].size, 1)


def test_a_third_order_state_constraint_is_caught_and_imposed():
    """x''' = u, x <= 1/6: between its collocation points x rises above the bound (by
    4e-5 on 20 intervals); the check reports the maximum itself, and with the constraint
    imposed at the control points it holds everywhere and the optimum is not below the
    reference (258.578254), where the points-only optimum (258.4986) is."""
    ell = 1 / 6
    with pytest.warns(PathViolationWarning):
        sol = Collocation(third_order("bound"), intervals=20).solve()
    excess, _ = dense_max(sol, lambda t, x, u: x[:, 0] - ell)
    assert not sol.verified and excess <= sol.path_violation <= excess + 1e-9
    assert sol.objective < THIRD_ORDER_REFERENCE - 1e-2
    held = Collocation(third_order("path"), intervals=20, inner_constraints=True).solve()
    excess, _ = dense_max(held, lambda t, x, u: x[:, 0] - ell)
    assert held.verified and excess <= 2e-8
    assert held.objective >= THIRD_ORDER_REFERENCE - 3e-6


def test_sample_and_check_read_one_control_interpolant():
    """Before its first collocation point an interval's control is the straight line from
    the previous interval's last point (the check's), which ``sol.at`` now returns too
    (it extrapolated the polynomial there)."""
    with pytest.warns(PathViolationWarning):
        sol = Collocation(speed_limit("path"), intervals=10).solve()
    tr = sol.transcription.phases[0]
    k, c1 = 4, tr.c[0]
    t0, h = sol.mesh[k], sol.mesh[k + 1] - sol.mesh[k]
    U = sol.data.raw["U"].reshape(10, 3)
    theta = np.array([0.0, 0.3, 0.7, 1.0]) * c1
    _, u = sol.at(t0 + theta * h)
    line = U[k - 1, 2] + theta / c1 * (U[k, 0] - U[k - 1, 2])
    assert np.allclose(u[:, 0], np.clip(line, -1.0, 1.0), atol=1e-12)


def test_chebyshev_maximum_is_exact_for_a_polynomial():
    """The search's building block: a degree-5 polynomial's maximum on [-1, 1] from its
    values at 10 Lobatto points, against the roots of its derivative."""
    rng = np.random.default_rng(3)
    z, to_coef = lobatto(10)
    for _ in range(20):
        p = np.polynomial.Polynomial(rng.normal(size=6))
        crit = [r.real for r in p.deriv().roots() if abs(r.imag) < 1e-12 and abs(r.real) <= 1]
        exact = max(p(np.array([-1.0, 1.0, *crit])))
        value, at = series_max((to_coef @ p(z))[None, :])
        assert value[0] == pytest.approx(exact, abs=1e-12) and p(at[0]) == pytest.approx(
            exact, abs=1e-12)


def test_control_points_bound_the_polynomial():
    """The convex-hull property the option relies on: on two pieces, the control points'
    maximum bounds the cubic's."""
    _, W = bernstein_points(3)
    nodes = np.r_[0.0, radau_points(3)]
    grid = np.linspace(0, 1, 2001)
    rng = np.random.default_rng(5)
    for _ in range(20):
        vals = rng.normal(size=4)
        curve = lagrange_basis(nodes, grid) @ vals
        assert curve.max() <= max(vals[0], vals[-1], *(W @ vals)) + 1e-12
    assert np.allclose(W @ np.ones(4), 1.0)
