"""A compiled landing controller: real-time Newton on the bang-bang plan's switching times.

On every ground ``f = K d + c_d v_f^2`` where the optimal landing is bang-bang it is full
push (``u = u_max``) for ``tau_1``, then full pull (``u = -u_max``) for ``tau_2`` until the
foot stops, with the body's arrest exactly within the crater's hold (the ``ARREST``
condition of :func:`softlanding.optimal.landing.landing_stance` active). From a measured
state the two durations solve two equations,

``v_f(tau_1 + tau_2) = 0`` and
``S (K d - 1/(1+r_m)) - r_m/(1+r_m) (S + v_b^2/2) = 0`` at the foot's stop
(``S = x_b - x_f`` the stroke, ``d = -x_f``),

the exact Newton re-solve of the plan's structure that :mod:`softlanding.control.mpc` runs
through :func:`ocp.refine_structure`, here compiled: the body moves in closed form (its
acceleration holds no ground), the foot's two states and their sensitivity (the transition
matrix of the pull arc) by adaptive Dormand-Prince 8(5,3) steps (the simulator's
coefficients, :mod:`softlanding.simulation.kernel.dop853`) to ``RTOL`` (to
``LOOSE_RTOL``, about 4 times fewer steps, while Newton's steps are far above that error:
the first ones after the estimate moved). Every sample starts Newton from the last plan
shifted by the sample (a real-time iteration, iterated to convergence: one or two Newton
steps once the estimate has settled). One sample takes at most ``WORK`` integrator steps
(the bound on its time): one that runs out keeps the last whole iterate, or the last plan,
and the next sample's Newton goes on from there (status ``DEFERRED``). Once the push has
ended only ``tau_2`` is left (the foot's stop), and the arrest condition is checked, not
solved. The acceleration coefficients come from
:func:`softlanding.model.dynamics.robot_rhs` (one definition of the dynamics).

The ground estimate is the recursive least squares of
:class:`~softlanding.control.estimation.GroundEstimator`, compiled into the same step.

Where the optimum creeps to the static depth (the plan's body rises at the foot's stop, or
the creep law's own plan reaches that depth with the momentum spent, judged on the ground
:data:`CREEP_SIGMAS` standard deviations stiffer and less draggy) the step hands over to the
creep law (:mod:`softlanding.control.creep`, phase :data:`CREEPING`, status
:data:`CREEP_LAW`) with ``P[P_CREEP] = 1``. A state neither covers (Newton fails, a duration
turns negative beyond the switch, the arrest cannot hold, a limit on the plan's path) is
reported, and the caller falls back to the re-planning MPC
(:func:`~softlanding.control.mpc.mpc_landing` counts it).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.control.creep import creep_force, creep_reachable
from softlanding.model.dynamics import VB, VF, robot_rhs
from softlanding.simulation.kernel.const import ENTRY, JIT
from softlanding.simulation.kernel.dop853 import E3 as DE3
from softlanding.simulation.kernel.dop853 import E5 as DE5
from softlanding.simulation.kernel.dop853 import A as DA
from softlanding.simulation.kernel.dop853 import B as DB

#: Relative and absolute tolerance of the foot's integration (Newton's last steps).
RTOL = 1e-13

#: Newton's iterations per sample at most, and its tolerance on the durations (relative to
#: the plan's length).
MAX_NEWTON, NEWTON_TOL = 30, 1e-13

#: The relative tolerance of the arcs while Newton's last step (relative to the plan's
#: length) is above ``TIGHTEN`` (the error of the arcs is then far below the step: the step
#: is as good; the last steps, to convergence, are at :data:`RTOL`), and the relative change
#: of the estimated ground after which a sample's first step counts as large.
LOOSE_RTOL, TIGHTEN = 1e-8, 1e-6

#: The integrator steps (taken or rejected) one sample may spend: the hard bound on its
#: work. A sample that runs out keeps the last whole Newton iterate (or the last plan,
#: shifted) and the next sample's Newton goes on from there (``M_DEFERRED`` counts them).
WORK = 100

#: What :func:`_flow` returns: the arc marched, the march failed, no integrator step left.
MARCH_FAILED, MARCHED, SPENT = 0, 1, 2

# the layout of the robot and ground numbers P
(P_AB0, P_BB, P_AF0, P_BF, P_GF, P_K, P_CD, P_RM, P_S, P_UMAX, P_HOLD0, P_NOISE,
 P_MARGIN, P_BUDGET, P_PERIOD, P_WORK, P_CREEP) = range(17)
NP = 17
# the layout of the controller's memory M
(M_PHASE, M_TAU1, M_TAU2, M_TH0, M_TH1, M_P00, M_P01, M_P11, M_SAMPLES, M_ITER,
 M_STATUS, M_XBT, M_VBT, M_XFT, M_UNCONVERGED, M_PRED, M_PRED_OK, M_KPLAN,
 M_CPLAN, M_LAST_STEP, M_WORK, M_DEFERRED, M_UCREEP) = (*range(15), 15, 19, 20, 21, 22, 23,
                                                       24, 25)
NM = 26

#: Phases: pushing (both arcs left), pulling (the foot's stop left), creeping (the creep
#: law's force, :mod:`softlanding.control.creep`, every sample to the foot's stop).
PUSH, PULL, CREEPING = 0, 1, 2
#: Statuses of a step: covered (the plan re-solved), and why not.
#: (:data:`DEFERRED`: the sample's integrator steps ran out, see :data:`WORK`.)
#: (:data:`CREEP_LAW`: the creep law's force, in ``M[M_UCREEP]``, covers the state; only with
#: ``P[P_CREEP] = 1``, else such a state is :data:`CREEP`, not covered.)
(OK, NEWTON_FAILED, ARREST_FAILS, PATH_LIMIT, CONVERGING, HOLDS, CREEP, DEFERRED,
 CREEP_LAW) = range(9)
STATUS_NAMES = {OK: "ok", NEWTON_FAILED: "newton failed", ARREST_FAILS: "arrest fails",
                PATH_LIMIT: "path limit", CONVERGING: "converging", HOLDS: "plan holds",
                CREEP: "creep", DEFERRED: "deferred", CREEP_LAW: "creep law"}

#: Relative agreement of the measured state with the plan's prediction, and of the estimate
#: with the plan's ground, under which a sample keeps the plan (as the re-planning MPC's).
PLAN_HOLDS_TOL = 1e-8

#: Standard deviations of the estimate by which the ground the creep law's takeover is judged
#: on is stiffer and less draggy than the estimate (:func:`_step`).
CREEP_SIGMAS = 3.0

#: The creep law's force is limited to keep the stroke this fraction of ``s`` inside its
#: limits (:func:`stroke_guard`; the force is held over a sample, the ground's changes).
STROKE_MARGIN = 1e-3

#: Newton iterations per sample while the switch is more than three samples away (one:
#: acados' real-time iteration).
BUDGET = 1
#: Samples in a row whose Newton step is still above a tenth of the period before the
#: state counts as not covered.
MAX_UNCONVERGED = 12


def force_coefficients(r_m: float) -> tuple[float, float]:
    """``beta, gamma`` of the foot's acceleration ``alpha + beta u + gamma f_g``.

    Parameters
    ----------
    r_m : float
        Mass ratio.
    """
    P = robot_numbers(r_m, 1.0, 1.0, 1.0, 0.0)
    return float(P[P_BF]), float(P[P_GF])


def ground_force_noise(r_m: float, sensor_noise: float, filtered: bool = False) -> float:
    """Standard deviation of one ground force the estimator derives from the foot's measured
    acceleration and force, each with noise ``sensor_noise`` (at least ``1e-6``: the
    estimator's weight of an exact measurement).

    Parameters
    ----------
    r_m : float
        Mass ratio.
    sensor_noise : float
        Standard deviation of the measured acceleration and force.
    filtered : bool
        The force is the one applied (known) and the foot's state filtered
        (:mod:`softlanding.control.foot_filter`): the acceleration's noise, and
        :data:`FILTERED_REGRESSOR` for the filtered state's error in the regressors.
    """
    beta, gamma = force_coefficients(r_m)
    if filtered:
        return max(sensor_noise * float(np.hypot(1.0 / gamma, FILTERED_REGRESSOR)), 1e-6)
    return max(sensor_noise * float(np.hypot(1.0, beta)) / abs(gamma), 1e-6)


#: The ground force's error from the filtered foot state in the regressors (its position
#: times ``K``, its velocity times ``2 c_d |v_f|``), relative to the sensor's noise: about
#: 1e-2 and 5e-2 of it measured at ``v0 = -1``; 0.1 (0.3: deeper on 4 of 5 cases).
FILTERED_REGRESSOR = 0.1


def robot_numbers(r_m: float, s: float, u_max: float, stiffness: float, c_d: float,
                  noise_std: float = 1e-6, margin: float = 0.0,
                  period: float = 0.01, creep: bool = False) -> np.ndarray:
    """The numbers the compiled step reads (``P``), from the one definition of the dynamics.

    Parameters
    ----------
    r_m, s, u_max : float
        Mass ratio, stroke, force limit.
    stiffness, c_d : float
        The ground's ``K`` and drag number (the plan's).
    noise_std : float
        Standard deviation of one measured ground force (the estimator's).
    margin : float
        Plan for the estimate less ``margin`` standard deviations.
    period : float
        The sample period (the plan-holds check predicts the next sample).
    creep : bool
        A state whose plan ends with the body rising (:data:`CREEP`) on ground with drag
        switches to the creep law (:mod:`softlanding.control.creep`; status
        :data:`CREEP_LAW`) instead of being reported not covered (``mpc_landing`` and
        ``softlanding export-controller``'s numbers have it on; the exported C has the law
        too).
    """
    x = np.zeros(4)
    b0 = robot_rhs(x, 0.0, 0.0, r_m)
    b1 = robot_rhs(x, 1.0, 0.0, r_m)
    g1 = robot_rhs(x, 0.0, 1.0, r_m)
    P = np.zeros(NP)
    P[P_AB0], P[P_BB] = float(b0[VB]), float(b1[VB] - b0[VB])
    P[P_AF0], P[P_BF], P[P_GF] = float(b0[VF]), float(b1[VF] - b0[VF]), float(g1[VF] - b0[VF])
    P[P_K], P[P_CD], P[P_RM], P[P_S], P[P_UMAX] = stiffness, c_d, r_m, s, u_max
    P[P_HOLD0] = 1.0 / (1.0 + r_m)
    P[P_NOISE] = noise_std
    P[P_MARGIN] = margin
    P[P_BUDGET] = BUDGET
    P[P_PERIOD] = period
    P[P_WORK] = WORK
    P[P_CREEP] = 1.0 if creep else 0.0
    return P


def new_memory(tau1: float, tau2: float, prior: tuple[float, float],
               prior_std: tuple[float, float], noise_std: float) -> np.ndarray:
    """The controller's memory (``M``) before impact: the first plan and the estimator's prior.

    Parameters
    ----------
    tau1, tau2 : float
        The first plan's push and pull durations (``tau1 = 0``: pulling from the start).
    prior, prior_std : (float, float)
        The estimator's prior ``(K, c_d)`` and its standard deviations.
    noise_std : float
        Standard deviation of one measured ground force.
    """
    M = np.zeros(NM)
    M[M_PHASE] = PUSH if tau1 > 0 else PULL
    M[M_TAU1], M[M_TAU2] = tau1, tau2
    M[M_TH0], M[M_TH1] = prior
    M[M_P00] = (prior_std[0] / noise_std) ** 2
    M[M_P11] = (prior_std[1] / noise_std) ** 2
    return M


def workspace() -> tuple[np.ndarray, np.ndarray]:
    """Work arrays of the compiled step: nothing is allocated per sample, and two arrays
    (not nine) keep the call's dispatch short. ``K``: the 13 stages, then the Jacobian
    (rows 13-14); ``W``: trial state, new state, state, residuals, path and end numbers,
    body, largest ``v_f``, integrator steps left."""
    return np.zeros((15, 6)), np.zeros(33)


@njit(**JIT, inline="always")
def _views(K, W):
    return (W[0:6], W[6:12], W[12:18], K[13:15, 0:2], W[18:20], W[20:26], W[26:31],
            W[31:32], W[32:33])


@njit(**JIT, inline="always")
def _foot_acc(P, u, xf, vf):
    """The foot's acceleration under force ``u`` (``-c_d v_f |v_f|``: the law ``c_d v_f^2`` of
    a descending foot, continued past the stop as a drag, so that a guess whose pull runs
    past the stop still marches)."""
    return P[P_AF0] + P[P_BF] * u + P[P_GF] * (-P[P_K] * xf - P[P_CD] * vf * abs(vf))


@njit(**JIT)
def _rhs(P, u, y, n, out, row):
    """The foot's ``[x_f, v_f]`` (and, ``n = 6``, its transition matrix, row-major) slope."""
    xf, vf = y[0], y[1]
    out[row, 0] = vf
    out[row, 1] = _foot_acc(P, u, xf, vf)
    if n == 6:
        j10 = -P[P_GF] * P[P_K]
        j11 = -2.0 * P[P_GF] * P[P_CD] * abs(vf)
        out[row, 2] = y[4]
        out[row, 3] = y[5]
        out[row, 4] = j10 * y[2] + j11 * y[4]
        out[row, 5] = j10 * y[3] + j11 * y[5]


@njit(**JIT)
def _flow(P, u, y, n, tau, K, Yt, ynew, body, vmax, tol, left):
    """March ``y`` (the foot, ``n`` states) under force ``u`` for ``tau`` to the relative
    tolerance ``tol``, in place; track the largest ``v_f`` and the stroke's range on the
    steps' nodes (the body from ``body = [x_b, v_b, a_b, S_min, S_max]`` in closed form).
    Each step (taken or rejected) spends one of the sample's ``left[0]``. Returns
    :data:`MARCHED`, :data:`MARCH_FAILED` or :data:`SPENT` (none left: ``y`` half-marched)."""
    if tau <= 0.0:
        return MARCHED
    t = 0.0
    h = min(tau, 0.02)
    _rhs(P, u, y, n, K, np.int64(0))
    for _ in range(100000):
        if left[0] <= 0.0:
            return SPENT
        left[0] -= 1.0
        if t + h >= tau:
            h = tau - t
        for s in range(1, 12):
            for i in range(n):
                acc = 0.0
                for j in range(s):
                    a = DA[s, j]
                    if a != 0.0:
                        acc += a * K[j, i]
                Yt[i] = y[i] + h * acc
            _rhs(P, u, Yt, n, K, s)
        for i in range(n):
            acc = 0.0
            for j in range(12):
                acc += DB[j] * K[j, i]
            ynew[i] = y[i] + h * acc
        _rhs(P, u, ynew, n, K, np.int64(12))
        e5 = 0.0
        e3 = 0.0
        for i in range(n):
            sc = tol + tol * max(abs(y[i]), abs(ynew[i]))
            a5 = 0.0
            a3 = 0.0
            for j in range(13):
                a5 += DE5[j] * K[j, i]
                a3 += DE3[j] * K[j, i]
            e5 += (a5 / sc) ** 2
            e3 += (a3 / sc) ** 2
        den = e5 + 0.01 * e3
        err = 0.0 if den == 0.0 else abs(h) * e5 / math.sqrt(den * n)
        if not math.isfinite(err):
            return MARCH_FAILED
        if err <= 1.0:
            t += h
            for i in range(n):
                y[i] = ynew[i]
                K[0, i] = K[12, i]
            xb = body[0] + body[1] * t + 0.5 * body[2] * t * t
            stroke = xb - y[0]
            body[3] = min(body[3], stroke)
            body[4] = max(body[4], stroke)
            vmax[0] = max(vmax[0], y[1])
            if t >= tau:
                return MARCHED
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0))
            h = h * fac
        else:
            h = h * max(0.2, 0.9 * err ** (-1.0 / 8.0))
        if h < 1e-14 * (1.0 + tau):
            return MARCH_FAILED
    return MARCH_FAILED


@njit(**JIT)
def _arrest(P, xb, vb, xf):
    """The arrest condition at the foot's stop (>= 0: the crater holds the body's arrest)."""
    S = xb - xf
    c = P[P_RM] / (1.0 + P[P_RM])
    return S * (P[P_K] * (-xf) - P[P_HOLD0]) - c * (S + 0.5 * vb * vb)


@njit(**JIT)
def _plan(P, x, tau1, tau2, K, Yt, ynew, y, J, r, lim, body, vmax, jac, tol, left):
    """Residuals ``r`` (and, ``jac``, their Jacobian ``J`` in ``(tau1, tau2)``) of the plan
    ``(tau1, tau2)`` from ``x``, the arcs marched to ``tol``; ``lim`` gets ``[max v_f before
    the stop, S_min, S_max]``. :data:`MARCHED`, or the march's failure or :data:`SPENT`."""
    umax = P[P_UMAX]
    a1 = P[P_AB0] + P[P_BB] * umax
    a2 = P[P_AB0] - P[P_BB] * umax
    vmax[0] = -np.inf
    S0 = x[0] - x[2]
    body[0], body[1], body[2], body[3], body[4] = x[0], x[1], a1, S0, S0
    y[0], y[1] = x[2], x[3]
    st = _flow(P, umax, y, 2, tau1, K, Yt, ynew, body, vmax, tol, left)
    if st != MARCHED:
        return st
    xf1, vf1 = y[0], y[1]
    acc1 = _foot_acc(P, umax, xf1, vf1)
    xb1 = x[0] + x[1] * tau1 + 0.5 * a1 * tau1 * tau1
    vb1 = x[1] + a1 * tau1
    y[2], y[3], y[4], y[5] = 1.0, 0.0, 0.0, 1.0
    body[0], body[1], body[2] = xb1, vb1, a2
    vmax[0] = max(vmax[0], vf1)
    vmax_push = vmax[0]
    st = _flow(P, -umax, y, 6, tau2, K, Yt, ynew, body, vmax, tol, left)
    if st != MARCHED:
        return st
    xfT, vfT = y[0], y[1]
    xbT = xb1 + vb1 * tau2 + 0.5 * a2 * tau2 * tau2
    vbT = vb1 + a2 * tau2
    r[0] = vfT
    r[1] = _arrest(P, xbT, vbT, xfT)
    lim[0] = vmax_push
    lim[1], lim[2] = body[3], body[4]
    lim[3], lim[4], lim[5] = xbT, vbT, xfT
    if not jac:
        return MARCHED
    accT = _foot_acc(P, -umax, xfT, vfT)
    # d/dtau1 (tau2 fixed): the pull arc's transition matrix on the push's slope at the switch
    dxf1 = y[2] * vf1 + y[3] * acc1
    dvf1 = y[4] * vf1 + y[5] * acc1
    dxb1 = vb1 + a1 * tau2
    dvb1 = a1
    # d/dtau2: the pull's slope at the stop
    dxf2, dvf2, dxb2, dvb2 = vfT, accT, vbT, a2
    S = xbT - xfT
    c = P[P_RM] / (1.0 + P[P_RM])
    hold = P[P_K] * (-xfT) - P[P_HOLD0]
    J[0, 0], J[0, 1] = dvf1, dvf2
    J[1, 0] = (dxb1 - dxf1) * hold - S * P[P_K] * dxf1 - c * ((dxb1 - dxf1) + vbT * dvb1)
    J[1, 1] = (dxb2 - dxf2) * hold - S * P[P_K] * dxf2 - c * ((dxb2 - dxf2) + vbT * dvb2)
    return MARCHED


@njit(**JIT)
def _converged(d, prev, scale):
    """Newton has converged: its last whole step ``d`` (at :data:`RTOL`) is below
    :data:`NEWTON_TOL` of ``scale``, or, in the quadratic regime (``d`` below
    :data:`TIGHTEN`), the next one would be: ``d^3 / prev^2``, the rate ``d / prev^2`` from
    the step before, ``prev`` (``< 0``: none). The iterate's error is then about that next
    step; the step that would only confirm it, and its arcs, are saved."""
    if d <= NEWTON_TOL * scale:
        return True
    return prev > 0.0 and d <= TIGHTEN * scale and d * d * d <= NEWTON_TOL * scale * prev * prev


@njit(**JIT)
def _solve_push(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left, budget):
    """Newton on ``(tau1, tau2)`` from ``M``'s (already shifted) plan, at most ``budget``
    iterations and ``left[0]`` integrator steps; the status (:data:`CONVERGING`: the
    budget ran out, the iterate is kept; :data:`DEFERRED`: the steps ran out, the last whole
    iterate is kept, the sample counted in ``M_DEFERRED``, the next sample goes on from
    there)."""
    t1, t2 = M[M_TAU1], M[M_TAU2]
    converged = False
    prev = -1.0  # the last whole step of this call (none yet)
    for it in range(budget):
        M[M_ITER] = it + 1
        # (the arcs to LOOSE_RTOL while Newton's steps are far larger than its error)
        tight = M[M_LAST_STEP] <= TIGHTEN * (1.0 + abs(t1) + t2)
        st = _plan(P, x, t1, t2, K, Yt, ynew, y, J, r, lim, body, vmax, np.bool_(True),
                   RTOL if tight else LOOSE_RTOL, left)
        if st == SPENT:
            M[M_DEFERRED] += 1
            if t1 > 0.0:
                M[M_TAU1], M[M_TAU2] = t1, t2
            return DEFERRED
        if st != MARCHED:
            return NEWTON_FAILED
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        if det == 0.0 or not math.isfinite(det):
            return NEWTON_FAILED
        d1 = (J[1, 1] * r[0] - J[0, 1] * r[1]) / det
        d2 = (J[0, 0] * r[1] - J[1, 0] * r[0]) / det
        # damped: no duration more than halved by one step (a far guess)
        lam = 1.0
        if t2 - d2 < 0.5 * t2:
            lam = min(lam, 0.5 * t2 / d2)
        if t1 > 0 and t1 - d1 < -0.5 * t1 - 0.05 * t2:
            lam = min(lam, (1.5 * t1 + 0.05 * t2) / d1)
        t1 -= lam * d1
        t2 -= lam * d2
        M[M_LAST_STEP] = abs(lam * d1) + abs(lam * d2)
        if not (t2 > 0.0 and math.isfinite(t1) and math.isfinite(t2)):
            return NEWTON_FAILED
        if tight and lam == 1.0 and _converged(abs(d1) + abs(d2), prev, 1.0 + abs(t1) + t2):
            converged = True
            break
        # (a loose step as well: its arcs' error only makes it larger, the rate d / prev^2
        # then over-estimated, the test stricter)
        prev = abs(d1) + abs(d2) if lam == 1.0 else -1.0
    if not converged:
        if t1 > 0.0:
            M[M_TAU1], M[M_TAU2] = t1, t2
            return CONVERGING
        if budget < MAX_NEWTON:
            return NEWTON_FAILED
        # to convergence, near the switch: the damping held back a switch overdue by more
        # than half the push left (an estimate that stiffened); as a converged one
    if t1 < 0.0:  # the switch is due already: pull from now, if the arrest then holds
        M[M_PHASE] = PULL
        return _solve_pull(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    M[M_TAU1], M[M_TAU2] = t1, t2
    M[M_XBT], M[M_VBT], M[M_XFT] = lim[3], lim[4], lim[5]
    if lim[0] > 1e-9 * (1.0 + abs(x[3])) or lim[1] < -1e-9 or lim[2] > P[P_S] * (1 + 1e-9):
        return PATH_LIMIT
    if lim[4] >= 0.0:  # the body rises at the foot's stop: a creep (the arrest's other root)
        return CREEP
    return OK


@njit(**JIT)
def _solve_pull(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left):
    """Newton on ``tau2`` for ``v_f = 0`` (the foot's stop) pulling from ``x``; the arrest
    condition then checked; the status (:data:`DEFERRED`: the integrator steps ``left[0]``
    ran out, the last whole iterate kept, the sample counted in ``M_DEFERRED``)."""
    t2 = M[M_TAU2]
    umax = P[P_UMAX]
    prev = -1.0  # the last whole step (none yet)
    for it in range(MAX_NEWTON):
        M[M_ITER] = it + 1
        st = _plan(P, x, 0.0, t2, K, Yt, ynew, y, J, r, lim, body, vmax, np.bool_(False), RTOL,
                   left)
        if st == SPENT:
            M[M_DEFERRED] += 1
            M[M_TAU1], M[M_TAU2] = 0.0, t2
            return DEFERRED
        if st != MARCHED:
            return NEWTON_FAILED
        acc = _foot_acc(P, -umax, y[0], y[1])
        if not acc > 0.0:
            return NEWTON_FAILED
        d = r[0] / acc
        whole = True
        if t2 - d < 0.5 * t2:
            d = 0.5 * t2
            whole = False
        t2 -= d
        if whole and _converged(abs(d), prev, 1.0 + t2):
            break
        prev = abs(d) if whole else -1.0
    else:
        return NEWTON_FAILED
    M[M_TAU1], M[M_TAU2] = 0.0, t2
    M[M_XBT], M[M_VBT], M[M_XFT] = lim[3], lim[4], lim[5]
    if lim[4] >= 0.0:  # the body rises at the foot's stop: a creep (the arrest's other root)
        return CREEP
    if r[1] < -1e-9 * (1.0 + abs(x[0] - x[2])):
        return ARREST_FAILS
    return OK


@njit(**JIT)
def _estimate(P, M, x, a_f, u):
    """One recursive least-squares update of ``(K, c_d)`` from a yielding foot's measured
    acceleration (as :meth:`GroundEstimator.update`)."""
    p0, p1 = -x[2], x[3] * x[3]
    y = (a_f - P[P_AF0] - P[P_BF] * u) / P[P_GF]
    q00, q01, q11 = M[M_P00], M[M_P01], M[M_P11]
    pp0 = q00 * p0 + q01 * p1
    pp1 = q01 * p0 + q11 * p1
    den = 1.0 + p0 * pp0 + p1 * pp1
    k0, k1 = pp0 / den, pp1 / den
    e = y - (p0 * M[M_TH0] + p1 * M[M_TH1])
    M[M_TH0] += k0 * e
    M[M_TH1] += k1 * e
    M[M_P00] = q00 - k0 * pp0
    M[M_P01] = q01 - k0 * pp1
    M[M_P11] = q11 - k1 * pp1
    M[M_SAMPLES] += 1


@njit(**JIT)
def _creep(P, M, x):
    """The creep law's force from ``x`` on the planned ground into ``M[M_UCREEP]``, the phase
    :data:`CREEPING`; :data:`CREEP_LAW`, or :data:`CREEP` where the law does not apply (no
    drag estimated: not covered)."""
    u = creep_force(P[P_AF0], P[P_BF], P[P_GF], P[P_AB0], P[P_BB], P[P_UMAX], P[P_HOLD0],
                    P[P_K], P[P_CD], x, P[P_PERIOD])
    M[M_ITER] = 0
    if not math.isfinite(u):
        M[M_STATUS] = CREEP
        return CREEP
    M[M_PHASE] = CREEPING
    M[M_UCREEP] = stroke_guard(P, x, u)
    M[M_STATUS] = CREEP_LAW
    return CREEP_LAW


@njit(**JIT)
def _approach_limit(dist, vel, h, decel):
    """The largest constant acceleration towards a limit ``dist`` away (approached at
    ``vel``) over a sample ``h`` after which the approach still stops short of it at
    ``decel``: the end speed ``w`` meets ``dist >= h (vel + w) / 2 + max(w, 0)^2 / (2 decel)``
    (receding by the end, ``w < 0``, when even stopping at the end is too late). No limit
    (``inf``) without a deceleration to stop by (``decel <= 0``: a force limit not above the
    body's weight)."""
    if not decel > 0.0:
        return np.inf
    c = dist - 0.5 * h * vel
    if c >= 0.0:
        w = decel * (math.sqrt(0.25 * h * h + 2.0 * c / decel) - 0.5 * h)
    else:
        w = 2.0 * c / h
    return (w - vel) / h


@njit(**ENTRY)
def stroke_guard(P, x, u):
    """The creep law's force ``u`` (held over a sample) limited so that the leg's extension
    (or compression) can still stop at half the body's own relative deceleration under the
    force limit (pulled extending, pushed compressing: the foot may rest) before the stroke
    leaves ``[m, s - m]`` (``m = STROKE_MARGIN s``; :func:`_approach_limit`): the law plans
    the foot only. The relative acceleration is affine in ``u`` (the yielding foot's
    included; a resting foot is taken to stay at rest, which a push beyond the crater's hold
    makes optimistic). A safety net, not a plan: a law that turns in time is untouched; where
    both limits cannot hold, the compression's wins, and the force limit over both."""
    S, V = x[0] - x[2], x[1] - x[3]
    m = STROKE_MARGIN * P[P_S]
    h, ab0, bb, umax = P[P_PERIOD], P[P_AB0], P[P_BB], P[P_UMAX]
    a0, slope = ab0, bb
    if x[3] < 0.0:
        a0 -= _foot_acc(P, 0.0, x[2], x[3])
        slope -= P[P_BF]
    top = _approach_limit(P[P_S] - m - S, V, h, 0.5 * (bb * umax - ab0))
    if a0 + slope * u > top:
        u = (top - a0) / slope
    floor = _approach_limit(S - m, -V, h, 0.5 * (ab0 + bb * umax))
    if -(a0 + slope * u) > floor:
        u = (-floor - a0) / slope
    return min(umax, max(-umax, u))


@njit(**JIT)
def _predict(P, x, M, K, Yt, ynew, y, body, vmax, left):
    """The state the plan in ``M`` predicts after the next sample from ``x``, for the
    plan-holds check (none if that sample ends at the foot's stop, or the integrator steps
    ``left[0]`` run out: the next sample then re-solves)."""
    t1 = M[M_TAU1] if M[M_PHASE] == PUSH else 0.0
    hn = P[P_PERIOD]
    if hn >= t1 + M[M_TAU2]:
        return
    umax = P[P_UMAX]
    a1 = P[P_AB0] + P[P_BB] * umax
    a2 = P[P_AB0] - P[P_BB] * umax
    tp = min(hn, t1)
    y[0], y[1] = x[2], x[3]
    body[0], body[1], body[2], body[3], body[4] = x[0], x[1], a1, 0.0, 0.0
    if _flow(P, umax, y, 2, tp, K, Yt, ynew, body, vmax, RTOL, left) != MARCHED:
        return
    xb = x[0] + x[1] * tp + 0.5 * a1 * tp * tp
    vb = x[1] + a1 * tp
    tq = hn - tp
    body[0], body[1], body[2] = xb, vb, a2
    if _flow(P, -umax, y, 2, tq, K, Yt, ynew, body, vmax, RTOL, left) != MARCHED:
        return
    M[M_PRED], M[M_PRED + 1] = xb + vb * tq + 0.5 * a2 * tq * tq, vb + a2 * tq
    M[M_PRED + 2], M[M_PRED + 3] = y[0], y[1]
    M[M_KPLAN], M[M_CPLAN] = P[P_K], P[P_CD]
    M[M_PRED_OK] = 1.0


@njit(**ENTRY)
def solve_plan(P, M, x, K, W, work=np.inf):
    """The plan in ``M`` re-solved from ``x`` for the ground in ``P``, Newton to convergence
    (no estimate, no shift); the status.

    Parameters
    ----------
    P, M : arrays
        :func:`robot_numbers`, :func:`new_memory` (its durations the guess).
    x : array of 4
        The state.
    K, W : arrays
        :func:`workspace`.
    work : float
        Most integrator steps (default: no bound, as before the impact); with a bound, the
        steps taken are added to ``M[M_WORK]`` and a solve that runs out returns
        :data:`DEFERRED`.
    """
    Yt, ynew, y, J, r, lim, body, vmax, left = _views(K, W)
    left[0] = work
    if M[M_PHASE] == PUSH:
        st = _solve_push(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left, MAX_NEWTON)
    else:
        st = _solve_pull(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    if work < np.inf:
        M[M_WORK] += work - left[0]
    return st


@njit(**ENTRY)
def control_step(P, M, x, a_f, u, h, estimate, K, W):
    """One sample of the controller, compiled: the estimate updated from the measurement
    (``estimate``), the plan shifted by the sample ``h`` just applied and re-solved from
    ``x`` for the estimated ground, in at most ``P[P_WORK]`` integrator steps (``M_WORK``
    says how many). Returns the status (:data:`OK` or why not covered); the plan is in
    ``M``.

    Parameters
    ----------
    P : array
        :func:`robot_numbers` (its ``K``, ``c_d`` are overwritten by the estimate).
    M : array
        :func:`new_memory`, updated in place.
    x : array of 4
        The measured state.
    a_f, u : float
        The measured foot acceleration and the force the sample ended under.
    h : float
        The sample just applied.
    estimate : bool
        Update the estimate (else keep the ground in ``P``).
    K, W : arrays
        :func:`workspace`.
    """
    Yt, ynew, y, J, r, lim, body, vmax, left = _views(K, W)
    left[0] = P[P_WORK]
    st = _step(P, M, x, a_f, u, h, estimate, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    M[M_WORK] = P[P_WORK] - left[0]
    return st


@njit(**JIT, inline="always")  # (a call would pass its nine arrays, refcounted)
def _step(P, M, x, a_f, u, h, estimate, K, Yt, ynew, y, J, r, lim, body, vmax, left):
    """:func:`control_step` on the views of its work arrays."""
    k_was, c_was = P[P_K], P[P_CD]
    if estimate and x[3] < 0.0:
        _estimate(P, M, x, a_f, u)
        if M[M_SAMPLES] >= 2:  # as the re-planning MPC: two samples before the fit is used
            m = P[P_MARGIN] * P[P_NOISE]
            # (at most half the estimate off: while it is still far from the truth, the
            # first samples', a plan for K - m sigma_K near 0 is far from any landing)
            P[P_K] = max(max(M[M_TH0] - m * math.sqrt(max(M[M_P00], 0.0)), 0.5 * M[M_TH0]),
                         1e-3)
            P[P_CD] = max(M[M_TH1] - m * math.sqrt(max(M[M_P11], 0.0)), 0.0)
    # a ground that moved: the last Newton step no longer says how far the plan is
    if abs(P[P_K] - k_was) > TIGHTEN * k_was or abs(P[P_CD] - c_was) > TIGHTEN * max(1.0, c_was):
        M[M_LAST_STEP] = np.inf
    # the sample went as the converged plan predicted, on the ground it was planned for,
    # which is still the estimate: by the principle of optimality its rest is still optimal
    holds = M[M_PRED_OK] == 1.0 and abs(P[P_K] - M[M_KPLAN]) <= PLAN_HOLDS_TOL * M[M_KPLAN] \
        and abs(P[P_CD] - M[M_CPLAN]) <= PLAN_HOLDS_TOL * max(1.0, M[M_CPLAN])
    if holds:
        scale = 1.0
        for i in range(4):
            scale = max(scale, abs(x[i]))
        for i in range(4):
            if abs(x[i] - M[M_PRED + i]) > PLAN_HOLDS_TOL * scale:
                holds = False
    M[M_PRED_OK] = 0.0
    if M[M_PHASE] == CREEPING:  # (feedback every sample to the foot's stop)
        return _creep(P, M, x)
    # the creep law reaches the static depth, the least any landing can: it takes over
    # (judged on the ground CREEP_SIGMAS standard deviations stiffer and less draggy: a
    # shallower static depth, less drag to spend the momentum)
    if P[P_CREEP] == 1.0 and M[M_SAMPLES] >= 2:
        k_hi = M[M_TH0] + CREEP_SIGMAS * P[P_NOISE] * math.sqrt(max(M[M_P00], 0.0))
        c_lo = M[M_TH1] - CREEP_SIGMAS * P[P_NOISE] * math.sqrt(max(M[M_P11], 0.0))
        if creep_reachable(P[P_AF0], P[P_BF], P[P_GF], P[P_AB0], P[P_BB], P[P_UMAX],
                           P[P_HOLD0], k_hi, c_lo, x):
            # (not where the planned ground, the margin's, has no drag left for the law:
            # the bang-bang plan goes on)
            if _creep(P, M, x) == CREEP_LAW:
                return CREEP_LAW
    if M[M_PHASE] == PUSH:
        if M[M_TAU1] > h:
            M[M_TAU1] -= h
            if holds:
                M[M_ITER] = 0
                _predict(P, x, M, K, Yt, ynew, y, body, vmax, left)
                M[M_STATUS] = HOLDS
                return HOLDS
            # a real-time iteration: a few Newton steps per sample while the switch is far
            # (the next samples go on converging), to convergence when it is near
            budget = int(P[P_BUDGET]) if M[M_TAU1] > 3.0 * h else MAX_NEWTON
            st = _solve_push(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left, budget)
            # (a run of large Newton steps: with noisy measurements the estimate moves every
            # sample, and the plan with it, by less than this)
            far = st == CONVERGING and M[M_LAST_STEP] > 0.1 * P[P_PERIOD]
            if st != DEFERRED:  # (a deferred sample counts neither way)
                M[M_UNCONVERGED] = M[M_UNCONVERGED] + 1 if far else 0
            if M[M_UNCONVERGED] > MAX_UNCONVERGED:
                st = NEWTON_FAILED
            if st == OK:
                _predict(P, x, M, K, Yt, ynew, y, body, vmax, left)
            M[M_STATUS] = st
            if st == CREEP and P[P_CREEP] == 1.0:
                return _creep(P, M, x)
            return st
        # the switch fell within the sample
        M[M_TAU2] = max(M[M_TAU2] - (h - M[M_TAU1]), 1e-3 * M[M_TAU2])
        M[M_PHASE] = PULL
    else:
        M[M_TAU2] = max(M[M_TAU2] - h, 1e-3 * M[M_TAU2])
    if holds:
        M[M_ITER] = 0
        _predict(P, x, M, K, Yt, ynew, y, body, vmax, left)
        M[M_STATUS] = HOLDS
        return HOLDS
    st = _solve_pull(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    if st == OK:
        _predict(P, x, M, K, Yt, ynew, y, body, vmax, left)
    M[M_STATUS] = st
    if st == CREEP and P[P_CREEP] == 1.0:
        return _creep(P, M, x)
    return st


__all__ = ["ARREST_FAILS", "BUDGET", "CONVERGING", "CREEP", "CREEPING", "CREEP_LAW", "CREEP_SIGMAS",
           "DEFERRED", "HOLDS", "LOOSE_RTOL",
           "MARCHED", "MARCH_FAILED", "MAX_NEWTON", "MAX_UNCONVERGED", "NEWTON_FAILED",
           "NEWTON_TOL", "OK", "PATH_LIMIT", "PLAN_HOLDS_TOL", "PULL", "PUSH", "RTOL", "SPENT",
           "TIGHTEN", "WORK", "STATUS_NAMES", "control_step",
           "force_coefficients", "ground_force_noise", "new_memory", "robot_numbers",
           "solve_plan", "STROKE_MARGIN", "stroke_guard", "workspace"]
