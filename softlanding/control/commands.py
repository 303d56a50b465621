"""The commands a landing controller issues, and what the loop reads from them.

A command is the force from a time origin on, as the plant applies it: an open-loop
schedule (:class:`~softlanding.model.controllers.ForceSchedule`, or a
:class:`~softlanding.model.controllers.FeedbackSchedule` whose rows may be affine laws),
and when the plan has the foot stop (from the origin). The actuator applies the command
issued ``delay`` samples ago; a controller that re-plans starts from where its command will
act (:func:`at_actuation`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ocp import Solution, SolveError
from softlanding.errors import RestNotProvenError
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.ground import Ground
from softlanding.model.robot import Impact, Robot
from softlanding.simulation.simulator import simulate

Schedule = ForceSchedule | FeedbackSchedule
"""A command's force: constant pieces, or affine laws of the state."""


class Command(NamedTuple):
    """A controller's command: its force from ``origin`` on.

    Attributes
    ----------
    origin : float
        The time (since impact) the schedule's time starts at.
    schedule : ForceSchedule or FeedbackSchedule
        The force from ``origin`` on.
    stop : float
        When the plan has the foot stop, from ``origin`` (``inf``: not planned).
    """

    origin: float
    schedule: Schedule
    stop: float


def plan_time(plan: Any) -> float:
    """When a state-started plan has the foot stop (from its start).

    Parameters
    ----------
    plan : RefinedSwitching or ocp.Solution
        The plan.
    """
    return float(plan.T if isinstance(plan, Solution) else np.sum(plan.durations))


def shifted(schedule: Any, skip: float) -> Any:
    """``schedule`` from ``skip`` on (its time restarted at 0).

    Parameters
    ----------
    schedule : ForceSchedule or FeedbackSchedule
        The schedule.
    skip : float
        The time cut off its start.
    """
    if skip <= 0:
        return schedule
    times = np.asarray(schedule.times, float)
    i = int(np.searchsorted(times, skip, side="right"))
    rest = tuple(float(t - skip) for t in times[i:])
    if isinstance(schedule, ForceSchedule):
        return ForceSchedule(rest, tuple(schedule.values[i:]))
    return FeedbackSchedule(rest, tuple(schedule.gains[i:]))


def force_integrals(schedule: Any, h: float) -> tuple[float, float]:
    """``int_0^h u dt`` and ``int_0^h (h - t) u dt`` of a force schedule over a sample
    (a feedback schedule, the arrest's, which no yielding foot runs: its force at the end).

    Parameters
    ----------
    schedule : ForceSchedule or FeedbackSchedule
        The force over the sample (its time from the sample's start).
    h : float
        The sample's length.
    """
    if not isinstance(schedule, ForceSchedule):
        u = float(schedule.gains[-1][4])
        return u * h, 0.5 * u * h * h
    u1 = u2 = t0 = 0.0
    for t, u in zip((*schedule.times, math.inf), schedule.values, strict=True):
        t1 = min(float(t), h)
        if t1 > t0:  # (h - t)^2 / 2 from t0 to t1
            u1 += u * (t1 - t0)
            u2 += u * 0.5 * ((h - t0) ** 2 - (h - t1) ** 2)
            t0 = t1
        if t1 >= h:
            break
    return u1, u2


def force_at(schedule: Any, t: float, x: np.ndarray) -> float:
    """The schedule's force at time ``t`` in state ``x``.

    Parameters
    ----------
    schedule : ForceSchedule or FeedbackSchedule
        The schedule.
    t : float
        The time (from the schedule's start).
    x : array of 4
        The state.
    """
    i = int(np.searchsorted(np.asarray(schedule.times), t, side="right"))
    if isinstance(schedule, ForceSchedule):
        return float(schedule.values[i])
    row = np.asarray(schedule.gains[i], float)
    return float(row[:4] @ x + row[4])


def force_at_end(schedule: Any, x: np.ndarray, h: float) -> float:
    """The force a sample of length ``h`` ended under, in its end state ``x``.

    Parameters
    ----------
    schedule : ForceSchedule or FeedbackSchedule
        The force over the sample.
    x : array of 4
        The state at the sample's end.
    h : float
        The sample's length.
    """
    return force_at(schedule, h * (1 - 1e-12), x)


def at_actuation(robot: Robot, impact: Impact, issued: list[Command], x: np.ndarray,
                 believed: Ground, delay: int, period: float, t: float,
                 stop: float) -> tuple[np.ndarray, float]:
    """Where a control computed now starts to act, and how long from now: the measured
    state ``x`` carried over the ``delay`` samples of the commands already issued (the last
    ``delay`` of ``issued`` in flight) on the believed ground; ``(x, 0)`` without delay.

    Parameters
    ----------
    robot, impact : Robot, Impact
        The landing.
    issued : list of Command
        Every command issued so far.
    x : array of 4
        The measured state.
    believed : Ground
        The ground the controller believes.
    delay : int
        Samples between a measurement and its actuation.
    period : float
        The sample period.
    t : float
        The measurement's time.
    stop : float
        The foot's speed below which it counts as stopped.

    Raises
    ------
    ocp.SolveError
        The foot stops within the delay (no plan from there).
    """
    x = np.array(x, float)
    n = len(issued)
    for j in range(delay):
        origin, command, _ = issued[max(0, n - delay + j)]
        try:
            x = simulate(robot, impact, shifted(command, t + j * period - origin), believed,
                         x0=x, t_max=period, energy=False).trajectory(t_end=period,
                                                                      n=2).x[-1]
        except RestNotProvenError as err:  # (the foot stopped and rests within the sample)
            raise SolveError("stops", message="the foot stops within the delay") from err
        if not x[3] < -stop:
            raise SolveError("stops", message="the foot stops within the delay")
    return x, delay * period


def saturated(control: Any, u_max: float | None) -> Any:
    """``control`` with its constant forces clipped to ``[-u_max, u_max]`` (itself where
    none is beyond; an affine row is left to the plant, which saturates it exactly:
    :meth:`~softlanding.control.plant.SteppingPlant.step`).

    Parameters
    ----------
    control : controller
        A schedule (others are returned as they are).
    u_max : float or None
        The force limit (None: none).
    """
    if u_max is None:
        return control
    if isinstance(control, ForceSchedule):
        if max(abs(v) for v in control.values) <= u_max:
            return control
        return ForceSchedule(control.times, tuple(min(u_max, max(-u_max, v))
                                                  for v in control.values))
    if isinstance(control, FeedbackSchedule):
        rows = tuple(row if any(row[:4]) or abs(row[4]) <= u_max
                     else (*row[:4], min(u_max, max(-u_max, row[4]))) for row in control.gains)
        return control if rows == control.gains else FeedbackSchedule(control.times, rows)
    return control


__all__ = ["Command", "Schedule", "at_actuation", "force_at", "force_at_end",
           "force_integrals", "plan_time", "saturated", "shifted"]
