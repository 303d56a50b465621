"""The generic ocp layer on problems with known answers."""

import math

import numpy as np
import pytest

from ocp import (
    InfeasibleError,
    MultipleShooting,
    OptimalControlProblem,
    ProblemDefinitionError,
    SolveError,
    continuation,
)
from ocp.structure.switching import detect_arcs, refine_switching
from tests.oracles.problems import min_time_double_integrator


@pytest.fixture(scope="module")
def di():
    return MultipleShooting(min_time_double_integrator(), nodes=41)


@pytest.mark.parametrize("d", [0.5, 1.0, 3.0, 7.0])
def test_min_time_double_integrator_refined_to_machine_precision(di, d):
    sol = di.solve({"d": d})
    assert sol.success and abs(sol.T - 2 * math.sqrt(d)) < 1e-2 * math.sqrt(d)
    st = detect_arcs(sol)
    assert st.kinds == ["max", "min"] and st.bang_bang
    r = refine_switching(sol, st)
    assert r.exact  # affine dynamics: arcs by the matrix exponential
    assert abs(r.T - 2 * math.sqrt(d)) <= 1e-9
    assert abs(r.switch_times[0] - math.sqrt(d)) <= 1e-9
    assert abs(r.objective - 2 * math.sqrt(d)) <= 1e-9


def test_resolving_with_new_parameters_does_not_rebuild(di):
    builds = di.n_builds
    solver_ids = None
    di.solve({"d": 0.5})  # with expand="auto" the second solve builds the expanded solver
    di.solve({"d": 0.7})
    for d in (1.0, 2.0, 4.0):
        di.solve({"d": d})
        ids = {k: id(v) for k, v in di._solvers.items()}
        solver_ids = solver_ids or ids
        assert ids == solver_ids
    assert di.n_builds == builds == 1


def test_warm_start_and_continuation(di):
    cold = di.solve({"d": 4.0})
    warm = di.solve({"d": 4.2}, warm_start=cold)
    assert warm.success
    assert warm.T == pytest.approx(2 * math.sqrt(4.2), rel=1e-3)
    assert warm.iterations < cold.iterations
    sols = continuation(di, {"d": 1.0}, "d", np.linspace(1.0, 3.0, 5))
    np.testing.assert_allclose([s.T for s in sols], 2 * np.sqrt(np.linspace(1, 3, 5)),
                               rtol=1e-3)


def test_extra_arcs_do_not_improve_min_time(di):
    sol = di.solve({"d": 2.0})
    r = refine_switching(sol, extra_arcs=2)
    assert len(r.kinds) == 4
    assert r.objective == pytest.approx(2 * math.sqrt(2.0), abs=1e-9)


def test_infeasible_problem_raises_with_status():
    p = min_time_double_integrator()
    p.terminal_constraint(p.x[0], -1.0)  # x(T) = d and x(T) = -1: contradictory
    ms = MultipleShooting(p, nodes=10)
    with pytest.raises(InfeasibleError) as e:
        ms.solve({"d": 1.0})
    assert e.value.status in ("Infeasible_Problem_Detected", "Restoration_Failed")
    assert e.value.iterate is not None and e.value.iterate.w.shape == (ms.n_w,)


def test_iteration_limit_raises_solve_error():
    ms = MultipleShooting(min_time_double_integrator(), nodes=20,
                          ipopt_options={"max_iter": 2})
    with pytest.raises(SolveError) as e:
        ms.solve({"d": 1.0})
    assert e.value.status == "Maximum_Iterations_Exceeded"


def test_lagrange_cost_and_fixed_time():
    # min int u^2 dt, x' = u, x(0) = 0, x(1) = 1  ->  u = 1, cost 1
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics([u])
    p.initial_constraint(x, 0.0)
    p.terminal_constraint(x, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    sol = MultipleShooting(p, nodes=10).solve({})
    assert sol.objective == pytest.approx(1.0, abs=1e-8)
    np.testing.assert_allclose(sol.u.ravel(), 1.0, atol=1e-8)
    d = sol.to_dict()
    assert d["status"] == "Solve_Succeeded" and len(d["controls"]["u"]) == 10


@pytest.mark.slow  # 3.2 s CPU
def test_cvodes_integrator_agrees_with_rk4():
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u", lower=-2, upper=2)
    p.set_dynamics([-x**3 + u])  # nonlinear
    p.initial_constraint(x, 1.0)
    p.terminal_constraint(x, 0.0)
    p.free_final_time(0.01, 20, 1.0)
    p.minimize_terminal(p.T)
    a = MultipleShooting(p, nodes=30, substeps=8).solve({})
    b = MultipleShooting(p, nodes=30, integrator="cvodes").solve({})
    assert a.T == pytest.approx(b.T, rel=1e-5)
    assert not p.is_affine_in_state()
    r = refine_switching(b)
    assert not r.exact and r.kinds == ["min"]
    # x' = -x^3 - 2 from 1 to 0: T = int_0^1 dx / (x^3 + 2)
    from scipy.integrate import quad

    assert r.T == pytest.approx(quad(lambda s: 1 / (s**3 + 2), 0, 1)[0], abs=1e-9)


def test_sampling_matches_nodes(di):
    sol = di.solve({"d": 1.0})
    t, x, u = sol.sample(401)
    assert t[-1] == pytest.approx(sol.T)
    np.testing.assert_allclose(x[-1], sol.x[-1], atol=1e-9)


def test_definition_errors():
    p = OptimalControlProblem()
    p.state("x")
    with pytest.raises(ProblemDefinitionError):
        p.state("x")
    with pytest.raises(ProblemDefinitionError):
        p.validate()
    u = p.control("u")
    with pytest.raises(ProblemDefinitionError):
        p.path_constraint(u, lower=p.x[0])  # bounds must not depend on x
    with pytest.raises(ValueError):
        p.set_dynamics([u])
        MultipleShooting(p, nodes=5).solve({"nope": 1.0})
