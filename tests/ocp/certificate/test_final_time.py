"""The free final time at a bound, a duration, a shifted clock: what the certificate and the
refinement hold the end of the horizon to.

Independent references (closed forms): ``x' = u``, ``|u| <= 1``, ``x(0) = 0``. Minimising
``-x(T) + T/2`` with ``T`` in [0.1, 2] gives ``u = 1``, ``T = 2`` (the upper bound),
``J = -1``; minimising ``2T - x(T)`` with ``T`` in [1, 5] gives ``u = 1``, ``T = 1`` (the
lower bound), ``J = 1``. There ``H = lambda u = -1`` and ``-dphi/dT`` is -1/2 and -2: the
free-T equality fails, the bound's inequality holds (``H <= -1/2`` at the upper bound, ``H >=
-2`` at the lower). The double integrator from rest, ``v(T) = 0``, maximising ``x(T)`` over a
horizon of 2: bang-bang, switch at 1, ``x(T) = 1``; with ``T`` in [0.5, 2] and the cost
``T - x(T)`` (``= T - T^2/4``), the local optimum at the lower bound ``T = 0.5``, ``J =
0.4375``.
"""

from __future__ import annotations

import numpy as np
import pytest

from ocp import (
    Collocation,
    InfeasibleError,
    MultipleShooting,
    OptimalControlProblem,
    ProblemDefinitionError,
    certify,
    refine_switching,
)
from ocp.certificate.checks import CERTIFIED, H_deviation
from ocp.certificate.costates import final_time_condition
from ocp.transcriptions.failure import DROPPED_VIOLATED


def _one_state(lo: float, hi: float, cost) -> OptimalControlProblem:
    p = OptimalControlProblem("T at a bound")
    x = p.state("x")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 0.0)
    p.free_final_time(lo, hi)
    p.minimize_terminal(cost(x, p.T))
    return p


@pytest.mark.parametrize("method", [MultipleShooting, Collocation])
@pytest.mark.parametrize("lo, hi, cost, T, J", [
    (0.1, 2.0, lambda x, T: -x + 0.5 * T, 2.0, -1.0),
    (1.0, 5.0, lambda x, T: 2 * T - x, 1.0, 1.0),
])
def test_a_free_final_time_at_its_bound_is_certified(method, lo, hi, cost, T, J):
    sol = method(_one_state(lo, hi, cost), 10).solve()
    ref = refine_switching(sol)
    assert ref.T == pytest.approx(T, abs=1e-12) and sol.objective == pytest.approx(J, abs=1e-6)
    # H = -1 against -dphi/dT = -1/2 (upper) or -2 (lower): the equality would refute
    for cert in (certify(sol), certify(sol, ref)):
        assert cert.verdict == CERTIFIED, cert.reasons
        assert cert.final_time_at_bound == (1 if T == hi else -1)  # (said, in its dict too)
        assert cert.to_dict()["final_time_at_bound"] == cert.final_time_at_bound


def test_the_bounds_side_decides():
    p = _one_state(0.1, 2.0, lambda x, T: -x + 0.5 * T)
    assert final_time_condition(p, 2.0, 0.0) == (True, 1)
    assert final_time_condition(p, 0.1, 0.0) == (True, -1)
    assert final_time_condition(p, 1.0, 0.0) == (True, 0)
    H = np.full(5, -1.0)
    assert H_deviation(H, -0.5, 1) == 0.0  # below the free-T value at the upper bound: held
    assert H_deviation(H, -0.5, -1) == pytest.approx(0.5)  # at the lower: off by 1/2
    assert H_deviation(H, -0.5, 0) == pytest.approx(0.5)  # inside: the equality
    assert H_deviation(np.array([-1.0, -0.9]), None) == pytest.approx(0.05)  # fixed T


def _double_integrator(times) -> OptimalControlProblem:
    p = OptimalControlProblem("double integrator")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(v, 0.0)
    times(p)
    return p


def test_a_fixed_duration_is_a_fixed_horizon():
    # fixed_duration(2) from t0 = 0: T cannot move, so H is free (was refuted: H = 1 held to
    # the free-T value 0; the refinement diverged with T unbounded)
    p = _double_integrator(lambda p: p.fixed_duration(2.0))
    p.minimize_terminal(-p.x[0])
    sol = MultipleShooting(p, 20).solve()
    ref = refine_switching(sol)
    assert ref.T == pytest.approx(2.0, abs=1e-12)
    assert ref.switch_times == pytest.approx([1.0], abs=1e-12)
    assert certify(sol).verdict == certify(sol, ref).verdict == CERTIFIED


def test_a_free_durations_bounds_hold_in_the_refinement():
    # free_duration(0.5, 2): the refinement read T's own bounds, infinite for a duration,
    # and returned T = 2e-15, J = 2e-15 (below the duration's bound)
    p = _double_integrator(lambda p: p.free_duration(0.5, 2.0))
    p.minimize_terminal(p.T - p.x[0])
    sol = MultipleShooting(p, 20).solve()
    ref = refine_switching(sol)
    assert ref.T == pytest.approx(0.5, abs=1e-12) and ref.objective == pytest.approx(0.4375)
    assert certify(sol).verdict == certify(sol, ref).verdict == CERTIFIED


def test_a_clock_not_starting_at_zero_is_refused_by_the_refinement():
    # t0 = 1, T = 3: the refinement measured its horizon from 0 (3 long) and returned J =
    # -2.25 for the transcription's -1, certified
    p = _double_integrator(lambda p: (p.fixed_initial_time(1.0), p.fixed_final_time(3.0)))
    p.minimize_terminal(-p.x[0])
    sol = MultipleShooting(p, 20).solve()
    assert sol.objective == pytest.approx(-1.0, abs=1e-6)
    assert certify(sol).verdict == CERTIFIED
    with pytest.raises(ValueError, match="initial time fixed at 1; the refinement's time "
                                         "starts at 0"):
        refine_switching(sol)


def test_contradictory_end_conditions_are_not_dropped_into_a_success():
    p = _double_integrator(lambda p: p.fixed_final_time(2.0))
    p.terminal_constraint(p.x[0], 0.5)
    p.terminal_constraint(p.x[0], 0.6)
    p.minimize_integral(p.u[0] ** 2)
    with pytest.raises(InfeasibleError, match="the end conditions contradict: with terminal "
                                              r"'x\(tf\) = 0.6' left out, the solution "
                                              "misses it by 0.1") as info:
        MultipleShooting(p, 20).solve(drop_dependent=True)
    assert info.value.status == DROPPED_VIOLATED


@pytest.mark.parametrize("tol", [float("nan"), -1.0, 0.0])
def test_a_verify_tolerance_that_checks_nothing_is_refused(tol):
    p = _one_state(0.1, 2.0, lambda x, T: -x + 0.5 * T)
    with pytest.raises(ProblemDefinitionError, match="verify_tol must be a relative "
                                                     "tolerance"):
        MultipleShooting(p, 10, verify_tol=tol)


@pytest.mark.parametrize("times", [
    lambda p: (p.fixed_final_time(3.0), p.free_initial_time(5.0, 6.0)),
    lambda p: (p.free_final_time(1.0, 2.0), p.free_initial_time(5.0, 6.0)),
    lambda p: (p.free_initial_time(5.0, 6.0), p.fixed_final_time(3.0)),
    lambda p: (p.free_initial_time(5.0, 6.0), p.free_final_time(1.0, 2.0)),
    lambda p: (p.free_final_time(1.0, 2.0), p.fixed_initial_time(5.0)),
])
def test_an_initial_time_after_every_final_time_is_refused_when_written(times):
    # (in one order it was accepted, and only Ipopt found the horizon empty)
    p = OptimalControlProblem("times")
    p.state("x")
    with pytest.raises(ProblemDefinitionError, match="initial time|final time"):
        times(p)
