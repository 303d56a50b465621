"""Exact future ranges of a linear functional in the static mode (the rest proof).

With the foot pinned at the crater bottom only the body moves:
``x_b' = v_b``, ``v_b' = alpha x_b + beta v_b + gamma``. A functional
``q = c . z`` is then ``p1 x_b + p2 v_b + p0`` and its range over all future
time has a closed form: a damped oscillation (turning points alternate and
shrink, so the first two bound the future), an over-damped motion (at most one
turning point, then a limit), pure damping without stiffness (drift at a
terminal velocity) or constant acceleration (a parabola).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import JIT, SMALL
from softlanding.simulation.kernel.linalg import hull


@njit(**JIT)
def _range_underdamped(w0, w1, beta, disc):
    """Range over t >= 0 of a damped oscillation ``w`` with ``w(0) = w0``, ``w'(0) = w1``."""
    lo, hi = w0, w0
    a = 0.5 * beta
    om = 0.5 * math.sqrt(-disc)
    Bc = (w1 - a * w0) / om
    P = a * w0 + om * Bc
    Qs = a * Bc - om * w0
    phi = math.atan2(Qs, P)
    t1 = ((phi + 0.5 * math.pi) % math.pi) / om
    for k in range(3):
        tk = t1 + k * math.pi / om
        wk = math.exp(a * tk) * (w0 * math.cos(om * tk) + Bc * math.sin(om * tk))
        lo, hi = hull(lo, hi, wk)
    return lo, hi


@njit(**JIT)
def _range_overdamped(w0, w1, beta, disc):
    """Range over t >= 0 of an over-damped (or critically damped) decay to 0."""
    lo, hi = w0, w0
    lo, hi = hull(lo, hi, 0.0)
    sq = math.sqrt(max(disc, 0.0))
    l1, l2 = 0.5 * (beta + sq), 0.5 * (beta - sq)
    if sq <= 1e-7 * abs(beta):
        lam = 0.5 * beta
        C1, C2 = w0, w1 - lam * w0
        if C2 != 0.0:
            ts = -(C2 + lam * C1) / (lam * C2)
            if ts > 0.0:
                lo, hi = hull(lo, hi, (C1 + C2 * ts) * math.exp(lam * ts))
    else:
        C1 = (w1 - l2 * w0) / (l1 - l2)
        C2 = w0 - C1
        if l1 * C1 != 0.0:
            ratio = -l2 * C2 / (l1 * C1)
            if ratio > 0.0:
                ts = math.log(ratio) / (l1 - l2)
                if ts > 0.0:
                    wk = C1 * math.exp(l1 * ts) + C2 * math.exp(l2 * ts)
                    lo, hi = hull(lo, hi, wk)
    return lo, hi


@njit(**JIT)
def _range_stiff(alpha, beta, gamma, xb, p1, p0, q0, q1, acc, vb):
    """Range when the body has a spring (``alpha != 0``)."""
    inf = np.inf
    if alpha > 0.0 or beta > 1e-14:
        if abs(q1) < SMALL and abs(acc) < SMALL and abs(vb) < SMALL:
            return q0, q0
        return -inf, inf
    xeq = -gamma / alpha
    qeq = p1 * xeq + p0
    w0, w1 = q0 - qeq, q1
    disc = beta * beta + 4.0 * alpha
    if disc < -1e-12 * (beta * beta + abs(alpha)):
        lo, hi = _range_underdamped(w0, w1, beta, disc)
    else:
        lo, hi = _range_overdamped(w0, w1, beta, disc)
    return qeq + lo, qeq + hi


@njit(**JIT)
def _range_damper(beta, gamma, xb, vb, p1, p2, p0, q0):
    """Range with damping but no spring: drift toward a terminal velocity."""
    inf = np.inf
    veq = -gamma / beta
    dv = vb - veq
    drift = p1 * veq
    lim_x = xb + dv / (-beta)
    if abs(drift) > SMALL:
        lo, hi = q0, q0
        k = (p1 + p2 * beta) * dv
        if k != 0.0:
            e = -drift / k
            if 0.0 < e < 1.0:
                ts = math.log(e) / beta
                qs = p1 * (xb + veq * ts + dv * (1.0 - e) / (-beta)) + p2 * (veq + dv * e) + p0
                lo, hi = hull(lo, hi, qs)
        if drift > 0.0:
            return lo, inf
        return -inf, hi
    qinf = p1 * lim_x + p2 * veq + p0
    return min(q0, qinf), max(q0, qinf)


@njit(**JIT)
def _range_parabola(gamma, vb, p1, p2, q0):
    """Range under constant acceleration: ``q = q0 + a1 t + a2 t^2``."""
    inf = np.inf
    a2 = 0.5 * p1 * gamma
    a1 = p1 * vb + p2 * gamma
    if abs(a2) > SMALL:
        tv = -a1 / (2.0 * a2)
        qv = q0 + a1 * tv + a2 * tv * tv if tv > 0.0 else q0
        if a2 > 0.0:
            return min(q0, qv), inf
        return -inf, max(q0, qv)
    if abs(a1) > SMALL:
        if a1 > 0.0:
            return q0, inf
        return -inf, q0
    return q0, q0


@njit(**JIT)
def future_range(A, z, c):
    """Exact range ``(lo, hi)`` of ``q(t) = c . z(t)`` over ``t >= 0`` in the static mode.

    Parameters
    ----------
    A : (5, 5) array
        Closed-loop static-mode matrix (foot rows zero).
    z : (5,) array
        Current augmented state.
    c : (5,) array
        The functional.

    Returns
    -------
    lo, hi : float
        Possibly infinite.
    """
    alpha, beta = A[1, 0], A[1, 1]
    gamma = A[1, 2] * z[2] + A[1, 3] * z[3] + A[1, 4]
    xb, vb = z[0], z[1]
    p1, p2 = c[0], c[1]
    p0 = c[2] * z[2] + c[3] * z[3] + c[4]
    q0 = p1 * xb + p2 * vb + p0
    acc = alpha * xb + beta * vb + gamma
    q1 = p1 * vb + p2 * acc
    if abs(alpha) > 1e-14:
        return _range_stiff(alpha, beta, gamma, xb, p1, p0, q0, q1, acc, vb)
    if beta < -1e-14:
        return _range_damper(beta, gamma, xb, vb, p1, p2, p0, q0)
    if beta > 1e-14:
        return -np.inf, np.inf
    return _range_parabola(gamma, vb, p1, p2, q0)
