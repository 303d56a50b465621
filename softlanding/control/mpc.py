"""Closed-loop control of the landing on a ground the robot does not know: :func:`mpc_landing`.

It composes the loop's objects (:mod:`softlanding.control.loop`): the true ground's stepping
plant (:class:`~softlanding.control.plant.SteppingPlant`), the sensor
(:class:`~softlanding.control.sensor.Sensor`: noise, delay), an estimator
(:mod:`softlanding.control.estimators`: measured or filtered) and a controller, the compiled
real-time controller (:class:`~softlanding.control.compiled.CompiledController`, the
default) or the re-planning MPC (:class:`~softlanding.control.replan.ReplanController`),
and runs it from the impact to rest (:func:`~softlanding.control.loop.run_loop`).
"""

from __future__ import annotations

import time
from functools import lru_cache
from typing import Any

from ocp.structure.switching import clear_cache
from softlanding.control.commands import plan_time
from softlanding.control.compiled import CompiledController
from softlanding.control.estimators import make_estimator
from softlanding.control.loop import LoopRecord, LoopRun, run_loop
from softlanding.control.options import (
    CONTROLLERS,
    DEFAULT_PERIOD,
    ESTIMATORS,
    MAX_NOISE,
    MAX_PERIOD,
    MIN_NOISE,
    MIN_PERIOD,
    check_choice,
    check_period,
)
from softlanding.control.plant import SteppingPlant
from softlanding.control.recovery import (  # noqa: F401 (mpc.RECOVERY_SAMPLES, as before)
    RECOVERY_SAMPLES,
)
from softlanding.control.replan import ReplanController
from softlanding.control.result import MPCLanding
from softlanding.control.sensor import ARREST_RESERVE, ARREST_TIME, HOLD_GAINS, Sensor
from softlanding.control.state_landing import state_landing_problem
from softlanding.errors import ParameterError, check, check_count, expect
from softlanding.model.ground import LINEAR_GROUND, DragGround, Ground, LinearGround
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import solve_landing


def mpc_landing(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                ground: Ground = LINEAR_GROUND, *, model: Ground = LINEAR_GROUND,
                period: float = DEFAULT_PERIOD, estimate: bool = True,
                max_samples: int = 100_000, reuse: bool = False,
                controller: str = "bangbang", noise: float = 0.0, delay: int = 0,
                seed: int = 0, margin: float = 0.0,
                estimator: str = "filtered") -> MPCLanding:
    """Land on ``ground`` under closed-loop control whose first plan assumes ``model``.

    Parameters
    ----------
    impact : Impact or float
        The impact velocity (``v0 <= -MIN_SPEED``).
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
        ``"bangbang"`` (default): the compiled real-time controller
        (:class:`~softlanding.control.compiled.CompiledController`: Newton on the
        push-then-pull plan's switching times, :mod:`softlanding.control.bangbang`, and the
        creep law, :mod:`softlanding.control.creep`, where the optimum creeps to the static
        depth; microseconds a sample, no NLP, no allocation in Python per sample); where
        neither covers the state (Newton fails, a plan that breaks a path limit), the
        compiled fallback acts within the sample (:mod:`softlanding.control.fallback`: the
        plan kept with the margin dropped, the creep law or the safe brake; counted in
        ``uncovered``). ``"replan"``: the re-planning MPC
        (:class:`~softlanding.control.replan.ReplanController`: every sample it must, the
        landing OCP re-solved; milliseconds to seconds a sample, a simulation study's
        baseline).
    noise : float
        Standard deviation of the Gaussian noise on every measured foot position, velocity,
        acceleration and force (paper units; 0: exact measurements, else within
        [:data:`~softlanding.control.options.MIN_NOISE`,
        :data:`~softlanding.control.options.MAX_NOISE`] = [1e-12, 0.1]). The estimator is
        told this level, so its standard deviations are the estimate's uncertainty.
    delay : int
        Samples between a measurement and the actuation of the control computed from it
        (0: at once); until then the last control computed goes on. The re-planning MPC's
        re-plan starts from the state where it will act: the measured one carried over the
        delay under the commands in flight, on the believed ground (the compiled controller
        plans from the measured state).
    seed : int
        The noise's random seed.
    margin : float
        ``controller="bangbang"``: plan for ``K - margin sigma_K``, ``c_d - margin
        sigma_c`` (the estimate less ``margin`` of its standard deviations) while the
        estimate is uncertain: a margin on the ground, not on the stroke (a plan whose
        optimum touches a stroke limit still touches it). Refused with ``"replan"`` and
        with ``estimate=False``.
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
    if impact.v0 > -MIN_SPEED:  # (slower, the loop's foot counts as stopped at the impact)
        raise ParameterError("v0", f"the controller lands impacts of {MIN_SPEED:g} or "
                                   f"faster (v0 <= {-MIN_SPEED:g}), got {impact.v0:g}")
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    check_model(model)
    check_choice("controller", controller, CONTROLLERS)
    period = check_period("period", period)
    margin = check("margin", margin, (lambda v: v >= 0, "must be >= 0"))
    if margin and controller != "bangbang":  # (the re-planning MPC plans for the estimate)
        raise ParameterError("margin", "applies to controller='bangbang' only")
    if margin and not estimate:  # (no estimate, no standard deviation to plan a margin from)
        raise ParameterError("margin", "applies to an estimated ground (not with "
                                       "estimate=False)")
    check_choice("estimator", estimator, ESTIMATORS)
    max_samples = check_count("max_samples", max_samples, 1, 10**7)
    sensor = Sensor(noise, delay, seed)
    plan = first_plan(impact, robot, model)
    problem = state_landing_problem()
    if not reuse:
        # the re-solves start from the NLPs cached for this problem: a landing starts from
        # none, so that it does not depend on what ran before it (its setup builds them)
        clear_cache(problem)
    plant = SteppingPlant(robot, impact, ground)
    if plan_time(plan) / period > max_samples:
        raise ParameterError("period", f"{period:g} takes about "
                                       f"{plan_time(plan) / period:.3g} samples over the "
                                       f"planned landing, more than max_samples = {max_samples}")
    # the foot has stopped when it is static, or creeps by rounding at the crater's exact
    # capacity (the optimal arrest uses all of it)
    stop = 1e-9 * max(1.0, abs(impact.v0))
    est = make_estimator(estimator, robot, model, sensor.noise, estimate, stop, plant.x)
    loop: ReplanController | CompiledController = CompiledController(
        robot, model, plan, est, period=period, margin=margin) if controller == "bangbang" \
        else ReplanController(robot, impact, model, plan, problem, est, period=period,
                              delay=sensor.delay, stop=stop)
    run = run_loop(loop, plant, sensor, period=period, max_samples=max_samples, stop=stop)
    return _landing(loop.record, run, plant, model=model, period=period, sensor=sensor,
                    controller=controller, margin=margin, estimator=est.name,
                    prepare_s=run.prepared - t_start)


MIN_SPEED = 1e-6
"""The slowest impact the controllers land (``|v0|``): below about 1e-9 the loop's test of a
stopped foot held the foot stopped at the impact, took no sample and reported the body
merely held at its weight (twice the optimal depth) as a landing."""


@lru_cache(maxsize=64)
def first_plan(impact: Impact, robot: Robot, model: Ground) -> Any:
    """The plan a landing starts from: the optimal landing on ``model``, refined if it can
    be, solved once per process and arguments and only read after (the controllers copy
    what they change). A study lands many true grounds on one model: the controller study's
    180 landings at three velocities start from three plans, not 180 solves of 0.1 s.

    Parameters
    ----------
    impact : Impact
        The touchdown.
    robot : Robot
        The robot.
    model : Ground
        The ground the plan assumes.

    Raises
    ------
    ocp.SolveError
        The plan cannot be made (not cached: a later call solves again).
    """
    first = solve_landing(impact, robot, model, replay=False)
    return first.refined if first.refined is not None else first.transcribed


def _landing(rec: LoopRecord, run: LoopRun, plant: SteppingPlant, *, model: Ground,
             period: float, sensor: Sensor, controller: str, margin: float, estimator: str,
             prepare_s: float) -> MPCLanding:
    """The landing's result from the loop's record and the plant's run."""
    final = run.final
    # within each sample (a sample's simulation also ranges over the future under its
    # control), then from the last sample on (the final simulation)
    stroke = ([lo for lo, _ in plant.stroke_ranges] + [final.stroke_min],
              [hi for _, hi in plant.stroke_ranges] + [final.stroke_max])
    paths = rec.step_paths
    return MPCLanding(robot=plant.robot, impact=plant.impact, ground=plant.ground, model=model,
                      period=period, result=final, depth=final.depth,
                      stroke_min=min(stroke[0]), stroke_max=max(stroke[1]),
                      u_peak=max(r.u_peak for _, r in plant.history),
                      step_times_ms=rec.step_times_ms, step_cpu_ms=rec.step_cpu_ms,
                      estimates=rec.estimates, replans=rec.replans, fallbacks=rec.fallbacks,
                      samples=run.samples, setup_ms=rec.setup_ms,
                      structure_changes=paths.count("structure"), step_paths=paths,
                      pieces=list(plant.history), prepare_time_s=prepare_s,
                      sample_limit_hit=run.sample_limit_hit, controller=controller,
                      uncovered=rec.uncovered, deferred=paths.count("bangbang (deferred)"),
                      creep_samples=paths.count("bangbang (creep law)"),
                      step_work=rec.step_work, noise=sensor.noise, delay=sensor.delay,
                      seed=sensor.seed, margin=margin, estimator=estimator,
                      compiled=rec.compiled)


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


__all__ = ["ARREST_RESERVE", "ARREST_TIME", "CONTROLLERS", "DEFAULT_PERIOD", "ESTIMATORS",
           "HOLD_GAINS", "MAX_NOISE", "MAX_PERIOD", "MIN_NOISE", "MIN_PERIOD", "MIN_SPEED",
           "MPCLanding",
           "Sensor", "check_model", "check_period", "first_plan", "mpc_landing"]
