"""Control regimes, the ground's mode logic and the event functionals of a segment.

An event of a segment is an upward zero crossing of ``C[k] . z(t)``; the
functionals depend on the ground mode (foot stops; support force above the
crater's hold or below zero; landing at the crater bottom) and on the control
regime (saturation on or off).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import (
    EV_LAND,
    EV_LIFT,
    EV_SAT_HIGH,
    EV_SAT_LOW,
    EV_STOP,
    EV_UNSAT,
    EV_YIELD,
    FLIGHT,
    JIT,
    LINEAR,
    OPEN_LOOP,
    SAT_HIGH,
    SAT_LOW,
    STATIC,
    TIE,
    YIELDING,
)
from softlanding.simulation.kernel.linalg import (
    dot,
    hermite_root,
    prop4_t,
    refine_t,
    row,
    row5,
    scaled,
)
from softlanding.simulation.kernel.model import M_FU, support_Fz


@njit(**JIT)
def control_vector(mode, regime, Kf, umax, k_ol):
    """The functional cu with u = cu . z for the current mode and regime (``k_ol``: the
    open-loop schedule's current gain row, a constant force ``u`` being ``[0, 0, 0, 0, u]``)."""
    cu = np.zeros(5)
    if regime == OPEN_LOOP:
        for j in range(5):
            cu[j] = k_ol[j]
    elif regime == SAT_HIGH:
        cu[4] = umax
    elif regime == SAT_LOW:
        cu[4] = -umax
    else:
        for j in range(5):
            cu[j] = Kf[mode, j]
    return cu


@njit(**JIT)
def classify(mode, z, Kf, umax):
    """Control regime of the feedback at ``z``: linear or saturated high or low."""
    ul = dot(row(Kf, mode), z)
    if ul > umax:
        return SAT_HIGH
    if ul < -umax:
        return SAT_LOW
    return LINEAR


@njit(**JIT)
def contact_mode(P, z, hold, Kf, umax, open_loop, k_ol):
    """Foot at rest at the crater bottom: static, yielding again (support force above the
    crater's ``hold``), or lifting off (below zero)."""
    if open_loop:
        u = dot(k_ol, z)
    else:
        u = dot(Kf[STATIC], z)
        u = min(umax, max(-umax, u))
    freq = dot(support_Fz(P), z) + P[M_FU] * u
    tol = TIE * max(1.0, hold)
    if freq > hold + tol:
        return YIELDING
    if freq < -tol:
        return FLIGHT
    return STATIC


@njit(**JIT)
def build_events(P, mode, regime, cu, d, hold, shift, Kf, umax, open_loop, C, codes):
    """Fill ``C`` and ``codes`` with the segment's event functionals; returns their count.

    ``d``: the crater's depth (where a flying foot lands); ``hold``: the largest support
    force it takes unyielding (the static mode's yield event).
    """
    ne = 0
    C[:, :] = 0.0
    if mode == YIELDING:
        C[ne, 3] = 1.0
        codes[ne] = EV_STOP
        ne += 1
    elif mode == STATIC:
        Fz = support_Fz(P)
        Fu = P[M_FU]
        tol = TIE * max(1.0, hold)
        for j in range(5):
            C[ne, j] = Fz[j] + Fu * cu[j]
            C[ne + 1, j] = -(Fz[j] + Fu * cu[j])
        C[ne, 4] -= hold + tol
        C[ne + 1, 4] -= tol
        codes[ne], codes[ne + 1] = EV_YIELD, EV_LIFT
        ne += 2
    else:
        C[ne, 2] = -1.0
        C[ne, 4] = shift - d
        codes[ne] = EV_LAND
        ne += 1
    if not open_loop and umax < np.inf:
        if regime == LINEAR:
            for j in range(5):
                C[ne, j] = Kf[mode, j]
                C[ne + 1, j] = -Kf[mode, j]
            C[ne, 4] -= umax
            C[ne + 1, 4] -= umax
            codes[ne], codes[ne + 1] = EV_SAT_HIGH, EV_SAT_LOW
            ne += 2
        else:
            sg = -1.0 if regime == SAT_HIGH else 1.0
            for j in range(5):
                C[ne, j] = sg * Kf[mode, j]
            C[ne, 4] += umax
            codes[ne] = EV_UNSAT
            ne += 1
    return ne


@njit(**JIT, forceinline=True)
def due_event(C, dC, ne, z):
    """Index of an event already due at the start of a segment, or -1."""
    for k in range(ne):
        g0 = dot(row(C, k), z)
        if g0 > 0.0 or (g0 == 0.0 and dot(row(dC, k), z) > 0.0):
            return k
    return -1


@njit(**JIT, forceinline=True)
def rows4(C):
    """The four rows of a (4, 5) array as a tuple of 5-tuples (``row(C, 0)`` would compile a
    specialisation of ``row`` for each literal index)."""
    return (row5(C[0]), row5(C[1]), row5(C[2]), row5(C[3]))


@njit(**JIT, forceinline=True)
def _crossing_time(A, nrm, z, z1, h, c, dc):
    """First time in (0, h] at which ``c . z`` turns positive, or -1 if it does not.

    A sign change over the step is refined directly; otherwise a maximum inside
    the step (``c A . z`` from + to -) is located and tested. ``A`` is a flat
    25-tuple with row norm ``nrm``; states and functionals are 5-tuples.
    """
    g0 = dot(c, z)
    g1 = dot(c, z1)
    if g0 <= 0.0 < g1:
        s0 = hermite_root(g0, dot(dc, z), g1, dot(dc, z1), h)
        return refine_t(A, nrm, z, c, 0.0, h, g0, g1, 2e-15, s0)
    if g1 <= 0.0 and dot(dc, z) > 0.0 and dot(dc, z1) < 0.0:
        # a maximum inside the step: does it poke above zero?
        dg0 = dot(dc, z)
        dg1 = dot(dc, z1)
        se = refine_t(A, nrm, z, scaled(dc, -1.0), 0.0, h, -dg0, -dg1, 2e-15, -1.0)
        ge = dot(c, prop4_t(A, nrm, z, se))
        if ge > 0.0:
            return refine_t(A, nrm, z, c, 0.0, se, g0, ge, 2e-15, -1.0)
    return -1.0


@njit(**JIT, forceinline=True)
def earliest_event(A, nrm, z, z1, h, C, dC, ne):
    """Earliest event in (0, h] of a marching step: ``(time, index)``; index -1 if none.

    ``C``, ``dC``: the event functionals and their derivatives as tuples of 5-tuples.
    """
    sbest = np.inf
    hit = -1
    for k in range(ne):
        sk = _crossing_time(A, nrm, z, z1, h, C[k], dC[k])
        if sk < 0.0:
            continue
        if sk < sbest:
            sbest = sk
            hit = k
    return sbest, hit


@njit(**JIT, forceinline=True)
def step_to(t, h, t_next):
    """A step of ``h`` from ``t`` cut at the time event ``t_next``: its length, and whether
    it reaches the event."""
    if t + h >= t_next:
        return t_next - t, True
    return h, False
