"""Issue 45 item 4: multistart spends its starts where optima differ, and stops when they repeat.

The case: Dubins' car (tests/oracles/several_optima.py) to a point behind it,
two local optima in closed form (turn left first: 5.695792, right first:
6.487898). The default guess does not converge and the sampled starts of
the tree before (states bent through box points, constant controls) reached
no optimum from 16 starts; the structured starts (bang sequences simulated,
the final time where the simulation comes closest to the target) reach both.

Fails on the tree before: there are no structured starts, no ``stop``.
"""

import math
from functools import cache

import casadi as ca
import numpy as np
import pytest

from ocp import Collocation, OptimalControlProblem, multistart
from ocp.definition.errors import ProblemDefinitionError
from ocp.search.starts import default_solution, start_coordinates, unpacked
from ocp.search.structured import PATTERNS, StructuredStarts, affine_controls
from tests.oracles.ocp_suite.pendulum_swingup import build as pendulum
from tests.oracles.several_optima import (
    DUBINS_TARGET,
    dubins_point,
    dubins_point_lengths,
    dubins_transcription,
)

LEFT, RIGHT = dubins_point_lengths()


@cache
def car() -> Collocation:
    return dubins_transcription()


@cache
def run(stop=None):
    return multistart(car(), n=8, seed=0, stop=stop)


def test_the_closed_form_lengths():
    """The oracle: LS and RS as an arc and a tangent, checked against a direct construction
    (the arc's end point, the tangent's direction and the target lie on one line)."""
    assert LEFT == pytest.approx(5.6957915978621525, rel=1e-14)
    assert RIGHT == pytest.approx(6.487898455928486, rel=1e-14)
    alpha = LEFT - math.sqrt((DUBINS_TARGET[0]) ** 2 + (DUBINS_TARGET[1] - 1) ** 2 - 1)
    end = np.array([math.sin(alpha), 1 - math.cos(alpha)])  # after turning left by alpha
    heading = np.array([math.cos(alpha), math.sin(alpha)])
    to_target = np.array(DUBINS_TARGET) - end
    assert heading @ to_target == pytest.approx(np.linalg.norm(to_target), rel=1e-12)


def test_which_controls_get_bang_levels():
    assert affine_controls(pendulum()) == [True]
    assert affine_controls(dubins_point()) == [True]
    p = OptimalControlProblem("heading")
    x = p.state("x")
    th, a = p.control("theta", -3, 3), p.control("a", -1, 1)
    p.set_dynamics({"x": ca.cos(th) + a})
    p.minimize_integral(a**2)
    assert affine_controls(p) == [False, False]  # in cos; in a quadratic cost
    p.minimize_integral(x)
    assert affine_controls(p) == [False, False]


def test_no_structured_start_is_made_twice():
    """The sequences without switches have no random time: on the tree before, their
    second turn (starts 7 and 8 of a run) repeated the first's solve exactly."""
    tr = car()
    maker = StructuredStarts(tr, {}, start_coordinates(tr, {}), default_solution(tr, {}))
    rng = np.random.default_rng(0)
    points = [maker.make(k, rng)[0] for k in range(2 * len(PATTERNS))]
    keys = [tuple(sorted(p.items())) for p in points]
    assert len(set(keys)) == len(keys)
    assert [p["u"] for p in points[:2]] == [-1.0, 1.0]  # the first turn as dealt
    assert all("u.t1" in p for p in points[len(PATTERNS):])  # then only switching ones


def test_a_structured_start_follows_the_dynamics_to_its_closest_approach():
    """A start with u = +1 throughout (sequence 1: no switch, high): the heading is t, the
    position the unit circle round (0, 1), corrected linearly to the target; the final
    time is where that circle comes closest to the target."""
    tr = car()
    coords = start_coordinates(tr, {})
    maker = StructuredStarts(tr, {}, coords, default_solution(tr, {}))
    assert PATTERNS[1] == (0, 1)
    point, w = maker.make(1, np.random.default_rng(0))
    assert point["u"] == 1.0 and "u.t1" not in point
    beta = math.atan2(DUBINS_TARGET[1] - 1, DUBINS_TARGET[0]) % (2 * math.pi)
    closest = beta + math.pi / 2  # the angle turned from (0, 0) to the nearest point
    T = point["T"]
    grid = coords[-1].hi / 400  # the simulation's step over the time box
    assert abs(T - closest) <= grid
    ps = unpacked(tr, {}, w).phases[0]
    t, x, u = ps.sample(50)
    assert t[-1] == pytest.approx(T) and np.allclose(u, 1.0)
    assert np.allclose(x[:, 2], t, atol=1e-9)  # psi' = u: exact
    s = t / T
    miss = np.array(DUBINS_TARGET) - [math.sin(T), 1 - math.cos(T)]
    circle = np.column_stack([np.sin(t), 1 - np.cos(t)]) + s[:, None] * miss
    # up to the linear interpolation of the simulation (step ~0.03) and of the mesh
    assert np.allclose(x[:, :2], circle, atol=1e-3)
    assert abs(miss).max() > 0.1  # the correction is seen
    assert np.allclose(x[-1, :2], DUBINS_TARGET)


def test_the_car_behind_finds_both_turns_where_sampled_starts_found_none():
    res = run()
    first = res.starts[0]
    assert first.origin == "default" and not first.success  # the default guess fails
    assert res.best.verified
    assert res.best.objective == pytest.approx(LEFT, rel=2e-3)  # 16 intervals
    objs = [o.objective for o in res.optima]
    assert any(o == pytest.approx(RIGHT, rel=2e-3) for o in objs)
    bang = [s for s in res.starts if s.origin == "bang"]
    # the first round alternates the kinds (2 of its 4 bang), later rounds follow the yields
    assert len(bang) >= 2 and all(s.verified for s in bang)
    assert sorted(s.origin for s in res.starts[1:5]) == ["bang", "bang", "sobol", "sobol"]
    assert sum(o.fraction for o in res.optima) == pytest.approx(
        1 - len(res.failures) / len(res.starts))
    assert "(x" in res.message and "%" in res.message and not res.stopped


def test_it_stops_when_the_optima_repeat_and_says_why():
    full, short = run(), run((1, 2))
    assert len(full.starts) == 8 and full.requested == 8
    n = len(short.starts)
    assert n < 8 and short.requested == 8
    assert short.stopped.startswith(f"stopped early after {n} starts")
    assert short.stopped in short.message
    # the same starts as the full run, in the same order, up to the stop
    assert [s.point for s in short.starts] == [s.point for s in full.starts[:n]]
    # the rule held: the best reached, and the last 2 starts brought no new objective
    objs = [s.objective for s in short.starts if s.verified]
    assert short.optima[0].count >= 1
    last = [s.objective for s in short.starts[-2:] if s.verified]
    earlier = [s.objective for s in short.starts[:-2] if s.verified]
    assert all(any(o == pytest.approx(e, rel=1e-6) for e in earlier) for o in last)
    assert min(objs) == pytest.approx(short.best.objective)


@pytest.mark.slow  # worker processes start and import the toolkit
def test_processes_stop_at_the_same_start():
    """Results are taken in the order of the starts, so a pool stops where a serial run
    does (starts queued past the stop are cancelled)."""
    short = run((1, 2))
    par = multistart(dubins_transcription, n=8, seed=0, stop=(1, 2), workers=2)
    assert par.stopped == short.stopped
    assert [(s.point, s.status) for s in par.starts] == [
        (s.point, s.status) for s in short.starts]
    assert [o.objective for o in par.optima] == pytest.approx(
        [o.objective for o in short.optima], rel=1e-9)


@pytest.mark.parametrize(("kwargs", "named"), [
    ({"structured": 1.5}, r"multistart\(structured\) must be a fraction"),
    ({"structured": True}, r"multistart\(structured\)"),
    ({"stop": (0, 3)}, r"multistart\(stop\[0\]\) must be >= 1"),
    ({"stop": (2,)}, r"multistart\(stop\) must be a pair"),
    ({"stop": "x"}, r"multistart\(stop\) must be a pair"),
    ({"stop": (2, 1.5)}, r"multistart\(stop\[1\]\) must be an integer"),
])
def test_bad_strategy_arguments_are_refused(kwargs, named):
    with pytest.raises(ProblemDefinitionError, match=named):
        multistart(car(), **kwargs)


class _Phase:
    """A phase of a stand-in solution: the state ``x = a t`` on [0, 1]."""

    t0, T = 0.0, 1.0

    def __init__(self, a):
        self.a = a

    def at(self, t):
        return self.a * np.asarray(t)[:, None], None


def _solution(objective, a):
    from types import SimpleNamespace

    return SimpleNamespace(objective=objective, phases=[_Phase(a)])


def test_the_stop_rule_reads_objectives_so_equal_cost_families_count_once():
    """Two trajectories of equal cost are two optima (reported apart) but one objective
    level for the stop rule: a family of equal-cost solutions must not keep a run going."""
    from ocp.search.optima import Optima, StopRule

    opt = Optima(1e-6, 1e-3)
    opt.add(0, _solution(1.0, 1.0))
    opt.add(1, _solution(1.0, 2.0))  # same cost, another trajectory
    opt.add(2, None)  # a failed start
    assert [o.starts for o in opt.ranked()] == [[0], [1]]
    assert opt.best_count() == 2 and opt.last_new == 0
    assert StopRule(2, 2).reason(opt, 2).startswith("stopped early after 3 starts")
    assert StopRule(3, 2).reason(opt, 2) == ""  # the best reached twice only
    opt.add(3, _solution(1.5, 1.0))  # a new, worse level
    assert opt.last_new == 3 and StopRule(2, 1).reason(opt, 3) == ""
    assert [round(o.fraction, 2) for o in opt.ranked()] == [0.25, 0.25, 0.25]
