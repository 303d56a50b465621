"""ocp features beyond single-phase autonomous problems, each on a problem with a known answer.

Time symbol, free and non-zero initial time, decision variables, state bounds,
controls in terminal constraints, integral constraints, initial-state costs,
multiple phases with linkage constraints, and the build-once property for all
of them; each for multiple shooting and collocation where both apply.
"""

import math

import numpy as np
import pytest

from ocp import (
    Collocation,
    MultiPhaseProblem,
    MultipleShooting,
    OptimalControlProblem,
    transcribe,
)

METHODS = [("multiple_shooting", {"nodes": 20}), ("collocation", {"intervals": 8})]


def solve(problem, method, params=None, **extra):
    name, opts = method
    return transcribe(problem, name, **{**opts, **extra}).solve(params or {})


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_time_symbol_in_dynamics_with_a_nonzero_initial_time(method):
    # x' = t on [1, 3], x(1) = 0  ->  x(3) = (9 - 1) / 2 = 4; u only to have a control
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics({"x": p.t + 0 * u})
    p.initial_constraint(x, 0.0)
    p.fixed_initial_time(1.0)
    p.fixed_final_time(3.0)
    p.minimize_integral(u**2)
    sol = solve(p, method)
    assert sol.t0 == 1.0 and sol.T == 3.0 and sol.t[0] == 1.0
    assert sol.x[-1, 0] == pytest.approx(4.0, abs=1e-9)
    t, xs, _ = sol.sample(7)
    np.testing.assert_allclose(xs[:, 0], (t**2 - 1) / 2, atol=1e-9)


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_time_varying_path_constraint_and_final_time_in_dynamics(method):
    # min int u^2, x' = u, x(0) = 0, x(T) = 1, T = 2, x <= t/2 (active all along):
    # x = t/2, u = 1/2, cost 1/2. The dynamics scale with T - t0 through p.T.
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics({"x": u * (p.T - p.t0) / 2})
    p.initial_constraint(x, 0.0)
    p.terminal_constraint(x, 1.0)
    p.path_constraint(x - p.t / 2, upper=0.0)
    p.fixed_final_time(2.0)
    p.minimize_integral(u**2)
    sol = solve(p, method)
    assert sol.objective == pytest.approx(0.5, abs=1e-7)
    np.testing.assert_allclose(sol.u, 0.5, atol=1e-4)  # degenerate: active all along


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_free_initial_time(method):
    # the latest start from x = 0 that still reaches x = 1 at T = 2 with |u| <= 1: t0 = 1
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.terminal_constraint(x, 1.0)
    p.free_initial_time(0.0, 1.9, guess=0.5)
    p.fixed_final_time(2.0)
    p.minimize(-p.t0)
    sol = solve(p, method)
    assert sol.t0 == pytest.approx(1.0, abs=1e-7)
    assert sol.t[0] == sol.t0 and sol.T == 2.0


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_decision_variable_is_estimated(method):
    # x' = -k x, x(0) = 1, x(1) = exp(-2)  ->  k = 2 (a decision parameter, not set at solve)
    p = OptimalControlProblem()
    x = p.state("x")
    k = p.variable("k", lower=0.0, upper=10.0, guess=1.0)
    p.set_dynamics({"x": -k * x})
    p.initial_constraint(x, 1.0)
    p.boundary_constraint(p.at_tf(x), math.exp(-2.0))
    p.fixed_final_time(1.0)
    p.minimize((k - 3.0) ** 2 * 0)  # nothing to minimise but feasibility
    name, opts = method
    tr = transcribe(p, name, **opts, substeps=8) if name == "multiple_shooting" \
        else transcribe(p, name, **opts)
    sol = tr.solve({})
    assert sol.variables["k"] == pytest.approx(2.0, rel=1e-6)
    with pytest.raises(ValueError, match="decision variable"):
        tr.solve({"k": 2.0})


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_state_bounds_and_initial_state_cost(method):
    # x' = u, |u| <= 1, x(1) = 2, x(0) free with x >= 0.5: min x(0)^2 -> x(0) = 1
    # (and with x(1) = 1.2 the bound x >= 0.5 binds: x(0) = 0.5)
    for target, x0 in ((2.0, 1.0), (1.2, 0.5)):
        p = OptimalControlProblem()
        x = p.state("x", lower=0.5, upper=5.0)
        u = p.control("u", -1, 1)
        p.set_dynamics({"x": u})
        p.terminal_constraint(x, target)
        p.fixed_final_time(1.0)
        p.minimize(p.at_t0(x) ** 2)
        sol = solve(p, method)
        assert sol.x[0, 0] == pytest.approx(x0, abs=1e-7)
        assert sol.objective == pytest.approx(x0**2, abs=1e-7)
        assert np.all(sol.x[:, 0] >= 0.5 - 1e-7)  # Ipopt relaxes bounds by 1e-8


def test_control_in_a_terminal_constraint():
    # x' = u, x(0) = 0, x(1) = 1, u(T) = 1.5 on the last interval; min int u^2
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.terminal_constraint(x, 1.0)
    p.terminal_constraint(u, 1.5)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    sol = MultipleShooting(p, nodes=10).solve({})
    assert sol.u[-1, 0] == pytest.approx(1.5, abs=1e-9)
    # the other nine intervals share the rest equally: 9 h u + 1.5 h = 1
    np.testing.assert_allclose(sol.u[:-1, 0], (1 - 0.15) / 0.9, atol=1e-8)
    assert sol.multipliers["terminal"].shape == (2,)


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_integral_constraint(method):
    # min int u^2, x' = u, x(0) = 0, x(1) free, int_0^1 x dt = c  ->  J = 3 c^2
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u")
    c = p.parameter("c")
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.integral_constraint(x, c)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    name, opts = method
    tr = transcribe(p, name, **({"nodes": 200} if name == "multiple_shooting" else opts))
    for cv in (1 / 3, 0.5):
        sol = tr.solve({"c": cv})
        tol = 1e-3 if name == "multiple_shooting" else 1e-9  # MS: first order in h
        assert sol.objective == pytest.approx(3 * cv**2, rel=tol)
    assert tr.n_builds == 1


def _hop(method, **opts):
    """Accelerate with 0 <= u <= 1 (phase 1), then brake at a fixed -1 with no control
    (phase 2), from rest to rest over d in minimum total time: T = 2 sqrt(d)."""
    mp = MultiPhaseProblem("hop")
    d = mp.parameter("d")
    push, brake = mp.phase("push"), mp.phase("brake")
    x, v = push.state("x"), push.state("v")
    u = push.control("u", 0, 1)
    push.set_dynamics({"x": v, "v": u})
    push.initial_constraint(x, 0.0)
    push.initial_constraint(v, 0.0)
    push.free_final_time(0.01, 10, guess=1.0)
    xb, vb = brake.state("x"), brake.state("v")
    brake.set_dynamics({"x": vb, "v": -1.0})
    brake.terminal_constraint(xb - d, 0.0)
    brake.terminal_constraint(vb, 0.0)
    brake.free_duration(0.01, 10, guess=1.0)
    mp.link(push, brake)
    mp.minimize(brake.T)
    return transcribe(mp, method, **opts)


@pytest.mark.parametrize("method", METHODS, ids=[m for m, _ in METHODS])
def test_two_phases_with_different_dynamics_and_free_switch_time(method):
    tr = _hop(method[0], **method[1])
    # multiple shooting is exact here (u = 1 is piecewise constant); Radau collocation
    # exploits its last collocation point on a bang arc by 5e-5 on 8 intervals
    tol = 1e-6 if method[0] == "multiple_shooting" else 1e-4
    for d in (1.0, 2.0):
        sol = tr.solve({"d": d})
        a, b = sol.phases
        assert b.T == pytest.approx(2 * math.sqrt(d), abs=tol)
        assert a.T == pytest.approx(math.sqrt(d), abs=100 * tol) and b.t0 == pytest.approx(a.T)
        np.testing.assert_allclose(b.x[0], a.x[-1], atol=1e-9)
        assert sol.link_multipliers["link"].shape == (3,)  # x, v, time
    assert tr.n_builds == 1
    traj = sol.trajectory(50)
    assert set(np.unique(traj.phase)) == {0, 1}
    assert traj.state_names == ("x", "v") and traj.control_names == ("u",)
    assert np.all(np.isnan(traj.u[traj.phase == 1]))
    assert "phase" in traj.to_xarray()
    with pytest.raises(AttributeError, match="multi-phase"):
        _ = sol.x


def test_linkage_with_a_jump_bouncing_ball():
    # drop from 1 (g = 1): hits at sqrt(2) with speed sqrt(2); restitution e: the second
    # phase climbs for e sqrt(2) to height e^2
    e = 0.6
    mp = MultiPhaseProblem("ball")
    fall, rise = mp.phase("fall"), mp.phase("rise")
    for ph in (fall, rise):
        ph.state("y")
        ph.state("v")
        ph.set_dynamics({"y": ph.x[1], "v": -1.0})
    fall.initial_constraint(fall.x[0], 1.0)
    fall.initial_constraint(fall.x[1], 0.0)
    fall.terminal_constraint(fall.x[0], 0.0)
    fall.free_final_time(0.1, 5)
    rise.terminal_constraint(rise.x[1], 0.0)
    rise.free_duration(0.1, 5)
    mp.link(fall, rise, states=["y"])
    mp.link_constraint(rise.at_t0(rise.x[1]) + e * fall.at_tf(fall.x[1]), 0.0, name="bounce")
    sol = Collocation(mp, intervals=4).solve()
    assert sol.phases[0].T == pytest.approx(math.sqrt(2), abs=1e-9)
    assert sol.phases[1].T - sol.phases[1].t0 == pytest.approx(e * math.sqrt(2), abs=1e-9)
    assert sol.phases[1].x[-1, 0] == pytest.approx(e**2, abs=1e-9)


def test_shared_decision_variable_across_phases():
    # two phases x' = a (a shared decision variable), lengths 1 and 2, x: 0 -> 6: a = 2
    mp = MultiPhaseProblem()
    a = mp.variable("a", -10, 10)
    phases = [mp.phase(), mp.phase()]
    for ph in phases:
        ph.state("x")
        ph.set_dynamics({"x": a})
    phases[0].initial_constraint(phases[0].x[0], 0.0)
    phases[0].fixed_final_time(1.0)
    phases[1].fixed_final_time(3.0)
    phases[1].terminal_constraint(phases[1].x[0], 6.0)
    mp.link(*phases)
    sol = MultipleShooting(mp, nodes=[3, 5]).solve()
    assert sol.variables["a"] == pytest.approx(2.0, abs=1e-10)
    assert sol.phases[1].t0 == pytest.approx(1.0)


def test_rebuild_free_resolves_with_new_features():
    tr = _hop("collocation", intervals=6)
    ids = None
    for d in (1.0, 1.5, 3.0):
        tr.solve({"d": d})
        now = {k: id(v) for k, v in tr._solvers.items()}
        ids = ids or now
        assert now == ids
    assert tr.n_builds == 1


def test_default_guess_interpolates_fixed_ends_and_uses_bound_midpoints():
    p = OptimalControlProblem()
    x = p.state("x")
    m = p.state("m", lower=0.2, upper=1.0)
    p.state("y", lower=2.0, upper=4.0)
    u = p.control("u", 0.0, 2.0)
    d = p.parameter("d")
    p.set_dynamics({"x": u / m, "m": -u, "y": 0 * u})
    p.initial_constraint(x, 1.0)
    p.terminal_constraint(2 * x - d, 0.0)  # x(T) = d / 2, affine in x alone
    p.fixed_final_time(1.0)
    ms = MultipleShooting(p, nodes=4)
    X = ms.default_guess({"d": 6.0})[ms.layout.iX].reshape(5, 3)
    np.testing.assert_allclose(X[:, 0], np.linspace(1.0, 3.0, 5))
    np.testing.assert_allclose(X[:, 1], 0.6)  # midpoint of [0.2, 1]
    np.testing.assert_allclose(X[:, 2], 3.0)
    U = ms.default_guess({"d": 6.0})[ms.layout.iU]
    np.testing.assert_allclose(U, 1.0)


def test_collocation_error_falls_with_the_degree():
    # brachistochrone on 20 intervals against the cycloid: Radau collocation of degree d
    # is of order 2d - 1 at the mesh points
    from tests.oracles.ocp_suite.problems import brachistochrone, brachistochrone_exact

    exact = brachistochrone_exact()
    sols = [Collocation(brachistochrone(), intervals=20, degree=d).solve() for d in (1, 2, 3)]
    errs = [abs(s.objective - exact) for s in sols]
    assert errs[0] > 1e-3 > errs[1] > 1e-7 > errs[2]
    # every collocation solution carries its error estimate, falling likewise
    est = [s.mesh_error for s in sols]
    assert est[0] > est[1] > est[2]
