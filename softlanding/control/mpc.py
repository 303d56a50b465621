"""Model-predictive control of the landing, with the ground estimated on line.

Every sample (period ``P``) the controller measures the state and the foot's acceleration,
updates its ground estimate (:class:`~softlanding.control.estimation.GroundEstimator`),
re-solves the landing from the measured state for the estimated ground
(:func:`~softlanding.control.state_landing.state_landing_problem`, through
:func:`ocp.refine_structure`: the last plan's arc structure re-solved, Newton first) and
applies the new plan for one period. The plan's tail (the arrest force until the body stops,
then its weight) is applied once the foot has stopped. The plant is the exact simulator on
the true ground (:class:`~softlanding.control.plant.SteppingPlant`).
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from ocp import MultipleShooting, Solution, SolveError, Trajectory, refine_structure
from ocp.switching import detect_arcs, refine_switching
from softlanding.control.estimation import GroundEstimate, GroundEstimator
from softlanding.control.plant import SteppingPlant
from softlanding.control.state_landing import (
    ground_numbers,
    state_landing_problem,
    state_parameters,
)
from softlanding.errors import check, check_count, expect
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import (
    arrest_schedule,
    landing_schedule,
    solve_landing,
    transcribed_schedule,
)
from softlanding.optimal.limits import force_limit
from softlanding.simulation.simulator import LandingResult, joined_trajectory
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted

#: The default sample period, in the paper's time unit ``sqrt(m_t / k_g)`` (26 ms on the
#: paper's rig, so 0.26 ms: a 4 kHz controller): a tenth of the shortest bang arc of the
#: paper's landings.
DEFAULT_PERIOD = 0.01


@dataclass
class MPCLanding:
    """A landing under model-predictive control.

    Attributes
    ----------
    robot, impact, ground
        The landing, and the true ground.
    model : Ground
        The ground the first plan assumed.
    period : float
        The sample period.
    result : LandingResult
        The final simulation (from the foot's stop to rest).
    depth : float
        The final depth.
    stroke_min, stroke_max, u_peak : float
        Over the whole landing (every step and the end).
    step_times_ms : list of float
        The computation of each sample (estimate and re-plan), in ms.
    estimates : list of GroundEstimate
        The ground estimate after each sample.
    replans : int
        Samples whose arc structure changed (re-planned by a transcription).
    fallbacks : int
        Samples whose re-plan failed (the previous plan was kept).
    setup_ms : float
        The re-solve's one-time build before the landing (not a step's time).
    samples : int
        Samples taken while the foot yielded.
    pieces : list of (float, LandingResult)
        The plant's simulations and their start times (the last one runs to rest).
    """

    robot: Robot
    impact: Impact
    ground: Ground
    model: Ground
    period: float
    result: LandingResult
    depth: float
    stroke_min: float
    stroke_max: float
    u_peak: float
    step_times_ms: list[float] = field(default_factory=list)
    estimates: list[GroundEstimate] = field(default_factory=list)
    replans: int = 0
    fallbacks: int = 0
    samples: int = 0
    setup_ms: float = 0.0
    pieces: list[tuple[float, LandingResult]] = field(default_factory=list)

    def trajectory(self, n: int = 1500) -> Trajectory:
        """The whole landing from the plant's exact simulations (``mode``: ground mode).

        Parameters
        ----------
        n : int
            About how many samples.
        """
        end = self.pieces[-1][0] + 1.2 * max(self.result.T, 1e-9)
        starts = [t0 for t0, _ in self.pieces] + [end]
        return joined_trajectory([(r, starts[k], starts[k + 1])
                                  for k, (_, r) in enumerate(self.pieces)], n)

    @property
    def stroke_held(self) -> bool:
        """``0 <= x_b - x_f <= s`` over the whole landing (to 1e-9)."""
        tol = 1e-9 * max(1.0, self.robot.s)
        return bool(self.stroke_min >= -tol and self.stroke_max <= self.robot.s + tol)

    @property
    def feasible(self) -> bool:
        """The stroke held and rest proven at the end."""
        return self.stroke_held and self.result.rest_proven

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        t = np.array(self.step_times_ms) if self.step_times_ms else np.array([np.nan])
        return json_safe({
            "depth": self.depth, "feasible": self.feasible, "stroke_held": self.stroke_held,
            "rest_proven": self.result.rest_proven, "stroke_min": self.stroke_min,
            "stroke_max": self.stroke_max, "u_peak": self.u_peak, "period": self.period,
            "samples": self.samples, "replans": self.replans, "fallbacks": self.fallbacks,
            "step_time_median_ms": float(np.median(t)),
            "step_time_p99_ms": float(np.percentile(t, 99)), "setup_ms": self.setup_ms,
            "estimate": None if not self.estimates else self.estimates[-1].__dict__,
            "ground": self.ground.to_dict(), "model_ground": self.model.to_dict(),
            "robot": self.robot.to_dict(), "impact": self.impact.to_dict()})


def mpc_landing(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                ground: Ground = LINEAR_GROUND, *, model: Ground = LINEAR_GROUND,
                period: float = DEFAULT_PERIOD, estimate: bool = True,
                max_samples: int = 100_000) -> MPCLanding:
    """Land on ``ground`` under MPC whose first plan assumes ``model``.

    Parameters
    ----------
    impact : Impact or float
        The impact velocity.
    robot : Robot
        The robot (with a force limit).
    ground : Ground
        The true ground (the plant's).
    model : LinearGround or DragGround
        What the controller assumes before its first measurement (the paper's ground).
    period : float
        The sample period (> 0).
    estimate : bool
        Update the ground estimate from the measurements (else keep ``model``).
    max_samples : int
        A bound on the samples while the foot yields.

    Raises
    ------
    ParameterError
        Bad arguments.
    ocp.SolveError
        The first plan cannot be made.
    """
    impact = Impact.of(impact)
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    period = check("period", period, (lambda v: v > 0, "must be > 0"))
    max_samples = check_count("max_samples", max_samples, 1, 10**7)
    first = solve_landing(impact, robot, model, replay=False)
    plan: Any = first.refined if first.refined is not None else first.transcribed
    problem = state_landing_problem()
    est = GroundEstimator(robot, drag=True, prior=ground_numbers(model))
    plant = SteppingPlant(robot, impact, ground)
    t0 = time.perf_counter()
    if not isinstance(plan, Solution):  # build the re-solve once, before the landing starts
        with contextlib.suppress(SolveError):
            _replan(problem, plan, 0.0, robot, model, plant.x)
    setup_ms = 1e3 * (time.perf_counter() - t0)
    out_times: list[float] = []
    estimates: list[GroundEstimate] = []
    fallbacks, replans, elapsed, samples = 0, 0, 0.0, 0
    believed = model
    # the foot has stopped when it is static, or creeps by rounding at the crater's exact
    # capacity (the optimal arrest uses all of it)
    stop = 1e-9 * max(1.0, abs(impact.v0))
    while plant.x[3] < -stop and samples < max_samples:
        schedule = _shifted(_schedule(plan, robot), elapsed)
        # a sample that would pass the planned stop of the foot ends there: the arrest is
        # then computed from the measured state, not from the plan's prediction of it
        h = min(period, _plan_time(plan) - elapsed)
        h = h if h > 1e-9 * period else period
        plant.step(schedule, h)  # the schedule's time starts at the step
        samples += 1
        if plant.x[3] >= -stop:  # the foot stopped within the sample: its arrest follows
            break
        t0 = time.perf_counter()
        u_end = _force_at_end(schedule, plant.x, h)  # the force the sample ended under
        if estimate:
            e = est.update(plant.x, plant.foot_acceleration(u_end), u_end)
            estimates.append(e)
            if e.samples >= 2:
                believed = e.ground()
        try:
            plan = _replan(problem, plan, elapsed + h, robot, believed, plant.x)
            elapsed = 0.0
        except SolveError:  # the structure changed: transcribe and refine anew
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            try:
                plan = _transcribed_plan(plan, elapsed + h, robot, believed, plant.x)
                elapsed = 0.0
                replans += 1
            except SolveError:  # keep the last plan for this sample
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                fallbacks += 1
                elapsed += h
        out_times.append(1e3 * (time.perf_counter() - t0))
    final = plant.finish(arrest_schedule(plant.x, robot.r_m) if plant.x[3] >= -stop else
                         _shifted(_schedule(plan, robot), elapsed))
    stroke = [r.stroke_min for _, r in plant.history], [r.stroke_max for _, r in plant.history]
    return MPCLanding(robot=robot, impact=impact, ground=ground, model=model, period=period,
                      result=final, depth=final.depth, stroke_min=min(stroke[0]),
                      stroke_max=max(stroke[1]),
                      u_peak=max(r.u_peak for _, r in plant.history),
                      step_times_ms=out_times, estimates=estimates, replans=replans,
                      fallbacks=fallbacks, samples=samples, setup_ms=setup_ms,
                      pieces=list(plant.history))


def _plan_time(plan: Any) -> float:
    """When the plan has the foot stop (from its start)."""
    return float(plan.T if isinstance(plan, Solution) else np.sum(plan.durations))


def _shifted(schedule: Any, skip: float) -> Any:
    """``schedule`` from ``skip`` on (its time restarted at 0)."""
    if skip <= 0:
        return schedule
    times = np.asarray(schedule.times, float)
    i = int(np.searchsorted(times, skip, side="right"))
    rest = tuple(float(t - skip) for t in times[i:])
    if isinstance(schedule, ForceSchedule):
        return ForceSchedule(rest, tuple(schedule.values[i:]))
    return FeedbackSchedule(rest, tuple(schedule.gains[i:]))


def _force_at_end(schedule: Any, x: np.ndarray, t: float) -> float:
    return _force(schedule, t * (1 - 1e-12), x)


def _force(schedule: Any, t: float, x: np.ndarray) -> float:
    """The schedule's force at time ``t`` in state ``x``."""
    i = int(np.searchsorted(np.asarray(schedule.times), t, side="right"))
    if isinstance(schedule, ForceSchedule):
        return float(schedule.values[i])
    row = np.asarray(schedule.gains[i], float)
    return float(row[:4] @ x + row[4])


def _schedule(plan: Any, robot: Robot) -> ForceSchedule | FeedbackSchedule:
    """A plan's open-loop control: refined arcs, or a transcription's steps (a structure that
    is not bang-bang, e.g. a singular creep to the depth that holds the robot's weight)."""
    if isinstance(plan, Solution):
        return transcribed_schedule(plan, robot.r_m, force_limit(robot))
    return landing_schedule(plan, robot.r_m)


def _replan(problem: Any, plan: Any, applied: float, robot: Robot, believed: Ground,
            x: np.ndarray) -> Any:
    """The last plan's structure re-solved from ``x`` for the believed ground."""
    if isinstance(plan, Solution):
        raise SolveError("transcribed", message="a transcribed plan has no structure to re-solve")
    durs = np.asarray(plan.durations, float).copy()
    keep = list(range(len(durs)))
    while applied > 0 and keep:
        i = keep[0]
        if durs[i] > applied:
            durs[i] -= applied
            break
        applied -= durs[i]
        keep.pop(0)
    if not keep:
        raise SolveError("no_arcs_left", message="the plan has run out")
    r = refine_structure(problem, tuple(plan.modes[i] for i in keep), durs[keep], x,
                         state_parameters(robot, believed, x))
    return _checked(r)


def _checked(r: Any) -> Any:
    """A re-plan that keeps its structure (no arc collapsed) and is finite."""
    if not (np.all(np.isfinite(r.durations)) and np.all(np.isfinite(r.xT))):
        raise SolveError("not_finite", message="the re-plan is not finite")
    if min(r.durations) <= 1e-9 * r.T:
        raise SolveError("arc_collapsed", message="an arc of the structure collapsed")
    return r


@lru_cache(maxsize=1)
def _state_transcription() -> MultipleShooting:
    return MultipleShooting(state_landing_problem(), nodes=60, integrator="rk4", substeps=4,
                            expand=True)


def _transcribed_plan(plan: Any, applied: float, robot: Robot, believed: Ground,
                      x: np.ndarray) -> Any:
    """The landing from ``x`` transcribed (from the rest of the last plan) and refined."""
    tr = _state_transcription()
    params = state_parameters(robot, believed, x)
    if isinstance(plan, Solution) and plan.transcription is tr:
        sol = tr.solve(params, warm_start=plan)
    else:
        rest = plan.trajectory(200)
        keep = rest.t >= applied
        guess = Trajectory(rest.t[keep] - applied, rest.x[keep], rest.u[keep],
                           rest.state_names, rest.control_names)
        try:
            sol = tr.solve(params, guess=guess)
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            sol = tr.solve(params)
    st = detect_arcs(sol).without_trailing_constrained()
    if not st.refinable:  # not bang-bang (a singular creep): the transcription is the plan
        return sol
    try:
        return _checked(refine_switching(sol, st))
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return sol


__all__ = ["DEFAULT_PERIOD", "MPCLanding", "mpc_landing"]
