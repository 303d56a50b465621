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
turns negative beyond the switch, the arrest cannot hold, a limit on the plan's path) is met
by the compiled fallback in the same call (:mod:`softlanding.control.fallback`: the plan kept
with the margin dropped, the creep law, or the safe brake), within the sample's bound.

The arrays' layout, phases, statuses and tolerances are
:mod:`softlanding.control.bangbang_layout`'s (every name re-exported here).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.control import bangbang_layout
from softlanding.control.bangbang_layout import (  # noqa: F401 (re-exported: bangbang.X)
    ARREST_FAILS,
    BODY_DECEL,
    BRAKE,
    BRAKING,
    BUDGET,
    CONVERGING,
    CREEP,
    CREEP_LAW,
    CREEP_SIGMAS,
    CREEPING,
    DEFERRED,
    FILTERED_REGRESSOR,
    HOLDS,
    KEPT,
    LOOSE_RTOL,
    M_CPLAN,
    M_DEFERRED,
    M_FALLBACKS,
    M_ITER,
    M_KPLAN,
    M_LAST_STEP,
    M_P00,
    M_P01,
    M_P11,
    M_PHASE,
    M_PRED,
    M_PRED_OK,
    M_SAMPLES,
    M_STATUS,
    M_TAU1,
    M_TAU2,
    M_TH0,
    M_TH1,
    M_UCREEP,
    M_UNCONVERGED,
    M_VBT,
    M_WHY,
    M_WORK,
    M_XBT,
    M_XFT,
    MARCH_FAILED,
    MARCHED,
    MAX_NEWTON,
    MAX_UNCONVERGED,
    NEWTON_FAILED,
    NEWTON_TOL,
    NM,
    NP,
    OK,
    P_AB0,
    P_AF0,
    P_BB,
    P_BF,
    P_BUDGET,
    P_CD,
    P_CREEP,
    P_GF,
    P_HOLD0,
    P_K,
    P_MARGIN,
    P_NOISE,
    P_PERIOD,
    P_RM,
    P_S,
    P_UMAX,
    P_WORK,
    PATH_LIMIT,
    PLAN_HOLDS_TOL,
    PULL,
    PUSH,
    RTOL,
    SPENT,
    STATUS_NAMES,
    STROKE_MARGIN,
    TIGHTEN,
    WORK,
    foot_acc,
    force_coefficients,
    ground_force_noise,
    new_memory,
    robot_numbers,
    workspace,
)
from softlanding.control.creep import creep_reachable
from softlanding.control.fallback import brake, creep_phase, fallback, stroke_guard
from softlanding.simulation.kernel.const import ENTRY, JIT
from softlanding.simulation.kernel.dop853 import E3 as DE3
from softlanding.simulation.kernel.dop853 import E5 as DE5
from softlanding.simulation.kernel.dop853 import A as DA
from softlanding.simulation.kernel.dop853 import B as DB


@njit(**JIT, inline="always")
def _views(K, W):
    return (W[0:6], W[6:12], W[12:18], K[13:15, 0:2], W[18:20], W[20:26], W[26:31],
            W[31:32], W[32:33])


@njit(**JIT)
def _rhs(P, u, y, n, out, row):
    """The foot's ``[x_f, v_f]`` (and, ``n = 6``, its transition matrix, row-major) slope."""
    xf, vf = y[0], y[1]
    out[row, 0] = vf
    out[row, 1] = foot_acc(P, u, xf, vf)
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
def _arrest_too_strong(P, xb, vb, xf):
    """The body's arrest after the foot's stop needs more than the force limit: the constant
    force ``u_b`` that stops it in the stroke left exceeds ``u_max`` (the landing OCP's
    ``ARREST_FORCE``, ``S u_max - u_b S >= 0``, to ``1e-9``). Where the crater holds the
    arrest (the pull's plan, checked after :data:`ARREST_FAILS`) the schedule would hold
    ``u_max`` over a foot at rest and the body fall through the stroke's lower limit: a limit
    on the plan's path beyond the arcs' (whose check ends at the foot's stop). (Not checked
    on a push's plan, whose arrest is active, ``u_b`` the crater's hold: the study's
    landings whose first plans broke it landed within the limits, 0.1 % from the optimum,
    as the estimate moved the plan; the fallback from the impact was 14-48 % deeper.)"""
    S = xb - xf
    c = P[P_RM] / (1.0 + P[P_RM])
    return c * (S + 0.5 * vb * vb) - S * P[P_UMAX] > 1e-9 * (1.0 + abs(S)) * P[P_UMAX]


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
    st = _flow(P, umax, y, np.int64(2), tau1, K, Yt, ynew, body, vmax, tol, left)
    if st != MARCHED:
        return st
    xf1, vf1 = y[0], y[1]
    acc1 = foot_acc(P, umax, xf1, vf1)
    xb1 = x[0] + x[1] * tau1 + 0.5 * a1 * tau1 * tau1
    vb1 = x[1] + a1 * tau1
    y[2], y[3], y[4], y[5] = 1.0, 0.0, 0.0, 1.0
    body[0], body[1], body[2] = xb1, vb1, a2
    vmax[0] = max(vmax[0], vf1)
    vmax_push = vmax[0]
    st = _flow(P, -umax, y, np.int64(6), tau2, K, Yt, ynew, body, vmax, tol, left)
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
    accT = foot_acc(P, -umax, xfT, vfT)
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
        acc = foot_acc(P, -umax, y[0], y[1])
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
    if _arrest_too_strong(P, lim[3], lim[4], lim[5]):  # (the crater holds: not covered)
        return PATH_LIMIT
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
    if _flow(P, umax, y, np.int64(2), tp, K, Yt, ynew, body, vmax, RTOL, left) != MARCHED:
        return
    xb = x[0] + x[1] * tp + 0.5 * a1 * tp * tp
    vb = x[1] + a1 * tp
    tq = hn - tp
    body[0], body[1], body[2] = xb, vb, a2
    if _flow(P, -umax, y, np.int64(2), tq, K, Yt, ynew, body, vmax, RTOL, left) != MARCHED:
        return
    M[M_PRED], M[M_PRED + 1] = xb + vb * tq + 0.5 * a2 * tq * tq, vb + a2 * tq
    M[M_PRED + 2], M[M_PRED + 3] = y[0], y[1]
    M[M_KPLAN], M[M_CPLAN] = P[P_K], P[P_CD]
    M[M_PRED_OK] = 1.0


@njit(**JIT)
def _settled(st, P, x, M, K, Yt, ynew, y, body, vmax, left):
    """A sample's end after a Newton solve of status ``st``: the next sample's prediction
    when it converged, the status recorded, the creep law where the plan gives way to it;
    the sample's status."""
    if st == OK:
        _predict(P, x, M, K, Yt, ynew, y, body, vmax, left)
    M[M_STATUS] = st
    if st == CREEP and P[P_CREEP] == 1.0:
        return creep_phase(P, M, x)
    return st


@njit(**ENTRY)
def solve_plan(P, M, x, K, W, work):
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
        Most integrator steps (``np.inf``: no bound, as before the impact); with a bound, the
        steps taken are added to ``M[M_WORK]`` and a solve that runs out returns
        :data:`DEFERRED`. Always given, as a float: one compiled signature for every caller
        (a default, omitted, was a second compile of the whole solve).
    """
    Yt, ynew, y, J, r, lim, body, vmax, left = _views(K, W)
    left[0] = work
    if M[M_PHASE] == PUSH:
        st = _solve_push(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left,
                         np.int64(MAX_NEWTON))  # (as the step passes it: one compile)
    else:
        st = _solve_pull(P, x, M, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    if work < np.inf:
        M[M_WORK] += work - left[0]
    return st


@njit(**ENTRY)
def structure_step(P, M, x, a_f, u, h, estimate, K, W):
    """:func:`control_step` without the fallback (the filtered step's recovery comes before
    it), its arguments the same: the status (:data:`OK`, or why the structure does not
    cover the state)."""
    Yt, ynew, y, J, r, lim, body, vmax, left = _views(K, W)
    left[0] = P[P_WORK]
    st = _step(P, M, x, a_f, u, h, estimate, K, Yt, ynew, y, J, r, lim, body, vmax, left)
    M[M_WORK] = P[P_WORK] - left[0]
    return st


@njit(**ENTRY)
def control_step(P, M, x, a_f, u, h, estimate, K, W):
    """One sample of the controller, compiled: the estimate updated from the measurement
    (``estimate``), the plan shifted by the sample ``h`` just applied and re-solved from
    ``x`` for the estimated ground, in at most ``P[P_WORK]`` integrator steps (``M_WORK``
    says how many). Where that structure does not cover the state, the fallback acts in the
    same call (:func:`~softlanding.control.fallback.fallback`: the plan kept with the margin
    dropped, the creep law or the safe brake). Returns the status; the plan (or the force)
    is in ``M``.

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
    # (:func:`structure_step` called, not its body inlined a second time: the compiled
    # controller, the filtered sample and this step share one compiled step)
    return fallback(P, M, x, structure_step(P, M, x, a_f, u, h, estimate, K, W))


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
        return creep_phase(P, M, x)
    if M[M_PHASE] == BRAKING:  # (the fallback's brake, every sample to the foot's stop)
        return brake(P, M, x)
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
            if creep_phase(P, M, x) == CREEP_LAW:
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
            return _settled(st, P, x, M, K, Yt, ynew, y, body, vmax, left)
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
    return _settled(st, P, x, M, K, Yt, ynew, y, body, vmax, left)


__all__ = [*bangbang_layout.__all__, "control_step", "solve_plan", "structure_step",
           "stroke_guard"]
