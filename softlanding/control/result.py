"""A landing under closed-loop control: what :func:`~softlanding.control.mpc_landing`
returns (the plant's pieces, the limits over the whole landing, every sample's path, time
and estimate)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp import Trajectory
from softlanding.control.estimation import GroundEstimate
from softlanding.control.loop_replay import CompiledRecord
from softlanding.model.ground import Ground
from softlanding.model.robot import Impact, Robot
from softlanding.model.terrain import paper_rig_units
from softlanding.simulation.simulator import LandingResult, joined_trajectory
from softlanding.util.jsonable import json_safe

#: The relative excess over the force limit :attr:`MPCLanding.force_held` allows (rounding).
FORCE_TOL = 1e-9


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
        What computed each sample: the compiled controller's ``"bangbang"`` and
        ``"bangbang (status)"``; the re-planning MPC's ``"plan holds"`` (no re-solve: the
        sample went as the plan predicted on its ground, which is still the estimate),
        ``"newton"`` (the plan's
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
        The controller's name (:data:`~softlanding.control.options.CONTROLLERS`).
    sample_limit_hit : bool
        ``max_samples`` ended the sampling before the foot stopped.
    uncovered : int
        ``controller="bangbang"``: samples the compiled controller did not cover (its
        structure, push then pull, did not fit the state and estimate; the impact's state
        counts as one): the compiled fallback met each within the sample (``step_paths``:
        ``"bangbang (kept: ...)"``,
        ``"bangbang (creep law: ...)"``, ``"bangbang (brake: ...)"``, after the colon why).
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
    def force_held(self) -> bool:
        """``|u| <= u_max`` over the whole landing (to 1e-9: the plant saturates every
        command, so a force beyond is a bug, not a landing)."""
        u_max = self.robot.u_max
        return u_max is None or bool(self.u_peak <= u_max * (1 + FORCE_TOL))

    @property
    def feasible(self) -> bool:
        """The stroke and the force held, and rest proven at the end."""
        return self.stroke_held and self.force_held and self.result.rest_proven

    def failure(self) -> str | None:
        """Why the landing is not :attr:`feasible` (one line), or None."""
        why = []
        if self.stroke_min < -1e-9 * max(1.0, self.robot.s):
            why.append(f"the stroke went below 0 ({self.stroke_min:.6g})")
        if self.stroke_max > self.robot.s * (1 + 1e-9) + 1e-9:
            why.append(f"the stroke went beyond s = {self.robot.s:g} ({self.stroke_max:.6g})")
        if not self.force_held:
            why.append(f"the force reached |u| = {self.u_peak:.6g}, beyond u_max = "
                       f"{self.robot.u_max:g}")
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
            "force_held": self.force_held,
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


__all__ = ["FORCE_TOL", "MPCLanding"]
