r"""Scenario problems (``ocp.scenarios.scenario``) against closed-form robust optima.

The problem: a double integrator with an uncertain gain ``b``,

    x' = v,  v' = b u,  x(0) = v(0) = 0,  T = 1,
    J_b = (x(1) - 1)^2 + rho int_0^1 u^2 dt,   rho = 0.01,  |u| <= 5 (never active).

**Reduction to one number.** ``x(1) = b c`` with ``c = int_0^1 (1 - t) u dt``, the same
``c`` for every scenario when the control is shared. For a given ``c`` the least
energy is ``int u^2 = c^2 / A`` with ``A = int_0^1 (1 - t)^2 dt = 1/3``, reached by
``u = c (1 - t) / A`` (Cauchy-Schwarz); every ``J_b`` grows with the energy at fixed
``c``, so every optimum below uses that profile and
``J_b(c) = (b c - 1)^2 + k c^2`` with ``k = rho / A``.

**Robust open loop (worst case), b in {b1, b2}, b1 < b2.** The parabolas ``J_b1`` and
``J_b2`` cross at ``c = 0`` and ``c_x = 2 / (b1 + b2)``; on ``(0, c_x)`` ``J_b1`` is the
larger and it still decreases at ``c_x`` when its own minimiser
``b1 / (b1^2 + k)`` exceeds ``c_x``; beyond ``c_x`` ``J_b2`` is the larger and it
increases when ``b2 / (b2^2 + k) < c_x``. Both hold for ``b = (1, 2)``, ``rho = 0.01``
(0.97 > 2/3 > 0.496), so the min-max sits on the crossing:

    c* = 2 / (b1 + b2) = 2/3,   worst = ((b2 - b1) / (b1 + b2))^2 + k c*^2
       = 1/9 + 0.04/3 = 0.124444...,   u*(t) = c* (1 - t) / A = 2 (1 - t),

with both scenarios active (equal costs). **Expected value** with weights ``w``:
``min_c sum w_b (b c - 1)^2 + k c^2`` gives ``c = sum w b / (sum w b^2 + k)``.
**Per-scenario optimum** (a tree branching at ``t = 0``): ``min_c (b c - 1)^2 + k c^2
= k / (b^2 + k)``, worst for the smaller gain. **Two-stage tree** branching at ``f``:
with ``c_s`` from the shared part and ``c_i`` from scenario i's own part,
``x_i(1) = b_i (c_s + c_i)``, energies ``c_s^2 / A_s + c_i^2 / A_2`` (``A_s = int_0^f``,
``A_2 = int_f^1`` of ``(1 - t)^2``). Each ``c_i`` minimises its own cost, leaving
``V_i(c_s) = (b_i c_s - 1)^2 r / (b_i^2 + r) + rho c_s^2 / A_s`` with ``r = rho / A_2``;
the tree's worst case is ``min_{c_s} max_i V_i(c_s)``, a one-dimensional convex
problem computed here by scipy (an independent computation).

**Discretisations.** Multiple shooting holds ``u`` constant on each interval; RK4 is
exact for these polynomial dynamics and the cost integral is exact, so the same
argument holds with the midpoint sums ``A_N = h sum (1 - t_{k+1/2})^2 = 1/3 - h^2/12``
(and likewise ``A_s``, ``A_2``): the discrete optimum is known in closed form and
checked to 1e-9 (measured: 1e-11). Radau collocation of
degree 3 represents the continuous optimum exactly (``x`` cubic, ``u`` linear,
``u^2`` integrated exactly), so it is checked against the continuous values.

**Free final time** (each scenario ends when its body is at rest): rest to rest over
``d`` with ``|u| <= 1``, ``min T``. In normalised time ``tau = t / T_i`` scenario ``i``
obeys ``x_i'' = T_i^2 b_i u(tau)``; ``v_i(1) = 0`` needs ``int u = 0`` and ``x_i(1) = d``
needs ``T_i^2 b_i X = d``, ``X = int_0^1 (1 - tau) u dtau <= 1/4`` (bang-bang, switch at
``tau = 1/2``). So the shared normalised schedule is every scenario's own minimum-time
one: ``T_i = 2 sqrt(d / b_i)``, worst ``2 sqrt(d / b_min)``.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from ocp import (
    MultiPhaseProblem,
    MultipleShooting,
    OptimalControlProblem,
    PathViolationWarning,
    ProblemDefinitionError,
    ScenarioProblem,
    ScenarioResult,
    transcribe,
)

RHO = 0.01
B = (1.0, 2.0)
SCEN = [{"b": B[0]}, {"b": B[1]}]
N = 20
METHODS = ("multiple_shooting", "collocation")


def gain_problem() -> OptimalControlProblem:
    p = OptimalControlProblem("gain")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -5, 5)
    b = p.parameter("b")
    p.set_dynamics({"x": v, "v": b * u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_terminal((x - 1) ** 2)
    p.minimize_integral(RHO * u**2)
    return p


def midpoint_A(lo: float, hi: float, n: int) -> float:
    """``int_lo^hi (1 - t)^2 dt`` by the midpoint rule on ``n`` intervals."""
    h = (hi - lo) / n
    tm = lo + (np.arange(n) + 0.5) * h
    return float(h * np.sum((1 - tm) ** 2))


def exact_A(lo: float, hi: float) -> float:
    return ((1 - lo) ** 3 - (1 - hi) ** 3) / 3


def A_for(method: str, lo: float = 0.0, hi: float = 1.0, n: int = N) -> float:
    return midpoint_A(lo, hi, n) if method == "multiple_shooting" else exact_A(lo, hi)


def robust_value(b: tuple[float, float], A: float) -> tuple[float, float]:
    c = 2 / (b[0] + b[1])
    return ((b[1] - b[0]) / (b[0] + b[1])) ** 2 + RHO * c**2 / A, c


def tree_value(f: float, A_s: float, A_2: float) -> float:
    r = RHO / A_2
    b = np.array(B)

    def worst(c: float) -> float:
        return float(np.max((b * c - 1) ** 2 * r / (b**2 + r) + RHO * c**2 / A_s))

    res = minimize_scalar(worst, bounds=(0.0, 2.0), method="bounded",
                          options={"xatol": 1e-12})
    return float(res.fun)


@pytest.fixture(scope="module")
def robust() -> dict[str, object]:
    sp = ScenarioProblem(gain_problem(), SCEN)
    return {m: sp.transcribe(m, nodes=N) for m in METHODS}


# ----------------------------------------------------------------- optima
@pytest.mark.parametrize("method", METHODS)
def test_robust_open_loop_is_the_closed_form_min_max(robust, method):
    res = robust[method].solve()
    A = A_for(method)
    worst, c = robust_value(B, A)
    assert isinstance(res, ScenarioResult) and res.success, res.message
    assert res.status == "Solve_Succeeded"
    assert res.worst == pytest.approx(worst, abs=1e-9)  # measured: 1e-11
    # the epigraph variable sits within Ipopt's bound relaxation (1e-8) of it
    assert res.fun == pytest.approx(worst, abs=3e-8)
    assert res.costs == pytest.approx([worst, worst], abs=1e-9)  # both active
    assert res.active == [0, 1]
    # the shared control: u = c (1 - t) / A (at the interval midpoints for shooting)
    t, _, u = res.nodes(0)
    if method == "multiple_shooting":
        tm = (t[:-1] + t[1:]) / 2
    else:
        tm = t[1:]  # the control at the collocation point t_{k+1}
    assert u[:, 0] == pytest.approx(c * (1 - tm) / A, abs=1e-6)
    assert np.array_equal(res.control("u", 0), res.control("u", 1))  # shared
    assert np.all(res.constraint_violation <= 1e-9)
    # each scenario's own state: x_i(1) = b_i c
    assert [res.state("x", i)[-1] for i in range(2)] == pytest.approx([c, 2 * c], abs=1e-7)


@pytest.mark.parametrize("method", METHODS)
def test_expected_value_is_the_closed_form(method):
    w = np.array([0.3, 0.7])
    b = np.array(B)
    sp = ScenarioProblem(gain_problem(), SCEN, objective="expected", weights=w)
    res = sp.transcribe(method, nodes=N).solve()
    k = RHO / A_for(method)
    c = (w @ b) / (w @ b**2 + k)
    costs = (b * c - 1) ** 2 + k * c**2
    assert res.success
    assert res.costs == pytest.approx(costs, abs=1e-8)
    assert res.fun == pytest.approx(w @ costs, abs=1e-8)
    assert res.expected == pytest.approx(res.fun, abs=1e-12)
    assert res.weights == pytest.approx(w)


@pytest.mark.parametrize("method", METHODS)
def test_tree_branching_at_zero_is_the_per_scenario_optimum(method):
    res = ScenarioProblem(gain_problem(), SCEN, branching=0.0).transcribe(
        method, nodes=N).solve()
    k = RHO / A_for(method)
    own = [k / (b**2 + k) for b in B]
    assert res.success
    assert res.worst == pytest.approx(max(own), abs=1e-7)
    assert res.active == [0]  # the smaller gain is the worse case
    # the inactive scenario's cost is anything below (min-max leaves it free); the
    # expected objective separates, so there every scenario reaches its own optimum
    sep = ScenarioProblem(gain_problem(), SCEN, objective="expected", branching=0.0)
    assert sep.transcribe(method, nodes=N).solve().costs == pytest.approx(own, abs=1e-8)


@pytest.mark.parametrize("method", METHODS)
def test_two_stage_tree_beats_open_loop_and_matches_the_dense_computation(robust, method):
    f = 0.5
    res = ScenarioProblem(gain_problem(), SCEN, branching=f).transcribe(
        method, nodes=N).solve()
    expected = tree_value(f, A_for(method, 0, f, N // 2), A_for(method, f, 1, N // 2))
    assert res.success
    assert res.worst == pytest.approx(expected, abs=1e-8)  # measured: 4e-10
    assert res.active == [0, 1]
    open_loop = robust[method].solve().worst
    assert res.worst < open_loop
    t, _, u0 = res.nodes(0)
    _, _, u1 = res.nodes(1)
    shared = t[:-1] < f * (1 - 1e-12)  # intervals before the branching
    assert np.array_equal(u0[shared], u1[shared])
    assert np.max(np.abs(u0[~shared] - u1[~shared])) > 0.1  # then each its own


def test_resolve_with_new_values_equals_a_fresh_build(robust):
    tr = robust["multiple_shooting"]
    new = [{"b": 1.5}, {"b": 3.0}]
    res = tr.solve(scenarios=new)
    fresh = ScenarioProblem(gain_problem(), new).transcribe(
        "multiple_shooting", nodes=N).solve()
    assert tr.n_builds == 1
    assert res.costs == pytest.approx(fresh.costs, abs=1e-9)
    assert res.scenarios == new
    assert res.worst == pytest.approx(robust_value((1.5, 3.0), A_for("multiple_shooting"))[0],
                                      abs=1e-7)
    again = tr.solve(warm_start=res)  # back to the defaults, warm-started
    assert again.worst == pytest.approx(robust_value(B, A_for("multiple_shooting"))[0],
                                        abs=1e-7)
    assert tr.n_builds == 1


def test_transcriptions_agree(robust):
    ms, col = (robust[m].solve() for m in METHODS)
    assert ms.worst == pytest.approx(col.worst, abs=5e-5)
    tm = np.linspace(0, 1, 41)
    ums = np.interp(tm, *_steps(ms))
    ucol = np.interp(tm, *_steps(col))
    assert np.max(np.abs(ums - ucol)) < 0.06  # piecewise constant against linear, h = 0.05


def _steps(res: ScenarioResult) -> tuple[np.ndarray, np.ndarray]:
    tr = res.trajectory(0, 400)
    return tr.t, tr["u"]


@pytest.mark.parametrize("method", METHODS)
def test_free_final_time_each_scenario_rests_at_its_own_time(method):
    d = 1.0
    p = OptimalControlProblem("rest_to_rest")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -1, 1)
    b = p.parameter("b")
    dd = p.parameter("d")
    p.set_dynamics({"x": v, "v": b * u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - dd, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.1, 10)
    p.minimize_terminal(p.T)
    res = ScenarioProblem(p, SCEN).transcribe(method, nodes=N).solve(params={"d": d})
    T = 2 * np.sqrt(d / np.array(B))
    assert res.success
    assert res.final_times == pytest.approx(T, abs=1e-6)
    assert res.costs == pytest.approx(T, abs=1e-6)
    assert res.worst == pytest.approx(T[0], abs=1e-6)
    assert res.active == [0]
    for i in range(2):
        tr = res.trajectory(i, 100)
        assert tr.t[-1] == pytest.approx(T[i], abs=1e-6)
        assert tr["x"][-1] == pytest.approx(d, abs=1e-6)
        assert tr["v"][-1] == pytest.approx(0.0, abs=1e-6)


# ------------------------------------------------------- checks and results
def up_and_down() -> OptimalControlProblem:
    """A state bound that the coarse grid only imposes at its nodes."""
    p = OptimalControlProblem("up_down")
    x, v = p.state("x", upper=0.2), p.state("v")
    u = p.control("u")
    b = p.parameter("b")
    p.set_dynamics({"x": v, "v": b * u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_terminal(10 * x**2)
    p.minimize_integral(u**2)
    return p


@pytest.mark.parametrize("verify", ["warn", "off"])
def test_success_never_hides_a_violated_constraint(verify):
    tr = ScenarioProblem(up_and_down(), SCEN).transcribe("multiple_shooting", nodes=3,
                                                          verify=verify)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PathViolationWarning)
        res = tr.solve()
    assert res.status == "Solve_Succeeded"
    assert not res.success
    assert list(res.verified) == [False, True]  # only scenario 0 climbs above 0.2
    name, (amount, t) = max(res.violations[0].items(), key=lambda kv: kv[1][0])
    assert name == "bounds of state 'x[0]'" and amount > 1e-3 and 0 < t < 1
    assert "scenario 0" in res.message
    fine = ScenarioProblem(up_and_down(), SCEN).transcribe("collocation", nodes=10).refine(
        tol=1e-7)  # refined where the bound is active: nothing violated
    assert fine.success and np.all(fine.constraint_violation <= 1e-6)
    assert max(fine.trajectory(0, 400)["x"]) == pytest.approx(0.2, abs=1e-6)


def test_result_reads_like_the_other_results(robust):
    res = robust["collocation"].solve()
    d = res.to_dict()
    json.dumps(d)
    assert d["active"] == [0, 1] and d["objective_kind"] == "worst"
    assert res.iterations > 0 and res.solve_time > 0
    assert res.active_scenario in (0, 1) and res.n_scenarios == 2
    tr = res.trajectory(1, 50)
    assert tr.state_names == ("x", "v") and tr.control_names == ("u",)
    assert tr.t[0] == 0.0 and tr.t[-1] == pytest.approx(1.0)
    assert "ScenarioResult" in repr(res) and "ScenarioTranscription" in repr(robust["collocation"])
    with pytest.raises(IndexError):
        res.nodes(2)


def rich() -> OptimalControlProblem:
    """Every kind of term: a common parameter in a state bound, a decision variable,
    path constraints on the control only and on the state, an initial time of 1, a free
    duration, a boundary constraint over both ends, an integral constraint and a cost
    integral on the same integrand."""
    p = OptimalControlProblem("rich")
    vmax, m = p.parameter("vmax"), p.parameter("m")
    x, v = p.state("x"), p.state("v", upper=vmax)
    u = p.control("u", -1, 1)
    k = p.variable("k", 0, 2)
    p.set_dynamics({"x": v, "v": u / m - 0.1 * k * v})
    p.path_constraint(u, upper=0.9, name="u_cap")
    p.path_constraint(x + v, upper=3.0, name="xv")
    p.fixed_initial_time(1.0)
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(v, 0.0)
    p.boundary_constraint(p.at_tf(x) - p.at_t0(x), 1.0, name="dist")
    p.integral_constraint(u**2, -math.inf, 2.0, name="energy")
    p.free_duration(0.5, 10, guess=3)
    p.minimize(p.T - p.t0 + (k - 1) ** 2 + 0.1 * p.integral(u**2))
    return p


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("branching", [None, 0.5])
def test_one_scenario_reproduces_the_problem_itself(method, branching):
    """The stacking (normalised time, integrals carried by states, phases at the
    branching) changes nothing but the bookkeeping: one scenario is the problem."""
    par = {"vmax": 0.8, "m": 1.2}
    with warnings.catch_warnings():  # collocation leaves v above vmax between its points
        warnings.simplefilter("ignore", PathViolationWarning)
        ref = transcribe(rich(), method, **{"intervals" if method == "collocation"
                                            else "nodes": N}).solve(par)
        res = ScenarioProblem(rich(), [{"m": 1.2}], branching=branching).transcribe(
            method, nodes=N).solve(params={"vmax": 0.8})
    assert res.worst == pytest.approx(ref.objective, abs=1e-8)
    assert res.final_times[0] == pytest.approx(ref.T, abs=1e-7)
    assert res.solution.variables["k"] == pytest.approx(ref.variables["k"], abs=1e-6)
    assert res.success == bool(ref.success and ref.verified)
    assert res.iterations < 60


def test_collocation_from_a_shooting_guess_on_a_hard_tree():
    """Two masses, rest at each T_i, v <= vmax active: collocation from its default
    guess can stall on such a stacked problem; from the shooting solution it converges
    in a few iterations to the same optimum (within the two grids' difference)."""
    sp = ScenarioProblem(rich(), [{"m": 1.2}, {"m": 2.0}], branching=0.5)
    ms = sp.transcribe("multiple_shooting", nodes=N).solve(params={"vmax": 0.8})
    assert ms.success
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PathViolationWarning)
        col = sp.transcribe("collocation", nodes=N).solve(params={"vmax": 0.8}, guess=ms)
    assert col.status == "Solve_Succeeded" and col.iterations < 60
    assert col.worst == pytest.approx(ms.worst, rel=2e-3)
    assert col.active == ms.active == [1]
    # the heavier body rests later; sharing the control never beats its own optimum
    assert col.final_times[1] > col.final_times[0]
    alone = MultipleShooting(rich(), nodes=N).solve({"vmax": 0.8, "m": 2.0})
    assert ms.worst >= alone.objective - 1e-9


# ------------------------------------------------------------- bad inputs
@pytest.mark.parametrize(("kwargs", "match"), [
    ({"scenarios": []}, "scenarios: the scenario list is empty"),
    ({"scenarios": {"b": 1.0}}, "scenarios: give a sequence"),
    ({"scenarios": [{"b": 1.0}, {"c": 2.0}]}, r"scenarios\[1\]: parameter names"),
    ({"scenarios": [{"m": 1.0}]}, r"scenarios\[0\]: \['m'\] are not parameters"),
    ({"scenarios": [{"b": 1.0}, {"b": math.nan}]}, r"scenarios\[1\]: values must be finite"),
    ({"branching": 1.5}, "branching=1.5 is outside the horizon"),
    ({"branching": -0.1}, "branching=-0.1 is outside the horizon"),
    ({"objective": "mean"}, "objective must be one of"),
    ({"weights": [0.5, 0.5]}, "weights: only with objective='expected'"),
    ({"objective": "expected", "weights": [0.6, 0.6]}, "weights must sum to 1"),
    ({"objective": "expected", "weights": [1.5, -0.5]}, "weights must be finite and non-neg"),
    ({"objective": "expected", "weights": [1.0]}, "weights: 1 weights for 2 scenarios"),
])
def test_bad_construction_raises_naming_the_argument(kwargs, match):
    args = {"scenarios": SCEN, **kwargs}
    with pytest.raises(ProblemDefinitionError, match=match):
        ScenarioProblem(gain_problem(), args.pop("scenarios"), **args)


def test_bad_problems_and_solve_arguments_raise(robust):
    with pytest.raises(ProblemDefinitionError, match="problem: expected a one-phase"):
        ScenarioProblem(MultiPhaseProblem("mp"), SCEN)  # type: ignore[arg-type]
    p = gain_problem()
    p.free_initial_time(-1, 1)
    with pytest.raises(ProblemDefinitionError, match="free initial time"):
        ScenarioProblem(p, SCEN)
    shared_bound = gain_problem()
    shared_bound.bound_control("u", -shared_bound.p[0], shared_bound.p[0])
    with pytest.raises(ProblemDefinitionError, match="control 'u' bound depends on a scenario"):
        ScenarioProblem(shared_bound, SCEN)
    with pytest.raises(ProblemDefinitionError, match="branching=0.33 is not a node"):
        ScenarioProblem(gain_problem(), SCEN, branching=0.33).transcribe(nodes=N)
    tr = robust["multiple_shooting"]
    with pytest.raises(ProblemDefinitionError, match="scenarios: 1 scenarios given"):
        tr.solve(scenarios=[{"b": 1.0}])
    with pytest.raises(ProblemDefinitionError, match=r"scenarios\[0\]: parameter names"):
        tr.solve(scenarios=[{"gain": 1.0}, {"gain": 2.0}])
    with pytest.raises(ProblemDefinitionError, match="params: \\['b'\\] are scenario"):
        tr.solve(params={"b": 1.0})
    with pytest.raises(ProblemDefinitionError, match="weights: only with"):
        tr.solve(weights=[0.5, 0.5])
    with pytest.raises(ProblemDefinitionError, match="refine: only a collocation"):
        tr.refine()


def test_the_guide_example_runs(capsys):
    guide = Path(__file__).resolve().parents[3] / "docs" / "guides" / "ocp_scenarios.md"
    code = re.findall(r"```python\n(.*?)```", guide.read_text(), re.S)[0]
    exec(compile(code, str(guide), "exec"), {})
    out = capsys.readouterr().out.split("\n")
    assert out[0].startswith("0.1244444444") and out[0].endswith("[0, 1] True")


def test_trajectory_after_restarts_its_times():
    import numpy as np

    from ocp import Trajectory

    tr = Trajectory(np.linspace(0, 1, 5), np.arange(10.0).reshape(5, 2), np.zeros((5, 1)),
                    ("a", "b"), ("u",), mode=np.array(list("vwxyz")))
    rest = tr.after(0.5)
    assert np.allclose(rest.t, [0, 0.25, 0.5]) and rest.x[0, 0] == 4.0
    assert list(rest.mode) == ["x", "y", "z"]
