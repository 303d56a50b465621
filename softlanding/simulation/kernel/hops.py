"""The limit depth of an undamped leg whose hops shrink toward the lift-off threshold.

With a conservative leg force ``u = k (l0 - s)`` (``k_d = 0``, no saturation, the
same law in every ground mode) the only loss is the ground's plastic work, so

    E_tot = E_mech(z) + V_leg(s) + W_g(d)

(mechanical energy, the leg's potential ``-int u ds``, the work done on the
ground) is conserved exactly through stance, flight and yielding. While the foot
is pinned the body oscillates without decay; the foot lifts off where the support
force reaches zero, always at the same stroke, with a body speed ``w`` set by the
oscillation's energy above the lift-off threshold, ``eps = m_b w^2 / 2``. Flight
is translation-invariant, so each hop depends on ``w`` alone until the foot lands;
landing yields the ground a little and lowers ``eps``. The hops shrink toward a
hop that lands with zero speed and loses nothing. Two kinds exist:

* the threshold (``eps -> 0``, flights ever shorter). The energy balance gives
  the limit depth exactly: ``E_thr(D) = E_tot``, where ``E_thr(D)`` is the
  energy of the threshold oscillation with the foot at ``D`` (a quadratic in
  ``D``, increasing beyond the static depth);
* symmetric hops: no damping makes the motion time-reversible, so a flight that
  lands at rest mirrors its lift-off and is at rest half-way, ``v_b(tau) =
  v_f(tau) = 0``, two equations linear in ``w`` whose determinant ``Delta(tau)``
  vanishes there. These are the "periodic hops"; the approach to them is a
  degenerate tangency (the landing is a near-triple root of the foot's height), and long
  runs can leave them: at ``k_p = 0.12, v0 = -6`` the depth settles near 3.532 for
  5,000 segments, then the hops leave and approach the threshold's limit, 6.87.
  No stop is made on them: the march goes on.

The march stops when the landing time falls, no root of ``Delta(tau)`` lies between
half of it and 0 (the hops head for the threshold), the stance cannot yield,
``E_tot`` is conserved, and each hop loses at most :data:`RHO` of ``eps``, a share
falling for three hops in a row (near the threshold the share lost per hop is
about proportional to ``eps``). That the hops then never end is not proven (it is
what the asymptotics say, and long runs approach the limit from below): the
landing's status says the rest is not proven, and its depth is the limit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import ENTRY, EV_LAND, EV_LIFT, FLIGHT, JIT, THETA, TIE
from softlanding.simulation.kernel.linalg import DGEMV, KIND_D, TRANS, expm, row5
from softlanding.simulation.kernel.model import (
    M_FU,
    M_FZ,
    closed_loop,
    crater_hold,
    energy_rel,
    ground_work,
)
from softlanding.simulation.kernel.rest import future_range

RHO = 0.05
"""Largest share of the excess ``eps`` lost per hop at which the march stops."""
ENERGY_TOL = 1e-9
"""Relative drift of ``E_tot`` from its value at impact that still counts as conserved."""

# hop-tracking slots: reference energy, last excess, last two loss shares, hops in a row,
# limit depth, lift-off time and stroke, last two flight times, the first symmetric hop's
# half-flight time (inf if none) and the flight time its scan covered
(H_EREF, H_EPS, H_R1, H_R2, H_N, H_DLIM, H_TLIFT, H_SL, H_T, H_TPREV, H_SYM,
 H_TSCAN) = range(12)
N_H = 12


@njit(**JIT)
def hop_state():
    """Fresh hop-tracking array (see the ``H_*`` slots)."""
    hk = np.full(N_H, np.nan)
    hk[H_N] = 0.0
    return hk


@njit(**ENTRY)
def hop_eligible(Kf, umax, open_loop):
    """True if the leg is a conservative spring ``u = k (l0 - s)`` in every ground mode."""
    if open_loop or umax < np.inf:
        return False
    for m in range(1, 3):
        for j in range(5):
            if Kf[m, j] != Kf[0, j]:
                return False
    k = Kf[0]
    return k[1] == 0.0 and k[3] == 0.0 and k[2] == -k[0] and k[0] < 0.0


@njit(**JIT)
def hop_event(code, z, t, hk):
    """Note a lift-off (time, stroke) or a landing (flight time) for :func:`hops_settled`."""
    if code == EV_LIFT:
        hk[H_TLIFT], hk[H_SL] = t, z[0] - z[2]
    elif code == EV_LAND and hk[H_TLIFT] == hk[H_TLIFT]:
        hk[H_TPREV], hk[H_T] = hk[H_T], t - hk[H_TLIFT]


@njit(**JIT)
def total_energy(P, z, z0, cu, d):
    """``E_mech + V_leg + W_g``: mechanical energy, the leg's potential, ground work."""
    s = z[0] - z[2]
    return energy_rel(P, z, z0) - (0.5 * cu[0] * s * s + cu[4] * s) + ground_work(P, d)


@njit(**JIT)
def threshold_energy(P, A, cu, z0, depth):
    """``E_tot`` of the body at rest at the lift-off threshold's turning point, foot at ``depth``.

    Returns NaN if the stance has no such oscillation (no spring, damping, a
    support force that depends on the body's speed, or no support at equilibrium).
    """
    alpha, beta = A[1, 0], A[1, 1]
    Fz, Fu = P[M_FZ:M_FU], P[M_FU]
    c0 = Fz[0] + Fu * cu[0]
    if not (alpha < 0.0 and beta == 0.0 and Fz[1] + Fu * cu[1] == 0.0 and c0 != 0.0):
        return np.nan
    z = np.zeros(5)
    z[2], z[4] = -depth, 1.0
    z[0] = -(A[1, 2] * z[2] + A[1, 4]) / alpha
    q_eq = 0.0
    for j in range(5):
        q_eq += (Fz[j] + Fu * cu[j]) * z[j]
    tol = TIE * max(1.0, crater_hold(P, depth))  # the lift-off event fires below -tol
    if not q_eq > 0.0:
        return np.nan
    z[0] += (q_eq + tol) / abs(c0)
    return total_energy(P, z, z0, cu, depth)


@njit(**JIT)
def limit_depth(P, A, cu, z0, d, energy):
    """Root ``D >= d`` of ``E_thr(D) = energy`` (a quadratic in ``D``); NaN if none."""
    h = max(1.0, d)
    f0 = threshold_energy(P, A, cu, z0, d) - energy
    f1 = threshold_energy(P, A, cu, z0, d + h) - energy
    f2 = threshold_energy(P, A, cu, z0, d + 2.0 * h) - energy
    a2 = (f2 - 2.0 * f1 + f0) / (2.0 * h * h)
    b = (f1 - f0) / h - a2 * h
    disc = b * b - 4.0 * a2 * f0
    if not (f0 < 0.0 and b > 0.0 and disc >= 0.0):
        return np.nan
    x = -2.0 * f0 / (b + math.sqrt(disc))
    for _ in range(2):  # polish on the exact balance (the fit's rounding)
        fx = threshold_energy(P, A, cu, z0, d + x) - energy
        x -= fx / (b + 2.0 * a2 * x)
    return d + x


@njit(**ENTRY)
def first_symmetric_hop(P, cu, s_lift, T):
    """Lower bound of the first root of ``Delta(tau)`` on ``(0, T/2]`` (the half-flight time of
    the shortest symmetric hop), ``inf`` if ``Delta`` keeps its sign there, NaN if the flight
    is not translation-invariant or too long to scan. ``Delta`` is scanned with the exact
    step map, eight points per unit of ``||A|| tau``.
    """
    Af = closed_loop(P, np.int64(FLIGHT), cu)  # not a literal: one closed_loop for all modes
    nrm = 0.0
    for i in range(4):
        if Af[i, 0] + Af[i, 2] != 0.0:
            return np.nan
        r = 0.0
        for j in range(5):
            r += abs(Af[i, j])
        nrm = max(nrm, r)
    half = 0.5 * T
    n = max(8, int(math.ceil(8.0 * half * nrm / THETA)))
    if n > 100_000:
        return np.nan
    h = half / n
    Phi = expm(Af, h)
    za = np.zeros(5)
    za[0], za[4] = s_lift, 1.0
    zb = np.zeros(5)
    zb[1] = 1.0
    ya, yb = np.zeros(5), np.zeros(5)
    ab = np.zeros(2)
    ab[0] = 1.0  # BLAS's alpha and beta
    prev = 0.0
    for k in range(1, n + 1):
        # za, zb = Phi @ za, Phi @ zb (the BLAS calls numba's @ makes)
        DGEMV(KIND_D, TRANS, 5, 5, ab.ctypes, Phi.ctypes, 5, za.ctypes, ab[1:].ctypes, ya.ctypes)
        DGEMV(KIND_D, TRANS, 5, 5, ab.ctypes, Phi.ctypes, 5, zb.ctypes, ab[1:].ctypes, yb.ctypes)
        za, ya, zb, yb = ya, za, yb, zb
        det = za[1] * zb[3] - za[3] * zb[1]
        if k > 1 and prev != 0.0 and prev * det <= 0.0:
            return (k - 1) * h
        prev = det
    return np.inf


@njit(**JIT)
def hops_pending(hk):
    """False while :func:`hops_settled` has nothing to check: the energy balance failed
    once, or the leg has not flown yet."""
    return not (hk[H_EREF] == np.inf or hk[H_T] != hk[H_T])


@njit(**JIT)
def hops_settled(P, A, z, z0, d, C, cu, hk):
    """At a stance entry of an eligible landing: True once the hops are settled.

    ``C`` holds the static mode's event rows (yield first). Each call records the
    excess ``eps`` over the threshold; the hops are settled when the stance cannot
    yield, ``E_tot`` has kept its value at impact, no symmetric hop lies
    between the last landing time and 0, the landing time falls, and the share of
    ``eps`` lost per hop is at most :data:`RHO` and has fallen for three hops in a
    row. Then ``hk[H_DLIM]`` is the limit depth.
    """
    if not hops_pending(hk):
        return False
    lo, hi = future_range(A, z, row5(C[0]))
    if hi > 0.0:
        hk[H_N], hk[H_EPS] = 0.0, np.nan
        return False  # the stance itself may yield
    if hk[H_EREF] != hk[H_EREF]:  # at impact (no rounding drift): the balance's value
        hk[H_EREF] = total_energy(P, z0, z0, cu, max(0.0, -z0[2]))
    energy = total_energy(P, z, z0, cu, d)
    if abs(energy - hk[H_EREF]) > ENERGY_TOL * max(1.0, abs(hk[H_EREF])):
        hk[H_EREF] = np.inf
        return False
    eps = energy - threshold_energy(P, A, cu, z0, d)
    last = hk[H_EPS]
    hk[H_EPS] = eps
    if not (eps > 0.0 and last == last):
        hk[H_N] = 0.0
        return False
    # no symmetric hop shorter than the last flight (the scan of (0, T/2] is kept while the
    # flight time does not grow beyond the one scanned)
    T = hk[H_T]
    if hk[H_SYM] != hk[H_SYM] or T > hk[H_TSCAN]:
        hk[H_SYM] = first_symmetric_hop(P, cu, hk[H_SL], T)
        hk[H_TSCAN] = T
    if not hk[H_SYM] > 0.5 * T:
        hk[H_N] = 0.0
        return False
    r = (last - eps) / last
    falling = hk[H_T] < hk[H_TPREV] and 0.0 < r <= RHO
    settled = falling and hk[H_N] >= 2.0 and r <= hk[H_R1] <= hk[H_R2]
    hk[H_R2], hk[H_R1] = hk[H_R1], r
    hk[H_N] = hk[H_N] + 1.0 if falling else 0.0
    if not settled:
        return False
    hk[H_DLIM] = limit_depth(P, A, cu, z0, d, hk[H_EREF])
    return hk[H_DLIM] == hk[H_DLIM]
