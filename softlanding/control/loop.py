"""The closed loop: a landing controller, its estimator, the sensor and the stepping plant.

Any controller that follows :class:`LandingController` runs in :func:`run_loop` (as
python-control's ``input_output_response`` runs any closed loop, and do-mpc composes its
controller, estimator and simulator): before the impact the controller prepares (builds,
compiles) and gives its first command; every sample the plant runs the command that acts
(the one issued ``delay`` samples ago) for one period, the sensor measures, the estimator
makes the reading, and the controller's :meth:`~LandingController.step` turns it into the
next command. When the foot stops, the body's arrest from the measured state ends the
landing (:meth:`~softlanding.control.sensor.Sensor.arrest`).

The controllers: :class:`~softlanding.control.replan.ReplanController` (re-solves the
landing OCP every sample it must) and :class:`~softlanding.control.compiled.CompiledController`
(the compiled bang-bang controller with the creep law, microseconds a sample).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from softlanding.control.commands import Command, force_at_end, shifted
from softlanding.control.estimation import GroundEstimate
from softlanding.control.estimators import MeasuredEstimator, Reading
from softlanding.control.loop_replay import CompiledRecord
from softlanding.control.plant import SteppingPlant
from softlanding.control.sensor import Sensor
from softlanding.simulation.simulator import LandingResult


@dataclass
class LoopRecord:
    """What a landing's controller did, sample by sample: the fields of
    :class:`~softlanding.control.result.MPCLanding` of the same names (each sample's wall and
    CPU time, path, estimate and integrator steps; the counts of re-plans, kept plans and
    fallback samples; the builds before the impact; the compiled samples for a replay).

    Attributes
    ----------
    step_times_ms, step_cpu_ms : list of float
        Each sample's wall and CPU time.
    step_paths : list of str
        Each sample's path (how the command was found).
    estimates : list of GroundEstimate
        Each sample's ground estimate.
    step_work : list of int
        Each sample's integrator steps.
    replans, fallbacks, uncovered : int
        Re-plans by transcription, fallback samples, samples (and the impact's first plan)
        the compiled structure did not cover.
    setup_ms : float
        The builds before the impact.
    compiled : CompiledRecord or None
        The compiled samples, for :func:`~softlanding.control.loop_replay.replay`.
    """

    step_times_ms: list[float] = field(default_factory=list)
    step_cpu_ms: list[float] = field(default_factory=list)
    step_paths: list[str] = field(default_factory=list)
    estimates: list[GroundEstimate] = field(default_factory=list)
    step_work: list[int] = field(default_factory=list)
    replans: int = 0
    fallbacks: int = 0
    uncovered: int = 0
    setup_ms: float = 0.0
    compiled: CompiledRecord | None = None
    _c0: float = 0.0
    _t0: float = 0.0

    def start(self) -> None:
        """A sample's computation starts (the CPU clock, a system call of ~1 us, read
        outside the wall clock's interval)."""
        self._c0, self._t0 = time.process_time(), time.perf_counter()

    def stop(self, more: bool = False) -> None:
        """The computation started by :meth:`start` ends: a new sample's time, or (``more``)
        added to the last one's.

        Parameters
        ----------
        more : bool
            Add to the last sample's time (a second computation within it).
        """
        wall = 1e3 * (time.perf_counter() - self._t0)
        cpu = 1e3 * (time.process_time() - self._c0)
        if more:
            self.step_times_ms[-1] += wall
            self.step_cpu_ms[-1] += cpu
        else:
            self.step_times_ms.append(wall)
            self.step_cpu_ms.append(cpu)


@runtime_checkable
class LandingController(Protocol):
    """What :func:`run_loop` runs: prepare before the impact, then one step per sample from a
    reading to a command, timing its own computation into its record.

    Attributes
    ----------
    name : str
        The controller's name (``"replan"``, ``"bangbang"``).
    record : LoopRecord
        Its samples' paths, times and estimates.
    estimator : MeasuredEstimator
        What makes its readings.
    """

    name: str
    record: LoopRecord
    estimator: MeasuredEstimator

    def prepare(self, x0: np.ndarray) -> Command:
        """Everything before the impact (builds, compilation); the first command.

        Parameters
        ----------
        x0 : array of 4
            The impact state.
        """
        ...

    def step(self, r: Reading) -> Command:
        """One sample: the reading to the command from now on.

        Parameters
        ----------
        r : Reading
            The sample.
        """
        ...


@dataclass
class LoopRun:
    """The plant's run under the loop.

    Attributes
    ----------
    final : LandingResult
        The last simulation (from the foot's stop, or the last sample, to rest).
    samples : int
        Samples taken while the foot yielded.
    sample_limit_hit : bool
        ``max_samples`` ended the sampling before the foot stopped.
    prepared : float
        When the controller's preparation ended (``time.perf_counter``).
    """

    final: LandingResult
    samples: int
    sample_limit_hit: bool
    prepared: float


def run_loop(controller: LandingController, plant: SteppingPlant, sensor: Sensor, *,
             period: float, max_samples: int, stop: float) -> LoopRun:
    """Land the plant under ``controller`` from the impact to rest.

    Parameters
    ----------
    controller : LandingController
        The controller (prepared here).
    plant : SteppingPlant
        The true ground's plant, at the impact.
    sensor : Sensor
        The measurements' noise and the actuation's delay.
    period : float
        The sample period.
    max_samples : int
        A bound on the samples while the foot yields.
    stop : float
        The foot's speed below which it has stopped (static, or creeping by rounding at the
        crater's exact capacity: the optimal arrest uses all of it).
    """
    estimator = controller.estimator
    measured = sensor.measure(plant.x)[0]
    issued = [controller.prepare(plant.x)]  # the commands issued, in order
    prepared = time.perf_counter()
    samples = 0
    while plant.x[3] < -stop and samples < max_samples:
        acting = issued[max(0, len(issued) - 1 - sensor.delay)]  # the actuator's
        schedule = shifted(acting.schedule, plant.t - acting.origin)
        # a sample that would pass the planned stop of the foot ends there: the arrest is
        # then computed from the measured state, not from the plan's prediction of it
        h = min(period, acting.origin + acting.stop - plant.t)
        h = h if h > 1e-9 * period else period
        x_before = measured
        plant.step(schedule, h)  # the schedule's time starts at the step
        samples += 1
        if plant.x[3] >= -stop:  # the foot stopped within the sample: its arrest follows
            break
        u_end = force_at_end(schedule, plant.x, h)  # the force the sample ended under
        measured, a_f, u_meas = sensor.measure(plant.x, plant.foot_acceleration(u_end), u_end)
        reading = estimator.reading(Reading(samples, plant.t, h, measured, a_f, u_meas,
                                            x_before, schedule, acting, issued), u_end)
        issued.append(controller.step(reading))
    if plant.x[3] >= -stop:
        robot = plant.robot
        final = plant.finish(sensor.arrest(sensor.measure(plant.x)[0], robot.r_m, robot.s,
                                           robot.u_max))
    else:
        origin, command, _ = issued[-1]
        final = plant.finish(shifted(command, plant.t - origin))
    return LoopRun(final, samples, samples >= max_samples and plant.x[3] < -stop, prepared)


__all__ = ["LandingController", "LoopRecord", "LoopRun", "run_loop"]
