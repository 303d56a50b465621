"""The exported C foot filter and filtered step against the Python (numba) ones, on the
measurements of random noisy landings of the filtered controller (and the plans' force
integrals and ground estimates on them).

A landing is the exported robot on a random ground, off the controller's prior, at a random
impact velocity, sample period, sensor noise and margin, landed as ``mpc_landing(...,
controller="bangbang", estimator="filtered")`` lands it: every sample the plan's force over
it integrated (:func:`~.reference.plan_force_integrals`), a plant (Runge-Kutta steps on the
true ground, the force's pieces exact) moved under it, the foot's state and acceleration
measured with noise, filtered (:func:`~softlanding.control.foot_filter.filter_step`), and
the filtered sample run on the filtered state and the force as applied
(:func:`~softlanding.control.recovery.filtered_step`: the estimate from the third sample on,
each sample weighed by :func:`~softlanding.control.recovery.sample_weight`; the bounded full
solve where the push's real-time iteration runs out). Every filter call's and every
step's inputs and every plan's integration are recorded, so that the C runs exactly the
same ones. Before the random landings run the probes of :data:`PROBES` (a fast impact on a
draggy ground, where the innovation check widens the prediction) and of
:data:`RECOVERY_PROBES` (fast draggy landings whose push needs the bounded full solve, over
several samples).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control import foot_filter as ff
from softlanding.control.estimation import GroundEstimator
from softlanding.control.export_c.binding import CController
from softlanding.control.export_c.reference import (
    ground_estimate,
    plan_force_integrals,
    plan_schedule,
    relative_difference,
)
from softlanding.control.recovery import filtered_step, sample_weight
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.limits import force_limit

#: Samples of one landing at most (the :data:`RECOVERY_PROBES` run whole).
MAX_SAMPLES = 40

#: Landings every comparison runs first: ``(v0, K, c_d, noise, period)`` (the prior's
#: ground the true one): a fast impact on a draggy ground, whose drag transient the
#: filter's interpolation does not follow (the innovation check's path).
PROBES = ((-10.0, 0.5, 1.0, 1e-3, 0.01), (-6.0, 0.5, 1.0, 1e-2, 0.01))

#: Landings run after :data:`PROBES`, whole (to the foot's stop): ``(v0, K, c_d)`` of the
#: true ground, from the prior ``K = 1``, ``c_d = 0`` (``mpc_landing``'s), at sensor noise
#: :data:`RECOVERY_NOISE`, margin :data:`RECOVERY_MARGIN`, period 0.01: the fast draggy
#: landings of the controller study whose push needs the bounded full solve.
RECOVERY_PROBES = ((-6.0, 0.5, 1.0), (-10.0, 0.5, 1.0), (-6.0, 0.75, 1.0),
                   (-10.0, 0.75, 1.0))
RECOVERY_NOISE, RECOVERY_MARGIN = 1e-3, 2.0


@dataclass(frozen=True)
class FilterCall:
    """One call of the foot filter: its inputs (``F`` and ``x`` before it), as
    :func:`~softlanding.control.foot_filter.filter_step` takes them.

    Attributes
    ----------
    F : ndarray
        The filter's memory before the call.
    x : ndarray
        The measured state before the call.
    g : float
        The measured foot acceleration less ``beta u`` at the sample's end.
    U1, U2 : float
        The force's integrals over the sample.
    h : float
        The sample.
    beta : float
        The foot's acceleration per unit of the robot's force.
    noise : float
        The measurements' standard deviation.
    """

    F: np.ndarray
    x: np.ndarray
    g: float
    U1: float
    U2: float
    h: float
    beta: float
    noise: float


@dataclass(frozen=True)
class PlanCall:
    """A plan's force integrated over a sample: ``P``, ``M`` after the step, the sample, and
    the integrals of the Python schedule (:func:`~.reference.plan_force_integrals`).

    Attributes
    ----------
    P, M : ndarray
        The controller's numbers and memory after the step.
    h : float
        The sample.
    U : ndarray
        The Python schedule's integrals over the sample.
    """

    P: np.ndarray
    M: np.ndarray
    h: float
    U: np.ndarray


@dataclass(frozen=True)
class StepCall:
    """One sample of the filtered controller: its inputs, as
    :func:`~softlanding.control.recovery.sample_weight` and
    :func:`~softlanding.control.recovery.filtered_step` take them.

    Attributes
    ----------
    P, M : ndarray
        The controller's numbers and memory before the step.
    F : ndarray
        The filter's memory after the sample's filter step (the weight's covariance).
    x : ndarray
        The filtered state.
    a_f, u, h : float
        The measured foot acceleration, the force the sample ended under, its length.
    estimate : bool
        The estimate's update (no fit from the filter's provisional samples).
    recovering : int
        Samples the recovery had gone on over before it.
    """

    P: np.ndarray
    M: np.ndarray
    F: np.ndarray
    x: np.ndarray
    a_f: float
    u: float
    h: float
    estimate: bool
    recovering: int


@dataclass
class LandingCalls:
    """The recorded calls of noisy filtered landings, in order (:func:`filtered_calls`).

    Attributes
    ----------
    filter : list of FilterCall
        The foot filter's calls.
    plans : list of PlanCall
        Every sample's plan integrated over it.
    steps : list of StepCall
        The filtered controller's samples.
    landings : int
        How many landings they make.
    """

    filter: list[FilterCall] = field(default_factory=list)
    plans: list[PlanCall] = field(default_factory=list)
    steps: list[StepCall] = field(default_factory=list)
    landings: int = 0


def _foot_acc(P: np.ndarray, u: float, xf: float, vf: float, truth: tuple[float, float]
              ) -> float:
    return float(P[bb.P_AF0] + P[bb.P_BF] * u
                 + P[bb.P_GF] * (truth[0] * -xf - truth[1] * vf * abs(vf)))


def _plant(P: np.ndarray, M: np.ndarray, x: np.ndarray, h: float,
           truth: tuple[float, float]) -> tuple[np.ndarray, float]:
    """The robot on the true ground over ``h`` under the plan's force (each constant piece
    by 8 classical Runge-Kutta steps of the foot, the body exact); the state and the force
    at the end."""
    ends, values = plan_schedule(P, M)
    xb, vb, xf, vf = (float(v) for v in x)
    a = 0.0
    u = float(values[-1])
    for b, u in zip((*ends, np.inf), values, strict=True):
        lo, hi = max(a, 0.0), min(b, h)
        a = max(a, b)
        if hi <= lo:
            continue
        dt = (hi - lo) / 8
        ab = float(P[bb.P_AB0] + P[bb.P_BB] * u)
        for _ in range(8):
            k1x, k1v = vf, _foot_acc(P, u, xf, vf, truth)
            k2x, k2v = vf + 0.5 * dt * k1v, _foot_acc(P, u, xf + 0.5 * dt * k1x,
                                                      vf + 0.5 * dt * k1v, truth)
            k3x, k3v = vf + 0.5 * dt * k2v, _foot_acc(P, u, xf + 0.5 * dt * k2x,
                                                      vf + 0.5 * dt * k2v, truth)
            k4x, k4v = vf + dt * k3v, _foot_acc(P, u, xf + dt * k3x, vf + dt * k3v, truth)
            xf += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            vf += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
            xb += dt * vb + 0.5 * ab * dt * dt
            vb += dt * ab
        if hi >= h:
            break
    return np.array([xb, vb, xf, vf]), float(u)


def _landing(robot: Robot, v0: float, prior: tuple[float, float], truth: tuple[float, float],
             noise: float, period: float, first: float, seed: int, margin: float,
             max_samples: int, calls: LandingCalls) -> int:
    """One filtered landing (its calls appended); the filter calls it made."""
    u_max = force_limit(robot)
    P = bb.robot_numbers(robot.r_m, robot.s, u_max, *prior,
                         bb.ground_force_noise(robot.r_m, noise, True), margin, period)
    M = bb.new_memory(0.1, 0.1, prior, (1.0, 1.0), float(P[bb.P_NOISE]))
    ws = bb.workspace()
    x = np.ascontiguousarray(Impact(v0).initial_state(robot), float)
    if int(bb.solve_plan(P, M, x, *ws, np.inf)) != bb.OK:
        return 0
    rng = np.random.default_rng(seed)
    F = ff.new_filter(x)
    beta = float(P[bb.P_BF])
    done = recovering = 0
    for sample in range(max_samples):
        length = (M[bb.M_TAU1] if M[bb.M_PHASE] == bb.PUSH else 0.0) + M[bb.M_TAU2]
        # a sample that would pass the plan's foot stop ends there (as mpc_landing's); the
        # first, in some landings, shorter (the impact within a period)
        h = min(first if sample == 0 else period, float(length))
        if h <= 1e-9 * period:
            break
        U1, U2 = U = plan_force_integrals(P, M, h)
        calls.plans.append(PlanCall(P.copy(), M.copy(), h, U))
        x, u_end = _plant(P, M, x, h, truth)
        if x[3] >= 0.0:  # the foot stopped within the sample
            break
        e = rng.normal(0.0, noise, 3)
        a_f = _foot_acc(P, u_end, x[2], x[3], truth) + e[2]
        measured = x.copy()
        measured[2] += e[0]
        measured[3] += e[1]
        g = a_f - beta * u_end
        calls.filter.append(FilterCall(F.copy(), measured.copy(), g, U1, U2, h, beta, noise))
        ff.filter_step(F, measured, g, U1, U2, h, beta, noise)
        done += 1
        measured[3] = min(measured[3], -1e-9 * max(1.0, abs(v0)))
        fit = bool(F[ff.F_N] > ff.PROVISIONAL)
        calls.steps.append(StepCall(P.copy(), M.copy(), F.copy(), measured.copy(), a_f, u_end,
                                    h, fit, recovering))
        weight = sample_weight(P, M, F, measured, a_f, u_end) if fit else 1.0
        st, recovering = filtered_step(P, M, measured, a_f, u_end, h, fit, weight,
                                       recovering, *ws)
        if st not in (bb.OK, bb.CONVERGING, bb.HOLDS, bb.DEFERRED) and not (
                st == bb.ARREST_FAILS and M[bb.M_PHASE] == bb.PULL):
            break  # a state the controller does not cover: the MPC would take over
    return done


def filtered_calls(robot: Robot, n_steps: int, seed: int = 0) -> LandingCalls:
    """The calls of the :data:`PROBES`, the :data:`RECOVERY_PROBES` and random filtered
    landings of ``robot``, ``n_steps`` filter calls in all (the last landing cut there).

    Parameters
    ----------
    robot : Robot
        With a force limit.
    n_steps : int
        Filter calls (and as many filtered steps).
    seed : int
        Of the landings.
    """
    rng = np.random.default_rng(seed)
    out = LandingCalls()
    n_probes = len(PROBES) + len(RECOVERY_PROBES)
    for i in itertools.count():
        if len(out.filter) >= n_steps:
            break
        margin, cap = 0.0, MAX_SAMPLES
        if i < len(PROBES):
            v0, k, c_d, noise, period = PROBES[i]
            prior = truth = (k, c_d)
            first = period
        elif i < n_probes:
            v0, k, c_d = RECOVERY_PROBES[i - len(PROBES)]
            prior, truth = (1.0, 0.0), (k, c_d)
            noise, margin, period, first = RECOVERY_NOISE, RECOVERY_MARGIN, 0.01, 0.01
            cap = 10 * MAX_SAMPLES  # (whole: the recovery comes late in the push)
        else:
            k = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
            c_d = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 1.0))
            prior = (k, c_d)
            truth = (k * float(rng.uniform(0.5, 1.5)), c_d * float(rng.uniform(0.5, 1.5)))
            noise = float(rng.choice([1e-4, 1e-3, 1e-2]))
            v0 = float(rng.uniform(-10.0, -0.5))
            period = float(rng.uniform(0.005, 0.03))
            first = period * float(rng.uniform(0.3, 1.0)) if rng.random() < 0.2 else period
            margin = float(rng.choice([0.0, 2.0]))
        out.landings += bool(_landing(robot, v0, prior, truth, noise, period, first,
                                      seed * 100_003 + i, margin, cap, out))
    del out.filter[n_steps:], out.steps[n_steps:]
    return out


@dataclass
class FilterComparison:
    """How far the C filter's outputs are from the numba filter's.

    Attributes
    ----------
    landings, steps : int
        Landings, filter steps compared.
    paths : dict
        How many steps took each of the filter's paths (``"first"``, ``"second"``, ``"redo"``:
        the first two samples redone at the third, ``"quadratic"``, ``"chord"``: a sample of
        another length) and were ``"widened"`` by the innovation check (numba's filter
        with the check and without it differ).
    plans : int
        Plans whose force integrals were compared.
    max_relative : dict
        ``"F"``, ``"x"``, ``"widened"`` (1 if the C's flag ever differs from numba's),
        ``"force integrals"`` (the C's ``sl_force_integrals`` against the Python schedule's),
        ``"estimate"`` (``sl_ground_estimate`` against the Python estimator's, at every
        plan): the largest relative difference of each.
    """

    landings: int = 0
    steps: int = 0
    plans: int = 0
    paths: dict[str, int] = field(default_factory=dict)
    max_relative: dict[str, float] = field(default_factory=lambda: {
        "F": 0.0, "x": 0.0, "widened": 0.0, "force integrals": 0.0, "estimate": 0.0})

    def worst(self) -> float:
        """The largest relative difference of any output."""
        return max(self.max_relative.values())

    def describe(self) -> str:
        """One line: what was compared and how far apart."""
        d = self.max_relative
        p = ", ".join(f"{k} {v}" for k, v in self.paths.items())
        return (f"{self.steps} filter steps of {self.landings} noisy landings ({p}), largest "
                f"relative difference {max(d['F'], d['x'], d['widened']):.3g}; the force "
                f"integrals of {self.plans} plans {d['force integrals']:.3g}, their ground "
                f"estimates {d['estimate']:.3g}")


def filter_path(F: np.ndarray, h: float) -> str:
    """Which of the filter's predictions a step from memory ``F`` over ``h`` takes.

    Parameters
    ----------
    F : array
        The filter's memory before the step.
    h : float
        The sample.
    """
    n, same = F[ff.F_N], abs(F[ff.F_H] - h) <= 1e-12 * h
    if n < 2:
        return ("first", "second")[int(n)]
    if n == 2 and same and F[ff.F_H0] > 0:
        return "redo"
    return "quadratic" if same else "chord"


def compare_filter(c: CController, n_steps: int = 600, seed: int = 0,
                   calls: LandingCalls | None = None) -> FilterComparison:
    """Run the filter calls of :func:`filtered_calls` through both filters and the plans'
    force integrals through ``sl_force_integrals`` and the Python schedule, and compare.

    Parameters
    ----------
    c : CController
        The compiled export.
    n_steps : int
        Filter steps.
    seed : int
        Of the landings.
    calls : LandingCalls, optional
        :func:`filtered_calls` of the export's robot, ``n_steps`` and ``seed`` (made if not
        given).
    """
    r = c.robot_numbers
    robot = Robot(r_m=float(r[bb.P_RM]), s=float(r[bb.P_S]), u_max=float(r[bb.P_UMAX]))
    if calls is None:
        calls = filtered_calls(robot, n_steps, seed)
    fcalls, pcalls = calls.filter, calls.plans
    out = FilterComparison(landings=calls.landings, steps=len(fcalls), plans=len(pcalls))
    est = GroundEstimator(robot)
    got: dict[str, list[np.ndarray]] = {"F": [], "x": [], "widened": [], "force integrals": [],
                                        "estimate": []}
    want: dict[str, list[np.ndarray]] = {k: [] for k in got}
    for k in fcalls:
        path = filter_path(k.F, k.h)
        Fp, Fc, xp, xc = k.F.copy(), k.F.copy(), k.x.copy(), k.x.copy()
        ff.filter_step(Fp, xp, k.g, k.U1, k.U2, k.h, k.beta, k.noise)
        wc = c.filter_step(Fc, xc, k.g, k.U1, k.U2, k.h, k.beta, k.noise)
        Fq, xq = k.F.copy(), k.x.copy()  # without the check: differs where it widened
        ff.filter_step(Fq, xq, k.g, k.U1, k.U2, k.h, k.beta, 0.0)
        wp = not np.array_equal(Fp, Fq)
        out.paths[path] = out.paths.get(path, 0) + 1
        out.paths["widened"] = out.paths.get("widened", 0) + int(wp)
        for key, a, b in (("F", Fc, Fp), ("x", xc, xp),
                          ("widened", np.array([float(wc)]), np.array([float(wp)]))):
            got[key].append(a)
            want[key].append(b)
    for pc in pcalls:
        got["force integrals"].append(c.force_integrals(pc.P, pc.M, pc.h))
        want["force integrals"].append(pc.U)
        got["estimate"].append(c.ground_estimate(pc.P, pc.M))
        want["estimate"].append(ground_estimate(pc.P, pc.M, est))
    for key in got:
        if got[key]:
            out.max_relative[key] = relative_difference(np.concatenate(got[key]),
                                                        np.concatenate(want[key]))
    return out


__all__ = ["MAX_SAMPLES", "PROBES", "RECOVERY_MARGIN", "RECOVERY_NOISE", "RECOVERY_PROBES",
           "FilterCall", "FilterComparison", "LandingCalls", "PlanCall", "StepCall",
           "compare_filter", "filter_path", "filtered_calls"]
