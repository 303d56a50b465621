"""The compiled landing controller as a loop's controller: the real-time Newton on the
push-then-pull plan's switching times with the creep law (:mod:`softlanding.control.bangbang`,
:mod:`softlanding.control.creep`) and the ground estimate in one compiled call per sample
(with the filtered estimate, the foot filter's step too: :mod:`softlanding.control.recovery`).

Its state is the compiled step's arrays: the robot's and ground's numbers ``P``, the memory
``M`` (the plan, the estimate), the foot filter's ``F`` (the estimator's) and the work arrays;
nothing is allocated per sample in the compiled code. Where the push-then-pull structure does
not cover a state, the compiled fallback acts in the same call, within the sample
(:mod:`softlanding.control.fallback`); no sample of the loop solves an NLP.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ocp.structure.switching import RefinedSwitching
from softlanding.control import bangbang as bb
from softlanding.control.commands import Command, plan_time
from softlanding.control.estimation import GroundEstimate
from softlanding.control.estimators import FilteredEstimator, MeasuredEstimator, Reading
from softlanding.control.fallback import fallback_step
from softlanding.control.foot_filter import new_filter
from softlanding.control.loop import LoopRecord
from softlanding.control.loop_replay import CompiledRecord, CompiledSample
from softlanding.control.recovery import filtered_sample
from softlanding.control.state_landing import ground_numbers
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.ground import Ground
from softlanding.model.robot import Robot
from softlanding.optimal.landing import arrest_schedule
from softlanding.optimal.limits import force_limit


class CompiledController:
    """The compiled bang-bang controller with the creep law
    (:func:`~softlanding.control.mpc_landing`'s ``"bangbang"``).

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit).
    model : Ground
        The ground its first plan assumed (the estimate's prior).
    plan : RefinedSwitching or ocp.Solution
        The first plan (covered if it is push then pull, or pull).
    estimator : MeasuredEstimator
        Its ground estimate (the compiled step runs the same; a filtered one's foot filter is
        stepped inside the compiled call).
    period, margin : float
        The sample period; plan for the estimate less ``margin`` standard deviations.
    record : LoopRecord, optional
        Where its samples are recorded (default: a new one).

    Attributes
    ----------
    P, M : ndarray
        The compiled step's numbers and memory.
    recovering : int
        Samples the filtered estimate's full solve has gone on over so far.
    """

    name = "bangbang"

    def __init__(self, robot: Robot, model: Ground, plan: Any, estimator: MeasuredEstimator,
                 *, period: float, margin: float, record: LoopRecord | None = None) -> None:
        self.robot, self.model, self.estimator = robot, model, estimator
        self.record = LoopRecord() if record is None else record
        self.u_max, self.r_m = force_limit(robot), robot.r_m
        self.ws = bb.workspace()
        self.recovering = 0
        kinds = tuple(m[0].kind for m in plan.modes) if isinstance(plan, RefinedSwitching) \
            and all(len(m) == 1 for m in plan.modes) else ()
        k, c_d = ground_numbers(model)
        noise = bb.ground_force_noise(robot.r_m, estimator.noise, estimator.F is not None)
        self.P = bb.robot_numbers(robot.r_m, robot.s, self.u_max, k, c_d, noise, margin, period,
                                  creep=True)
        # a first plan of the structure (push then pull, or pull) is the memory's; another
        # (a creep, a boundary arc) gives the compiled plan's first guess, half and half
        self.covered = kinds in (("max", "min"), ("min",))
        T = plan_time(plan)
        d = np.asarray(plan.durations, float) if self.covered else np.array([0.5 * T, 0.5 * T])
        t1, t2 = (d[0], d[1]) if kinds == ("max", "min") or not self.covered \
            else (0.0, float(d[-1]))
        self.M = bb.new_memory(t1, t2, (k, c_d), (1.0, 1.0), noise)
        if self.covered:  # the first plan's state at the foot's stop (its schedule's tail)
            self.M[bb.M_XBT], self.M[bb.M_VBT], self.M[bb.M_XFT] = np.asarray(plan.xT,
                                                                             float)[:3]

    def prepare(self, x0: np.ndarray) -> Command:
        """Compile (or load numba's cache) before the impact, a sample must not pay for it;
        a first plan not of the structure solved compiled from the impact (its fallback's
        force where that does not cover it); the first command.

        Parameters
        ----------
        x0 : array of 4
            The impact state.
        """
        self._compile()
        if not self.covered:  # (before the impact: no bound on the work)
            x = np.array(x0, float)
            st = int(bb.solve_plan(self.P, self.M, x, *self.ws, np.inf))
            if fallback_step(self.P, self.M, x, st) != st:  # (counted as a sample's would be)
                self.record.uncovered += 1
        F = self.estimator.F
        # the compiled samples' inputs, for a replay as a control loop (:mod:`.loop_replay`)
        self.record.compiled = CompiledRecord(self.P.copy(), self.M.copy(),
                                              None if F is None else F.copy())
        return Command(0.0, self.schedule(), self.stop_time())

    def _compile(self) -> None:
        """Each compiled call the samples make, run once on copies."""
        P, M, ws = self.P, self.M, self.ws
        x = np.array([10.0, -1.0, -0.1, -1.0])
        bb.control_step(P.copy(), M.copy(), x.copy(), 0.0, 0.0, 1e-3 * P[bb.P_PERIOD], False,
                        *ws)
        if self.estimator.F is not None:  # (and the filtered sample, with the bounded full
            # solve it may need: loading that mid-landing took 17 ms)
            bb.solve_plan(P.copy(), M.copy(), x.copy(), *ws, float(P[bb.P_WORK]))
            filtered_sample(P.copy(), M.copy(), new_filter(np.array([10.0, -1.0, 0.0, -1.0])),
                            x.copy(), 0.0, 0.0, 0.0, 1e-3 * P[bb.P_PERIOD], 0.0, 0.0, 0.0,
                            0.0, False, 0.0, 0, *ws)

    def step(self, r: Reading) -> Command:
        """One sample, compiled (the estimate, the foot filter's step, the plan's re-solve or
        the creep law's force, the fallback where the structure does not cover the state).

        Parameters
        ----------
        r : Reading
            The sample.
        """
        rec, est, M = self.record, self.estimator, self.M
        x_in = r.x.copy()
        fallbacks = M[bb.M_FALLBACKS]
        rec.start()
        fit = est.fits(r.sample)
        if est.F is None:
            status = int(bb.control_step(self.P, M, r.x, r.a_f, r.u, r.h, fit, *self.ws))
        else:  # the filter's step, the sample's weight and the step in one call
            assert isinstance(est, FilteredEstimator)  # (the one with a foot filter F)
            st, self.recovering = filtered_sample(
                self.P, M, est.F, r.x, r.g, r.U1, r.U2, r.h, est.beta, est.noise, r.a_f,
                r.u, fit, est.stop, self.recovering, *self.ws)
            status = int(st)
        rec.stop()
        self._log(r, x_in, fit, status)
        name = "bangbang" if status == bb.OK else f"bangbang ({bb.STATUS_NAMES[status]})"
        if M[bb.M_FALLBACKS] > fallbacks:  # (the structure did not cover the state)
            rec.uncovered += 1
            name = f"bangbang ({bb.STATUS_NAMES[status]}: {bb.STATUS_NAMES[int(M[bb.M_WHY])]})"
        rec.step_paths.append(name)
        return Command(r.t, self.schedule(), self.stop_time())

    def _log(self, r: Reading, x_in: np.ndarray, fit: bool, status: int) -> None:
        """The sample's work, its inputs and outputs (for a replay), and the estimate."""
        rec, est = self.record, self.estimator
        rec.step_work.append(int(self.M[bb.M_WORK]))
        if rec.compiled is not None:
            F = est.F
            filt = None
            if F is not None:
                assert isinstance(est, FilteredEstimator)  # (the one with a foot filter F)
                filt = (float(r.g), float(r.U1), float(r.U2), float(est.beta),
                        float(est.noise), float(est.stop))
            rec.compiled.samples.append(CompiledSample(
                x_in, float(r.a_f), float(r.u), float(r.h), bool(fit), filt,
                status, self.M.copy(), None if F is None else F.copy(), self.recovering))
        if est.enabled:
            rec.estimates.append(self.estimate())

    def schedule(self) -> ForceSchedule | FeedbackSchedule:
        """The plan's force from now: push until the switch, pull until the foot's stop,
        then the arrest of the body (saturated at the force limit) and its weight (from the
        plan's state at the stop); or,
        creeping or braking, the creep law's or the brake's force of this sample (held: the
        next sample computes the next)."""
        M = self.M
        if M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING):
            return ForceSchedule((), (float(M[bb.M_UCREEP]),))
        t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
        t2 = float(M[bb.M_TAU2])
        x_t = np.array([M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT], 0.0])
        tail = arrest_schedule(x_t, self.r_m)
        assert isinstance(tail, ForceSchedule)  # (a constant arrest force, then the weight)
        times = ((t1,) if t1 > 0 else ()) + (t1 + t2,) + tuple(t1 + t2 + t for t in tail.times)
        # (the arrest's force saturated at the limit: a noisy state's arrest may ask more)
        values = ((self.u_max,) if t1 > 0 else ()) + (-self.u_max,) + tuple(
            min(self.u_max, max(-self.u_max, v)) for v in tail.values)
        return ForceSchedule(times, values)

    def stop_time(self) -> float:
        """When the plan has the foot stop (from now; creeping or braking: not planned,
        ``inf``)."""
        if self.M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING):
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


__all__ = ["CompiledController"]
