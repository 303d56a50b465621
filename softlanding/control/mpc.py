"""Model-predictive control of the landing, with the ground estimated on line.

Every sample (period ``P``) the controller measures the state and the foot's acceleration,
updates its ground estimate (:class:`~softlanding.control.estimation.GroundEstimator`),
re-solves the landing from the measured state for the estimated ground
(:func:`~softlanding.control.state_landing.state_landing_problem`, through
:func:`ocp.refine_structure`: the last plan's arc structure re-solved, Newton first) and
applies the new plan for one period. The plan's tail (the arrest force until the body stops,
then its weight) is applied once the foot has stopped. The plant is the exact simulator on
the true ground (:class:`~softlanding.control.plant.SteppingPlant`).

A sample the plan explains keeps the plan without a re-solve: the measured state equals the
plan's exact prediction on the ground it was planned for, and the estimate is still that
ground (both to ``PLAN_HOLDS_TOL``). For refined (bang-bang) plans this is the principle of
optimality: the rest of an optimal plan is optimal from any state on its path. A transcribed
plan (a creep, not bang-bang) is kept the same way; it is optimal on its own grid only, and
re-solving it every sample changed the study's depths by at most 4e-9.
"""

from __future__ import annotations

import contextlib
import math
import time
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from ocp import (
    OptimalControlProblem,
    Solution,
    SolveError,
    Trajectory,
    refine_structure,
)
from ocp.structure.switching import Mode, RefinedSwitching, clear_cache
from softlanding.control import bangbang as bb
from softlanding.control.estimation import GroundEstimate, GroundEstimator, filtered_weight
from softlanding.control.foot_filter import PROVISIONAL, covariance, filter_step, new_filter
from softlanding.control.loop_replay import CompiledRecord, CompiledSample
from softlanding.control.plant import SteppingPlant
from softlanding.control.recovery import (  # noqa: F401 (mpc.RECOVERY_SAMPLES, as before)
    RECOVERY_SAMPLES,
    filtered_sample,
)
from softlanding.control.state_landing import (
    ground_numbers,
    plan_schedule,
    solve_from_state,
    state_landing_problem,
    state_parameters,
    state_transcription,
)
from softlanding.errors import ParameterError, RestNotProvenError, check, check_count, expect
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.dynamics import VB, robot_rhs
from softlanding.model.ground import LINEAR_GROUND, DragGround, Ground, LinearGround
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.model.terrain import paper_rig_units
from softlanding.optimal.landing import (
    T_MAX,
    affine_laws,
    arrest_schedule,
    solve_landing,
)
from softlanding.optimal.limits import force_limit
from softlanding.simulation.simulator import LandingResult, joined_trajectory, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted

#: The default sample period, in the paper's time unit ``sqrt(m_t / k_g)`` (26 ms on the
#: paper's rig, so 0.26 ms: a 4 kHz controller): a tenth of the shortest bang arc of the
#: paper's landings.
DEFAULT_PERIOD = 0.01

#: The shortest sample period taken: 1e-4 (2.6 us on the paper's rig), about 10,000 samples
#: over the longest landing of the unknown-ground study (T < 1); a shorter one would run for
#: hours (1e-9: a million times more samples) and is refused at once.
MIN_PERIOD = 1e-4

#: The longest sample period taken: the landing problem's horizon bound (``T_MAX``). A period
#: beyond the landing is one open-loop sample; far beyond it (1e300) the simulation's times
#: lose every digit of the landing's.
MAX_PERIOD = T_MAX

#: The controllers :func:`mpc_landing` runs, by name.
CONTROLLERS = ("replan", "bangbang")

#: What the ground estimate regresses (:func:`mpc_landing`'s ``estimator``).
ESTIMATORS = ("measured", "filtered")

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
        The computation of each sample (its estimate and control update only), in ms of
        wall time.
    step_cpu_ms : list of float
        The same in the process's CPU time (what a loaded machine's waits do not inflate).
    estimates : list of GroundEstimate
        The ground estimate after each sample.
    replans : int
        Samples whose arc structure changed (re-planned by a transcription).
    fallbacks : int
        Samples whose re-plan failed (the previous plan was kept).
    structure_changes : int
        Samples re-planned by Newton on a neighbouring structure (an arc dropped or added).
    step_paths : list of str
        What re-planned each sample: ``"plan holds"`` (no re-solve: the sample went as the
        plan predicted on its ground, which is still the estimate), ``"newton"`` (the plan's
        structure), ``"structure"``
        (a neighbouring structure, Newton), ``"continuation"`` (Newton along grounds from the
        plan's to the estimate), ``"ipopt"`` (the plan's structure, Ipopt),
        ``"transcription"`` or ``"kept"`` (every re-plan failed).
    setup_ms : float
        The one-time builds before the landing (not a step's time): the re-solves of the
        plan's structure and its suffixes, and the transcription of the last resort.
    prepare_time_s : float
        Everything before the impact, in s of wall time: the first plan, the builds
        (``setup_ms``) and any compilation; never counted in a step's time.
    controller : str
        The controller's name (:data:`CONTROLLERS`).
    sample_limit_hit : bool
        ``max_samples`` ended the sampling before the foot stopped.
    uncovered : int
        ``controller="bangbang"``: samples the compiled controller did not cover (its
        structure, push then pull, did not fit the state and estimate); each of them and the
        rest of the landing fell back to the re-planning MPC (``step_paths`` says why).
    deferred : int
        ``controller="bangbang"``: samples whose integrator steps ran out (the bound on one
        sample's work, :data:`softlanding.control.bangbang.WORK`): each applied the last
        whole Newton iterate, or the last plan, and the next sample's Newton went on from
        there (``step_paths``: ``"bangbang (deferred)"``).
    creep_samples : int
        ``controller="bangbang"``: samples under the creep law
        (:mod:`softlanding.control.creep`; ``step_paths``: ``"bangbang (creep law)"``).
    step_work : list of int
        ``controller="bangbang"``: the integrator steps of each sample the compiled
        controller ran (at most :data:`softlanding.control.bangbang.WORK`).
    noise, delay, seed, margin, estimator
        The sensing, the margin and the ground estimate's regression the landing ran with
        (:func:`mpc_landing`).
    samples : int
        Samples taken while the foot yielded.
    pieces : list of (float, LandingResult)
        The plant's simulations and their start times (the last one runs to rest).
    compiled : CompiledRecord or None
        ``controller="bangbang"``: the compiled controller's samples (inputs, status and
        memory), to time them again as a robot's control loop runs them
        (:func:`softlanding.control.loop_replay.replay`).
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
    step_cpu_ms: list[float] = field(default_factory=list)
    estimates: list[GroundEstimate] = field(default_factory=list)
    replans: int = 0
    fallbacks: int = 0
    structure_changes: int = 0
    step_paths: list[str] = field(default_factory=list)
    samples: int = 0
    setup_ms: float = 0.0
    prepare_time_s: float = 0.0
    controller: str = "replan"
    sample_limit_hit: bool = False
    uncovered: int = 0
    deferred: int = 0
    creep_samples: int = 0
    step_work: list[int] = field(default_factory=list)
    noise: float = 0.0
    delay: int = 0
    seed: int = 0
    margin: float = 0.0
    estimator: str = "measured"
    pieces: list[tuple[float, LandingResult]] = field(default_factory=list)
    compiled: CompiledRecord | None = field(default=None, repr=False, compare=False)

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

    def failure(self) -> str | None:
        """Why the landing is not :attr:`feasible` (one line), or None."""
        why = []
        if self.stroke_min < -1e-9 * max(1.0, self.robot.s):
            why.append(f"the stroke went below 0 ({self.stroke_min:.6g})")
        if self.stroke_max > self.robot.s * (1 + 1e-9) + 1e-9:
            why.append(f"the stroke went beyond s = {self.robot.s:g} ({self.stroke_max:.6g})")
        if not self.result.rest_proven:
            why.append(f"rest is not proven ({self.result.status})")
        if self.sample_limit_hit:
            why.append(f"the foot still moved after max_samples = {self.samples} samples")
        return "; ".join(why) or None

    def step_stats(self) -> dict[str, float | None]:
        """Median, 99th percentile and maximum of the step times (wall and CPU, ms); None
        when no sample computed anything (the foot stopped within the first)."""
        out: dict[str, float | None] = {}
        for key, vals in (("time", self.step_times_ms), ("cpu", self.step_cpu_ms)):
            a = np.asarray(vals, float)
            for stat, f in (("median", np.median), ("p99", lambda v: np.percentile(v, 99)),
                            ("max", np.max)):
                out[f"step_{key}_{stat}_ms"] = float(f(a)) if a.size else None
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        return json_safe({
            "depth": self.depth, "feasible": self.feasible, "stroke_held": self.stroke_held,
            "rest_proven": self.result.rest_proven, "stroke_min": self.stroke_min,
            "stroke_max": self.stroke_max, "u_peak": self.u_peak, "period": self.period,
            "samples": self.samples, "replans": self.replans, "fallbacks": self.fallbacks,
            "structure_changes": self.structure_changes, "controller": self.controller,
            "uncovered": self.uncovered, "deferred": self.deferred,
            "creep_samples": self.creep_samples,
            "step_work_max": max(self.step_work, default=None), "noise": self.noise,
            "delay": self.delay,
            "seed": self.seed, "margin": self.margin, "estimator": self.estimator,
            "steps": len(self.step_times_ms), **self.step_stats(), "setup_ms": self.setup_ms,
            "prepare_time_s": self.prepare_time_s,
            "period_rig_ms": 1e3 * self.period * paper_rig_units().time,
            "sample_limit_hit": self.sample_limit_hit, "failure": self.failure(),
            "estimate": None if not self.estimates else self.estimates[-1].__dict__,
            "ground": self.ground.to_dict(), "model_ground": self.model.to_dict(),
            "robot": self.robot.to_dict(), "impact": self.impact.to_dict()})


def mpc_landing(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                ground: Ground = LINEAR_GROUND, *, model: Ground = LINEAR_GROUND,
                period: float = DEFAULT_PERIOD, estimate: bool = True,
                max_samples: int = 100_000, reuse: bool = False,
                controller: str = "replan", noise: float = 0.0, delay: int = 0,
                seed: int = 0, margin: float = 0.0,
                estimator: str = "filtered") -> MPCLanding:
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
        The sample period, in [:data:`MIN_PERIOD`, :data:`MAX_PERIOD`].
    estimate : bool
        Update the ground estimate from the measurements (else keep ``model``).
    max_samples : int
        A bound on the samples while the foot yields.
    reuse : bool
        Start the re-solves from the NLPs earlier landings in this process solved (faster
        steps: fewer builds within a sample) instead of none. The Newton re-solve starts
        from the last solution of each cached structure, so the landing then depends on
        what ran before it: in the unknown-ground study, 57 of 60 within 2 % and a 99th
        percentile step of 14 ms with reuse, 59 of 60 and 152 ms without.
    controller : str
        ``"replan"``: the re-planning MPC above. ``"bangbang"``: the compiled real-time
        Newton on the push-then-pull plan's switching times
        (:mod:`softlanding.control.bangbang`; no NLP, no allocation in Python per sample),
        and the creep law (:mod:`softlanding.control.creep`) where the optimum creeps to
        the static depth; where neither covers the state (Newton fails, an arrest that no
        longer holds), the sample and the rest of the landing fall back to the re-planning
        MPC (counted in ``uncovered``).
    noise : float
        Standard deviation of the Gaussian noise on every measured foot position, velocity,
        acceleration and force (paper units; 0: exact measurements). The estimator is told
        this level, so its standard deviations are the estimate's uncertainty.
    delay : int
        Samples between a measurement and the actuation of the control computed from it
        (0: at once); until then the last control computed goes on. A re-plan (the
        re-planning MPC's, or the compiled controller's fallback) starts from the state
        where it will act: the measured one carried over the delay under the commands in
        flight, on the believed ground.
    seed : int
        The noise's random seed.
    margin : float
        ``controller="bangbang"``: plan for ``K - margin sigma_K``, ``c_d - margin
        sigma_c`` (the estimate less ``margin`` of its standard deviations) while the
        estimate is uncertain.
    estimator : str
        What the ground estimate regresses (:data:`ESTIMATORS`) from noisy measurements.
        ``"measured"``: the measured foot position, velocity, acceleration and force, as
        they come. ``"filtered"`` (default): the force the controller applied (it
        commanded it, the plant applies it exactly, saturated at ``u_max``) instead of its
        noisy measurement, and the foot's
        position and velocity filtered with its measured acceleration
        (:mod:`softlanding.control.foot_filter`); the plans start from the filtered state
        too. Each sample weighs by the filtered state's error in its force
        (:func:`~softlanding.control.estimation.filtered_weight`). With exact measurements
        both are the same (and the landing records ``"measured"``). In the controller study
        (noise 1e-3, delay 1, margin 2) the filtered estimate lands all 60 cases within 3 %
        of the clairvoyant depth (largest 1.021), the measured one 59 (largest 1.10).

    Raises
    ------
    ParameterError
        Bad arguments.
    ocp.SolveError
        The first plan cannot be made.
    """
    t_start = time.perf_counter()
    impact = Impact.of(impact)
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    check_model(model)
    if controller not in CONTROLLERS:
        raise ParameterError("controller", f"must be one of {', '.join(CONTROLLERS)}, got "
                                           f"{controller!r}")
    period = check_period("period", period)
    margin = check("margin", margin, (lambda v: v >= 0, "must be >= 0"))
    if estimator not in ESTIMATORS:
        raise ParameterError("estimator", f"must be one of {', '.join(ESTIMATORS)}, got "
                                          f"{estimator!r}")
    max_samples = check_count("max_samples", max_samples, 1, 10**7)
    first = solve_landing(impact, robot, model, replay=False)
    plan: Any = first.refined if first.refined is not None else first.transcribed
    problem = state_landing_problem()
    if not reuse:
        # the re-solves start from the NLPs cached for this problem: a landing starts from
        # none, so that it does not depend on what ran before it (its setup builds them)
        clear_cache(problem)
    plant = SteppingPlant(robot, impact, ground)
    if _plan_time(plan) / period > max_samples:
        raise ParameterError("period", f"{period:g} takes about "
                                       f"{_plan_time(plan) / period:.3g} samples over the "
                                       f"planned landing, more than max_samples = {max_samples}")
    sensor = Sensor(noise, delay, seed)
    # (exact measurements need no filter: its estimate would be the measurement)
    filtered = estimator == "filtered" and sensor.noise > 0
    estimator = "filtered" if filtered else "measured"  # (what runs: the same when exact)
    filt = new_filter(plant.x) if filtered else None
    beta = bb.force_coefficients(robot.r_m)[0]
    est = GroundEstimator(robot, drag=True, prior=ground_numbers(model),
                          noise_std=bb.ground_force_noise(robot.r_m, sensor.noise, True)
                          if filtered else max(sensor.noise, 1e-6))
    fast = _FastState.start(plan, robot, model, period, sensor, margin, filtered) \
        if controller == "bangbang" else None
    # the compiled samples' inputs, for a replay as a control loop (:mod:`.loop_replay`)
    record = CompiledRecord(fast.P.copy(), fast.M.copy(), None if filt is None else filt.copy()) \
        if fast is not None and fast.active else None
    # the filtered regression's per-sample weights: one force's variance from the
    # acceleration's noise, and the filtered state's error the estimator's noise allows for
    # (both in units of the sensor's noise variance)
    force_var, allowance = 1.0 / bb.force_coefficients(robot.r_m)[1] ** 2, bb.FILTERED_REGRESSOR

    def weight_of(x: np.ndarray, a_f: float, u: float) -> float:
        """The fallback estimator's weight of a sample (1 unless filtered)."""
        if filt is None:
            return 1.0
        e = est.estimate
        return filtered_weight(x, est.ground_force(a_f, u), (e.stiffness, e.c_d),
                               covariance(filt), force_var, allowance)

    t0 = time.perf_counter()
    if fast is None or not fast.active:
        _prepare(problem, plan, robot, model, plant.x)  # the builds, before the landing starts
    setup_ms = 1e3 * (time.perf_counter() - t0)
    prepare_s = time.perf_counter() - t_start
    out_times: list[float] = []
    cpu_times: list[float] = []
    step_work: list[int] = []
    estimates: list[GroundEstimate] = []
    paths: list[str] = []
    fallbacks, replans, elapsed, samples, uncovered = 0, 0, 0.0, 0, 0
    believed = planned_for = model
    # the commands issued, each (its time origin, its schedule from there, the planned stop
    # of the foot from there); the actuator applies the one issued `delay` samples ago
    issued: list[tuple[float, Any, float]] = [
        (0.0, fast.schedule() if fast is not None and fast.active else _schedule(plan, robot),
         fast.stop_time() if fast is not None and fast.active else _plan_time(plan))]
    # the foot has stopped when it is static, or creeps by rounding at the crater's exact
    # capacity (the optimal arrest uses all of it)
    stop = 1e-9 * max(1.0, abs(impact.v0))
    measured = sensor.measure(plant.x)[0]
    x_act: np.ndarray | None  # where a re-plan acts (None: the foot stops before)
    while plant.x[3] < -stop and samples < max_samples:
        origin, command, planned_stop = issued[max(0, len(issued) - 1 - sensor.delay)]
        schedule = _shifted(command, plant.t - origin)
        # a sample that would pass the planned stop of the foot ends there: the arrest is
        # then computed from the measured state, not from the plan's prediction of it
        h = min(period, origin + planned_stop - plant.t)
        h = h if h > 1e-9 * period else period
        x_before = measured
        plant.step(schedule, h)  # the schedule's time starts at the step
        samples += 1
        if plant.x[3] >= -stop:  # the foot stopped within the sample: its arrest follows
            break
        u_end = _force_at_end(schedule, plant.x, h)  # the force the sample ended under
        measured, a_f, u_meas = sensor.measure(plant.x, plant.foot_acceleration(u_end), u_end)
        if filt is not None:  # the force as applied and its integrals over the sample
            # (the actuator's: inputs of the estimate, as the measurements are)
            u_meas, g = u_end, a_f - beta * u_end  # (g: the foot's continuous acceleration)
            U1, U2 = _force_integrals(schedule, h)
        else:
            # the foot still yields (the loop's condition, a contact sensor's): a noisy v_f
            # that reads otherwise is clipped (the plans start from a yielding foot)
            measured[3] = min(measured[3], -stop)
        compiled = fast is not None and fast.active
        x_in = measured.copy() if compiled and record is not None else None
        # the controller's sample from here: its estimate (the foot filter's step included)
        # and its control update (the CPU clock, a system call of ~1 us, read outside the
        # wall clock's interval)
        c0, t0 = time.process_time(), time.perf_counter()
        if not compiled:
            if filt is not None:  # the foot's filtered state, clipped as above
                filter_step(filt, measured, g, U1, U2, h, beta, sensor.noise)
                measured[3] = min(measured[3], -stop)
        else:
            assert fast is not None
            # (the filter's first states are provisional: no fit from them)
            fit = estimate and (filt is None or samples > PROVISIONAL)
            if filt is None:
                status = fast.step(measured, a_f, u_meas, h, fit)
            else:  # the filter's step, the sample's weight and the step in one call
                status = fast.filtered_sample(measured, filt, g, U1, U2, h, beta,
                                              sensor.noise, a_f, u_meas, fit, stop)
            out_times.append(1e3 * (time.perf_counter() - t0))
            cpu_times.append(1e3 * (time.process_time() - c0))
            step_work.append(int(fast.M[bb.M_WORK]))
            if record is not None and x_in is not None:
                record.samples.append(CompiledSample(
                    x_in, float(a_f), float(u_meas), float(h), bool(fit),
                    None if filt is None else (float(g), float(U1), float(U2), float(beta),
                                               float(sensor.noise), float(stop)),
                    status, fast.M.copy(), None if filt is None else filt.copy(),
                    fast.recovering))
            if estimate:
                estimates.append(fast.estimate())
            # (an arrest short of the crater's hold while pulling: the pull is still the
            # fastest stop of the foot, the arrest then digs a little; no plan of this
            # structure does better, and measurement noise makes it short by rounding)
            pulling = fast.M[bb.M_PHASE] == bb.PULL
            if status in (bb.OK, bb.CONVERGING, bb.HOLDS, bb.DEFERRED, bb.CREEP_LAW) or (
                    status == bb.ARREST_FAILS and pulling):
                paths.append("bangbang" if status == bb.OK else
                             f"bangbang ({bb.STATUS_NAMES[status]})")
                issued.append((plant.t, fast.schedule(), fast.stop_time()))
                continue
            # not covered: this sample and the rest of the landing re-plan as the MPC does
            uncovered += 1
            fast.hand_over(est)
            believed = planned_for = est.estimate.ground() if est.samples >= 2 else model
            c0, t0 = time.process_time(), time.perf_counter()
            try:
                x_act, lead = _at_actuation(robot, impact, issued, measured, believed,
                                            sensor.delay, period, plant.t, stop)
                plan = solve_from_state(robot, believed, x_act)
                paths.append(f"fallback ({bb.STATUS_NAMES[status]})")
                issued.append((plant.t + lead, _schedule(plan, robot), _plan_time(plan)))
                elapsed = -lead
                replans += 1
            except SolveError:
                raise_if_interrupted()
                fallbacks += 1
                paths.append(f"kept ({bb.STATUS_NAMES[status]})")
                issued.append((plant.t, _shifted(command, plant.t - origin),
                               origin + planned_stop - plant.t))
                plan, elapsed = None, 0.0
            out_times[-1] += 1e3 * (time.perf_counter() - t0)
            cpu_times[-1] += 1e3 * (time.process_time() - c0)
            continue
        if plan is None:  # a fallback that found no plan: the estimate goes on, and the
            # re-plan is tried again from this sample's state (else the last command goes on)
            if estimate and measured[3] < 0 and (filt is None or samples > PROVISIONAL):
                e = est.update(measured, a_f, u_meas, weight_of(measured, a_f, u_meas))
                estimates.append(e)
                if e.samples >= 2:
                    believed = e.ground()
            try:
                x_act, lead = _at_actuation(robot, impact, issued, measured, believed,
                                            sensor.delay, period, plant.t, stop)
                plan = solve_from_state(robot, believed, x_act)
                elapsed, planned_for = -lead, believed
                replans += 1
                paths.append("fallback (retried)")
                issued.append((plant.t + lead, _schedule(plan, robot), _plan_time(plan)))
            except SolveError:
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                fallbacks += 1
                paths.append("kept")
                issued.append(issued[-1])
            out_times.append(1e3 * (time.perf_counter() - t0))
            cpu_times.append(1e3 * (time.process_time() - c0))
            continue
        if estimate and measured[3] < 0 and (filt is None or samples > PROVISIONAL):
            # (a noisy v_f may read >= 0: nothing to fit)
            e = est.update(measured, a_f, u_meas, weight_of(measured, a_f, u_meas))
            estimates.append(e)
            if e.samples >= 2:
                believed = e.ground()
        # (not at the plan's foot stop: a foot still creeping there needs a new plan, the
        # rest of this one assumes it stopped)
        if elapsed + h < _plan_time(plan) - 1e-12 * period and _plan_holds(
                robot, impact, schedule, h, x_before, measured, planned_for, believed):
            # the plan's own ground explains the sample and is still believed: by the
            # principle of optimality the plan's rest is the optimum from here, no re-solve
            paths.append("plan holds")
            elapsed += h
            out_times.append(1e3 * (time.perf_counter() - t0))
            cpu_times.append(1e3 * (time.process_time() - c0))
            issued.append(issued[-1])
            continue
        try:
            x_act, lead = _at_actuation(robot, impact, issued, measured, believed,
                                        sensor.delay, period, plant.t, stop)
        except SolveError:  # the foot stops before a new plan could act: the last goes on
            x_act, lead = None, 0.0
        try:
            if x_act is None:
                raise SolveError("stops", message="the foot stops within the delay")
            plan, path = _replan(problem, plan, elapsed + h + lead, robot, believed, x_act,
                                 planned_for)
            elapsed, planned_for = -lead, believed
        except SolveError:  # no structure near the last one fits: transcribe and refine anew
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            try:
                if x_act is None:
                    raise SolveError("stops", message="the foot stops within the delay")
                plan = _transcribed_plan(plan, elapsed + h + lead, robot, believed, x_act)
                elapsed, path, planned_for = -lead, "transcription", believed
                replans += 1
            except SolveError:  # keep the last plan for this sample
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                fallbacks += 1
                elapsed, path = elapsed + h, "kept"
        paths.append(path)
        out_times.append(1e3 * (time.perf_counter() - t0))
        cpu_times.append(1e3 * (time.process_time() - c0))
        issued.append((plant.t - elapsed, _schedule(plan, robot), _plan_time(plan)))
    if plant.x[3] >= -stop:
        final = plant.finish(sensor.arrest(sensor.measure(plant.x)[0], robot.r_m, robot.s))
    else:
        origin, command, _ = issued[-1]
        final = plant.finish(_shifted(command, plant.t - origin))
    # within each sample (a sample's simulation also ranges over the future under its
    # control), then from the last sample on (the final simulation)
    stroke = ([lo for lo, _ in plant.stroke_ranges] + [final.stroke_min],
              [hi for _, hi in plant.stroke_ranges] + [final.stroke_max])
    return MPCLanding(robot=robot, impact=impact, ground=ground, model=model, period=period,
                      result=final, depth=final.depth, stroke_min=min(stroke[0]),
                      stroke_max=max(stroke[1]),
                      u_peak=max(r.u_peak for _, r in plant.history),
                      step_times_ms=out_times, step_cpu_ms=cpu_times, estimates=estimates,
                      replans=replans,
                      fallbacks=fallbacks, samples=samples, setup_ms=setup_ms,
                      structure_changes=paths.count("structure"), step_paths=paths,
                      pieces=list(plant.history), prepare_time_s=prepare_s,
                      sample_limit_hit=samples >= max_samples and plant.x[3] < -stop,
                      controller=controller, uncovered=uncovered,
                      deferred=paths.count("bangbang (deferred)"),
                      creep_samples=paths.count("bangbang (creep law)"), step_work=step_work,
                      noise=sensor.noise,
                      delay=sensor.delay, seed=seed, margin=margin, estimator=estimator,
                      compiled=record)


class Sensor:
    """What the controller measures: the state, the foot's acceleration and the force, with
    Gaussian noise of one standard deviation ``noise`` on the foot's position, velocity,
    acceleration and the force; and the delay (samples) before its control acts.

    Parameters
    ----------
    noise : float
        Standard deviation (>= 0).
    delay : int
        Samples (>= 0).
    seed : int
        Random seed.
    """

    def __init__(self, noise: float = 0.0, delay: int = 0, seed: int = 0) -> None:
        self.noise = check("noise", noise, (lambda v: v >= 0, "must be >= 0"))
        if isinstance(delay, bool) or not isinstance(delay, int | np.integer):
            raise ParameterError("delay", f"must be a whole number of samples, got {delay!r}")
        self.delay = check_count("delay", int(delay), 0, 1000)
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ParameterError("seed", f"must be a whole number >= 0, got {seed!r}")
        self.rng = np.random.default_rng(int(seed))

    def measure(self, x: np.ndarray, a_f: float = 0.0,
                u: float = 0.0) -> tuple[np.ndarray, float, float]:
        """The measured state, foot acceleration and force.

        Parameters
        ----------
        x : array of 4
            The true state.
        a_f, u : float
            The true foot acceleration and force.
        """
        if self.noise == 0.0:
            return np.array(x, float), float(a_f), float(u)
        e = self.rng.normal(0.0, self.noise, 4)
        m = np.array(x, float)
        m[2] += e[0]
        m[3] += e[1]
        return m, float(a_f + e[2]), float(u + e[3])


    def arrest(self, x: np.ndarray, r_m: float, stroke_max: float = math.inf
               ) -> ForceSchedule | FeedbackSchedule:
        """The body's arrest from the measured state of a stopped foot: exact measurements,
        the constant force that stops it in the stroke left, then its weight
        (:func:`~softlanding.optimal.landing.arrest_schedule`). Noisy ones: the stroke left
        less a reserve of ``ARREST_RESERVE`` standard deviations of the foot's position (a
        measured stroke may be long), then the weight with a damped hold of the stroke
        where the body stopped (the open-loop weight alone would let a velocity the noise
        left drift the body forever). A body that no longer descends (the end of a creep)
        coasts up at no force to its top, if that is within ``stroke_max``, and gets that
        damped hold there, with exact measurements too. A body so slow that braking over
        the whole stroke would outlast :data:`ARREST_TIME` brakes within it.

        Parameters
        ----------
        x : ndarray
            The measured state ``[x_b, v_b, x_f, v_f]`` (the foot stopped).
        r_m : float
            The robot's mass ratio.
        stroke_max : float
            The stroke's limit (a noisy arrest lets a rising body coast up to its top, at
            no force, where that is within it).

        Returns
        -------
        ForceSchedule or FeedbackSchedule
            The arrest's force from the sample on.
        """
        stroke = float(x[0] - x[2])
        # a body so slow that braking over the whole stroke outlasts ARREST_TIME brakes over
        # what it covers in that time (its force above the weight m_b |v_b| / ARREST_TIME:
        # 3e-4 of it at v_b = -0.02)
        brake = 0.5 * abs(float(x[1])) * ARREST_TIME
        if self.noise == 0.0 and x[1] < 0:
            x_e = np.array(x, float)
            x_e[0] = min(x_e[0], x_e[2] + brake)
            return arrest_schedule(x_e, r_m)
        reserve = min(ARREST_RESERVE * self.noise, 0.5 * stroke)
        x_r = np.array(x, float)
        x_r[0] -= reserve  # the arrest sees the stroke less the reserve
        x_r[0] = min(x_r[0], x_r[2] + brake) if x[1] < 0 else x_r[0]
        tail = arrest_schedule(x_r, r_m)
        assert isinstance(tail, ForceSchedule)
        w = r_m / (1 + r_m)
        # where the arrest stops the body (the reserve left), or where it is
        end = stroke - (x_r[0] - x_r[2]) if x[1] < 0 and stroke - reserve > 0 else stroke
        times, forces = tail.times, tail.values[:-1]
        if x[1] > 0:
            # a body still rising (a re-planned creep's pull may leave it so): no force until
            # its weight alone stops it, then the hold at that stroke (held where it is, the
            # damped hold would brake it by pushing the foot into ground at its capacity)
            a = float(robot_rhs(np.asarray(x, float), 0.0, 0.0, r_m)[VB])
            if a < 0 and stroke - 0.5 * x[1] ** 2 / a < stroke_max:
                times, forces, end = (-x[1] / a,), (0.0,), stroke - 0.5 * x[1] ** 2 / a
        hold = (-HOLD_GAINS[0], -HOLD_GAINS[1], HOLD_GAINS[0], HOLD_GAINS[1],
                w + HOLD_GAINS[0] * end)
        rows = [(0.0, 0.0, 0.0, 0.0, v) for v in forces] + [hold]
        return FeedbackSchedule(times, tuple(rows))


#: Standard deviations of the foot's measured position kept as a stroke reserve by a noisy
#: arrest.
ARREST_RESERVE = 3.0
#: The longest braking of the arrest (paper time units, 26 s on the paper's rig): a tenth of
#: the simulation's horizon, within which its rest is proven. A body slower than
#: ``2 stroke / ARREST_TIME`` (0.04 over the paper's whole stroke) brakes over a part of it.
ARREST_TIME = 1000.0
#: ``k_p, k_d`` of the damped hold of the stroke after a noisy arrest (per unit of the
#: paper's force; critically damped for the body's mass ``r_m/(1+r_m)`` about 5/6).
HOLD_GAINS = (1.0, 2.0)


class _FastState:
    """The compiled controller's numbers, memory and work arrays, and its schedules."""

    def __init__(self, P: np.ndarray, M: np.ndarray, robot: Robot, active: bool) -> None:
        self.P, self.M, self.active = P, M, active
        self.u_max, self.r_m = force_limit(robot), robot.r_m
        self.ws = bb.workspace()
        self.recovering = 0  # samples the full solve has gone on over so far

    @classmethod
    def start(cls, plan: Any, robot: Robot, model: Ground, period: float,
              sensor: Sensor, margin: float = 0.0, filtered: bool = False) -> _FastState:
        """From the first plan (covered if it is push then pull, or pull)."""
        kinds = tuple(m[0].kind for m in plan.modes) if isinstance(plan, RefinedSwitching) \
            and all(len(m) == 1 for m in plan.modes) else ()
        u_max = force_limit(robot)
        k, c_d = ground_numbers(model)
        noise = bb.ground_force_noise(robot.r_m, sensor.noise, filtered)
        P = bb.robot_numbers(robot.r_m, robot.s, u_max, k, c_d, noise, margin, period,
                             creep=True)
        covered = kinds in (("max", "min"), ("min",))
        d = np.asarray(plan.durations, float) if covered else np.array([0.0, 1.0])
        t1, t2 = (d[0], d[1]) if kinds == ("max", "min") else (0.0, float(d[-1]))
        M = bb.new_memory(t1, t2, (k, c_d), (1.0, 1.0), noise)
        out = cls(P, M, robot, covered)
        if covered:  # the first plan's state at the foot's stop (its schedule's tail)
            M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT] = np.asarray(plan.xT, float)[:3]
        # compile (or load numba's cache) before impact: a sample must not pay for it
        probe = M.copy()
        bb.control_step(P.copy(), probe, np.array([10.0, -1.0, -0.1, -1.0]), 0.0, 0.0,
                        1e-3 * period, False, *out.ws)
        if filtered:  # (and the filtered sample, with the bounded full solve it may need:
            # loading that mid-landing took 17 ms)
            bb.solve_plan(P.copy(), M.copy(), np.array([10.0, -1.0, -0.1, -1.0]), *out.ws,
                          float(P[bb.P_WORK]))
            filtered_sample(P.copy(), M.copy(), new_filter(np.array([10.0, -1.0, 0.0, -1.0])),
                            np.array([10.0, -1.0, -0.1, -1.0]), 0.0, 0.0, 0.0,
                            1e-3 * period, 0.0, 0.0, 0.0, 0.0, False, 0.0, 0, *out.ws)
        return out

    def step(self, x: np.ndarray, a_f: float, u: float, h: float, estimate: bool) -> int:
        """One compiled sample with the measured estimate; the status."""
        return int(bb.control_step(self.P, self.M, x, a_f, u, h, estimate, *self.ws))

    def filtered_sample(self, x: np.ndarray, F: np.ndarray, g: float, U1: float, U2: float,
                        h: float, beta: float, noise: float, a_f: float, u: float,
                        estimate: bool, stop: float) -> int:
        """One compiled sample with the filtered estimate, the foot filter's step included
        (:func:`~softlanding.control.recovery.filtered_sample`: ``x`` filtered in place, the
        sample weighed in the estimate, a push whose real-time iteration ran out of samples
        solved in full over at most :data:`~softlanding.control.recovery.RECOVERY_SAMPLES`
        samples); the status."""
        st, self.recovering = filtered_sample(self.P, self.M, F, x, g, U1, U2, h, beta,
                                              noise, a_f, u, estimate, stop, self.recovering,
                                              *self.ws)
        return int(st)

    def schedule(self) -> ForceSchedule | FeedbackSchedule:
        """The plan's force from now: push until the switch, pull until the foot's stop,
        then the arrest of the body and its weight (from the plan's state at the stop); or,
        creeping, the creep law's force of this sample (held: the next sample computes the
        next)."""
        M = self.M
        if M[bb.M_PHASE] == bb.CREEPING:
            return ForceSchedule((), (float(M[bb.M_UCREEP]),))
        t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
        t2 = float(M[bb.M_TAU2])
        x_t = np.array([M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT], 0.0])
        tail = arrest_schedule(x_t, self.r_m)
        assert isinstance(tail, ForceSchedule)  # (a constant arrest force, then the weight)
        times = ((t1,) if t1 > 0 else ()) + (t1 + t2,) + tuple(t1 + t2 + t for t in tail.times)
        values = ((self.u_max,) if t1 > 0 else ()) + (-self.u_max,) + tuple(tail.values)
        return ForceSchedule(times, values)

    def stop_time(self) -> float:
        """When the plan has the foot stop (from now; creeping: not planned, ``inf``)."""
        if self.M[bb.M_PHASE] == bb.CREEPING:
            return math.inf
        t1 = float(self.M[bb.M_TAU1]) if self.M[bb.M_PHASE] == bb.PUSH else 0.0
        return t1 + float(self.M[bb.M_TAU2])

    def estimate(self) -> GroundEstimate:
        """The compiled estimator's fit and standard deviations."""
        M, noise = self.M, self.P[bb.P_NOISE]
        return GroundEstimate(float(M[bb.M_TH0]), float(M[bb.M_TH1]),
                              float(np.sqrt(max(M[bb.M_P00], 0.0)) * noise),
                              float(np.sqrt(max(M[bb.M_P11], 0.0)) * noise),
                              int(M[bb.M_SAMPLES]))

    def hand_over(self, est: GroundEstimator) -> None:
        """Give the estimate to the re-planning MPC's estimator, and stop."""
        M = self.M
        est.theta = np.array([M[bb.M_TH0], M[bb.M_TH1]])
        est.P = np.array([[M[bb.M_P00], M[bb.M_P01]], [M[bb.M_P01], M[bb.M_P11]]])
        est.noise = float(self.P[bb.P_NOISE])
        est.samples = int(M[bb.M_SAMPLES])
        self.active = False


def check_model(model: Any, name: str = "model") -> Ground:
    """The controller's model ground: linear or drag (``f = K d + c_d v^2``, what it plans
    for and estimates).

    Parameters
    ----------
    model : LinearGround or DragGround
        What the caller gave.
    name : str
        The argument's name in the message.

    Raises
    ------
    ParameterError
        Another ground model, or not a ground.
    """
    if not isinstance(model, LinearGround | DragGround):
        what = getattr(model, "name", type(model).__name__)
        raise ParameterError(name, f"the controller plans for a linear or drag ground "
                                   f"(f = K d + c_d v^2), not the {what} ground")
    return model


def check_period(name: str, period: Any) -> float:
    """A sample period within [:data:`MIN_PERIOD`, :data:`MAX_PERIOD`].

    Parameters
    ----------
    name : str
        The argument's name in the message (``--period`` on the command line).
    period : float
        What the caller gave.

    Raises
    ------
    ParameterError
        Not finite, or out of the range.
    """
    return check(name, period, (lambda v: (v >= MIN_PERIOD) & (v <= MAX_PERIOD),
                                f"must be within [{MIN_PERIOD:g}, {MAX_PERIOD:g}] (the "
                                f"shortest bounds the samples per landing to about 1e4)"))


PLAN_HOLDS_TOL = 1e-8
"""Relative agreement of the measured state with the plan's prediction, and of the estimate
with the plan's ground, under which a sample keeps the plan (no re-solve)."""


def _plan_holds(robot: Robot, impact: Impact, schedule: Any, h: float, x_before: np.ndarray,
                x: np.ndarray, planned_for: Ground, believed: Ground) -> bool:
    """Whether the sample went as the plan predicted, on the ground it was planned for, and
    that ground is still what the controller believes."""
    k0, c0 = ground_numbers(planned_for)
    k1, c1 = ground_numbers(believed)
    if abs(k1 - k0) > PLAN_HOLDS_TOL * k0 or abs(c1 - c0) > PLAN_HOLDS_TOL * max(1.0, c0):
        return False
    try:
        predicted = simulate(robot, impact, schedule, planned_for, x0=x_before, t_max=h,
                             energy=False).trajectory(t_end=h, n=2).x[-1]
    except RestNotProvenError:  # (the plan's own sample ends off the stroke: it does not hold)
        return False
    scale = max(1.0, float(np.max(np.abs(x))))
    return bool(np.max(np.abs(predicted - x)) <= PLAN_HOLDS_TOL * scale)


def _at_actuation(robot: Robot, impact: Impact, issued: list, x: np.ndarray,
                  believed: Ground, delay: int, period: float, t: float,
                  stop: float) -> tuple[np.ndarray, float]:
    """Where a control computed now starts to act, and how long from now: the measured
    state ``x`` carried over the ``delay`` samples of the commands already issued (each
    ``(origin, schedule, stop)``, the last ``delay`` of ``issued`` in flight) on the
    believed ground; ``(x, 0)`` without delay.

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
            x = simulate(robot, impact, _shifted(command, t + j * period - origin), believed,
                         x0=x, t_max=period, energy=False).trajectory(t_end=period,
                                                                      n=2).x[-1]
        except RestNotProvenError as err:  # (the foot stopped and rests within the sample)
            raise SolveError("stops", message="the foot stops within the delay") from err
        if not x[3] < -stop:
            raise SolveError("stops", message="the foot stops within the delay")
    return x, delay * period


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


def _force_integrals(schedule: Any, h: float) -> tuple[float, float]:
    """``int_0^h u dt`` and ``int_0^h (h - t) u dt`` of a force schedule over a sample
    (a feedback schedule, the arrest's, which no yielding foot runs: its force at the end)."""
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
    is not bang-bang, e.g. a singular creep to the depth that holds the robot's weight), and
    the body's arrest, or its coast if it still rises (:func:`plan_schedule`)."""
    return plan_schedule(plan, robot)


def _replan(problem: OptimalControlProblem, plan: Any, applied: float, robot: Robot,
            believed: Ground, x: np.ndarray,
            planned_for: Ground | None = None) -> tuple[RefinedSwitching, str]:
    """The last plan's structure re-solved from ``x`` for the believed ground, and how.

    Newton on the plan's structure (less the arcs already applied) first; when the estimate
    moved far from the plan's ground, Newton along a path of grounds from that one to the
    believed one (a first drag estimate moves ``c_d`` from 0 to 1 at once); then Newton on
    the structure's neighbours (an arc dropped, e.g. one that collapsed, or one added at the
    end), each about a millisecond; Ipopt on the plan's structure last.
    """
    if isinstance(plan, Solution):
        raise SolveError("transcribed", message="a transcribed plan has no structure to re-solve")
    modes, durs = _remaining(plan, applied)
    params = state_parameters(robot, believed, x)
    try:
        return _checked(refine_structure(problem, modes, durs, x, params, ipopt=False)), "newton"
    except SolveError as err:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        collapsed = err.iterate if err.status == "arc_collapsed" else None
    if planned_for is not None and planned_for != believed:
        try:
            return _continued(problem, modes, durs, x, params,
                              state_parameters(robot, planned_for, x)), "continuation"
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
    for m, d in _neighbours(modes, durs, collapsed):
        try:
            return _checked(refine_structure(problem, m, d, x, params, ipopt=False)), "structure"
        except (SolveError, ValueError):  # (ValueError: a mode outside the control set)
            raise_if_interrupted()
    return _checked(refine_structure(problem, modes, durs, x, params, fast=False)), "ipopt"


CONTINUATION_STEPS = 4
"""Grounds on the path from the plan's ground to the believed one (Newton at each)."""


def _continued(problem: OptimalControlProblem, modes: tuple, durs: np.ndarray, x: np.ndarray,
               params: dict[str, float], start: dict[str, float]) -> RefinedSwitching:
    """Newton along ``K`` and ``c_d`` from ``start``'s values to ``params``', each re-solve
    starting from the last one's durations."""
    r = None
    for lam in np.linspace(0.0, 1.0, CONTINUATION_STEPS + 1)[1:]:
        p = dict(params)
        for name in ("stiffness", "c_d"):
            p[name] = start[name] + lam * (params[name] - start[name])
        r = _checked(refine_structure(problem, modes, durs, x, p, ipopt=False))
        durs = np.asarray(r.durations, float)
    assert r is not None
    return r


def _remaining(plan: RefinedSwitching, applied: float) -> tuple[tuple, np.ndarray]:
    """The plan's modes and durations left after ``applied`` (finished arcs dropped)."""
    durs = np.asarray(plan.durations, float).copy()
    first = 0
    while applied > 0 and first < len(durs):
        if durs[first] > applied:
            durs[first] -= applied
            break
        applied -= durs[first]
        first += 1
    if first == len(durs):
        raise SolveError("no_arcs_left", message="the plan has run out")
    return tuple(plan.modes[first:]), durs[first:]


def _neighbours(modes: tuple, durs: np.ndarray,
                collapsed: RefinedSwitching | None) -> list[tuple[tuple, np.ndarray]]:
    """Structures next to ``modes``: without an arc that collapsed (from the re-solve's
    durations), without the first or the last arc, without any other arc, and with a bang
    arc added at the end (short ones first: an arc that appears starts short)."""
    out: list[tuple[tuple, np.ndarray]] = []
    if collapsed is not None:
        tiny = np.flatnonzero(collapsed.durations <= 1e-9 * collapsed.T)
        out += [_without(modes, np.asarray(collapsed.durations, float), int(i)) for i in tiny]
    k = len(modes)
    order = [0, k - 1, *range(1, k - 1)] if k > 1 else []
    out += [_without(modes, durs, i) for i in dict.fromkeys(order)]
    last = modes[-1][0].kind
    if len(modes[-1]) == 1 and last in _FLIP:
        out.append((modes + ((_FLIP[last],),), np.r_[durs[:-1], 0.99 * durs[-1],
                                                      0.01 * durs[-1]]))
    seen: set[tuple] = set()
    unique = []
    for m, d in out:
        if m and m not in seen:
            seen.add(m)
            unique.append((m, d))
    return unique


_FLIP = {"max": Mode("min"), "min": Mode("max")}


def _without(modes: tuple, durs: np.ndarray, i: int) -> tuple[tuple, np.ndarray]:
    """``modes`` without arc ``i``, its time given to its neighbours (one arc if they then
    repeat a mode)."""
    m, d = list(modes), [float(v) for v in durs]
    gone = d.pop(i)
    m.pop(i)
    if 0 < i < len(m) and m[i - 1] == m[i]:
        d[i - 1] += gone + d.pop(i)
        m.pop(i)
    elif 0 < i < len(m):
        d[i - 1] += 0.5 * gone
        d[i] += 0.5 * gone
    elif m:
        d[min(i, len(m) - 1)] += gone
    return tuple(m), np.asarray(d)


def _checked(r: RefinedSwitching) -> RefinedSwitching:
    """A re-plan that keeps its structure (no arc collapsed) and is finite."""
    if not (np.all(np.isfinite(r.durations)) and np.all(np.isfinite(r.xT))):
        raise SolveError("not_finite", message="the re-plan is not finite")
    if min(r.durations) <= 1e-9 * r.T:
        raise SolveError("arc_collapsed", r, message="an arc of the structure collapsed")
    if not affine_laws(r):  # a stroke held under drag: no exact schedule of this plan
        raise SolveError("law_not_affine", message="a boundary arc's law is not affine")
    return r


def _prepare(problem: OptimalControlProblem, plan: Any, robot: Robot, model: Ground,
             x: np.ndarray) -> None:
    """Build, before the landing, what a sample may need: the Newton re-solves of the plan's
    structure and of its suffixes (the structures left as its arcs end, each solved once
    from the plan's state where it starts) and the transcription of the last resort."""
    _warm_transcription()
    if isinstance(plan, Solution):
        return
    starts = plan.junctions()[:, :problem.nx]
    for j in range(len(plan.modes)):
        x_j = x if j == 0 else starts[j]
        params = state_parameters(robot, model, x_j)
        modes, durs = tuple(plan.modes[j:]), np.asarray(plan.durations[j:], float)
        for ipopt in (True, False):  # an Ipopt solve for the active set, then its Newton
            with contextlib.suppress(SolveError, ValueError):
                refine_structure(problem, modes, durs, x_j, params, ipopt=ipopt)


@lru_cache(maxsize=1)
def _warm_transcription() -> None:
    """Build the transcription and its solvers (cold and warm-started) once per process: the
    first solves cost seconds, which no sample can afford."""
    tr = state_transcription()
    x = SteppingPlant(PAPER_ROBOT, Impact(-3.0), LINEAR_GROUND).x  # the paper's impact
    params = state_parameters(PAPER_ROBOT, LINEAR_GROUND, x)
    with contextlib.suppress(SolveError), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a coarse grid's path warning: only builds count
        tr.solve(params, warm_start=tr.solve(params))


def _transcribed_plan(plan: Any, applied: float, robot: Robot, believed: Ground,
                      x: np.ndarray) -> Any:
    """The landing from ``x`` transcribed (from the rest of the last plan) and refined."""
    if isinstance(plan, Solution):
        return solve_from_state(robot, believed, x, warm_start=plan)
    # (a delayed actuation may have run past the plan's end: then no guess from it)
    guess = plan.trajectory(200).after(applied) if applied < 0.99 * plan.T else None
    found = solve_from_state(robot, believed, x, guess=guess)
    return found if isinstance(found, Solution) else _checked(found)


__all__ = ["ARREST_RESERVE", "ARREST_TIME", "CONTROLLERS", "DEFAULT_PERIOD", "ESTIMATORS",
           "HOLD_GAINS", "MAX_PERIOD", "MIN_PERIOD", "MPCLanding", "Sensor",
           "check_model", "check_period", "mpc_landing"]
