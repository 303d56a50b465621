"""The re-planning MPC: a landing controller that re-solves the landing every sample it must.

Every sample it updates its ground estimate from the reading, and re-solves the landing from
the measured state (carried over the delay to where its command acts) for the estimated
ground: the last plan's arc structure by Newton, along a path of grounds, on a neighbouring
structure or by Ipopt (:func:`~softlanding.control.resolve.replan_structure`), a fresh
transcription last; a sample the plan explains keeps it
(:func:`~softlanding.control.resolve.plan_holds`). The plan's tail (the arrest force until
the body stops, then its weight) is applied once the foot has stopped.

Its samples take milliseconds to seconds (an NLP solve): a simulation study's controller, not
a real-time one (:class:`~softlanding.control.compiled.CompiledController` is).
"""

from __future__ import annotations

import time
from typing import Any

from ocp import OptimalControlProblem, SolveError
from softlanding.control.commands import Command, at_actuation, plan_time, saturated
from softlanding.control.estimators import MeasuredEstimator, Reading
from softlanding.control.loop import LoopRecord
from softlanding.control.resolve import (
    plan_holds,
    prepare_resolves,
    replan_structure,
    transcribed_plan,
)
from softlanding.control.state_landing import plan_schedule
from softlanding.model.ground import Ground
from softlanding.model.robot import Impact, Robot
from softlanding.util.signals import raise_if_interrupted


class ReplanController:
    """The re-planning MPC (:func:`~softlanding.control.mpc_landing`'s ``"replan"``).

    Parameters
    ----------
    robot, impact : Robot, Impact
        The landing.
    model : Ground
        The ground its first plan assumed.
    plan : RefinedSwitching or ocp.Solution
        The first plan (from the impact, for ``model``).
    problem : OptimalControlProblem
        :func:`~softlanding.control.state_landing.state_landing_problem`.
    estimator : MeasuredEstimator
        Its ground estimate.
    period, delay, stop : float, int, float
        The sample period, the actuation's delay (samples), the foot's stop speed.
    record : LoopRecord, optional
        Where its samples are recorded (a new one if not given).

    Attributes
    ----------
    plan : RefinedSwitching or ocp.Solution
        The plan it applies.
    believed, planned_for : Ground
        The ground it believes now, and the one its plan was made for.
    """

    name = "replan"

    def __init__(self, robot: Robot, impact: Impact, model: Ground, plan: Any,
                 problem: OptimalControlProblem, estimator: MeasuredEstimator, *,
                 period: float, delay: int, stop: float,
                 record: LoopRecord | None = None) -> None:
        self.robot, self.impact, self.model, self.plan = robot, impact, model, plan
        self.problem, self.estimator = problem, estimator
        self.period, self.delay, self.stop = period, delay, stop
        self.record = LoopRecord() if record is None else record
        self.believed = self.planned_for = model
        self.elapsed = 0.0  # the time since the plan's start (negative: it acts later)

    def prepare(self, x0: Any) -> Command:
        """Build what a sample may need (the re-solves of the plan's structure and its
        suffixes, the transcription of the last resort: ``record.setup_ms``); the first
        plan's command.

        Parameters
        ----------
        x0 : array of 4
            The impact state.
        """
        t0 = time.perf_counter()
        prepare_resolves(self.problem, self.plan, self.robot, self.model, x0)
        self.record.setup_ms = 1e3 * (time.perf_counter() - t0)
        return self._command(0.0)

    def step(self, r: Reading) -> Command:
        """One sample: the estimate, then the plan kept or re-solved; the command.

        Parameters
        ----------
        r : Reading
            The sample.
        """
        self.record.start()
        self.estimator.filter(r)
        self._estimate(r)
        # (not at the plan's foot stop: a foot still creeping there needs a new plan, the
        # rest of this one assumes it stopped)
        if self.elapsed + r.h < plan_time(self.plan) - 1e-12 * self.period and plan_holds(
                self.robot, self.impact, r.applied, r.h, r.x_before, r.x, self.planned_for,
                self.believed):
            # the plan's own ground explains the sample and is still believed: by the
            # principle of optimality the plan's rest is the optimum from here, no re-solve
            self.record.step_paths.append("plan holds")
            self.elapsed += r.h
            self.record.stop()
            return r.issued[-1]
        path = self._replanned(r)
        self.record.step_paths.append(path)
        self.record.stop()
        return self._command(r.t - self.elapsed)

    def _command(self, origin: float) -> Command:
        """The plan's command from ``origin`` (its forces saturated at the limit)."""
        schedule = saturated(plan_schedule(self.plan, self.robot), self.robot.u_max)
        return Command(origin, schedule, plan_time(self.plan))

    def _estimate(self, r: Reading) -> None:
        """The estimate updated from the sample (two samples before it is believed)."""
        e = self.estimator.update(r)
        if e is not None:
            self.record.estimates.append(e)
            if e.samples >= 2:
                self.believed = e.ground()

    def _at_actuation(self, r: Reading) -> tuple[Any, float]:
        return at_actuation(self.robot, self.impact, r.issued, r.x, self.believed, self.delay,
                            self.period, r.t, self.stop)

    def _replanned(self, r: Reading) -> str:
        """The plan re-solved from where its command acts (its structure, else a
        transcription; else kept); how."""
        try:
            x_act, lead = self._at_actuation(r)
        except SolveError:  # the foot stops before a new plan could act: the last goes on
            x_act, lead = None, 0.0
        applied = self.elapsed + r.h + lead
        try:
            if x_act is None:
                raise SolveError("stops", message="the foot stops within the delay")
            self.plan, path = replan_structure(self.problem, self.plan, applied, self.robot,
                                               self.believed, x_act, self.planned_for)
            self.elapsed, self.planned_for = -lead, self.believed
            return path
        except SolveError:  # no structure near the last one fits: transcribe and refine anew
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        try:
            if x_act is None:
                raise SolveError("stops", message="the foot stops within the delay")
            self.plan = transcribed_plan(self.plan, applied, self.robot, self.believed, x_act)
            self.elapsed, self.planned_for = -lead, self.believed
            self.record.replans += 1
            return "transcription"
        except SolveError:  # keep the last plan for this sample
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            self.record.fallbacks += 1
            self.elapsed += r.h
            return "kept"


__all__ = ["ReplanController"]
