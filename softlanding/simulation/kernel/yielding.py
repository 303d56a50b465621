"""The yielding mode of a non-affine ground: adaptive Dormand-Prince 8(5,3) with events.

Drag and added mass act only while the foot yields, so only the yielding segments of a
non-affine landing are integrated (the static and flight modes stay on the exact path of
:mod:`.landing`). :func:`march_yield` integrates ``y = [z, W_act, W_drag, W_grain,
W_plastic]`` (:mod:`.groundlaw`) with DOP853's 12-stage step and its 5th/3rd-order error
estimate (Hairer's step-size control, as in SciPy: relative and absolute tolerance ``rtol``
on every component, the energy quadratures included).

Events are upward zero crossings of linear functionals ``c . z`` (foot stops, saturation
on or off, the cone completing its growth); a crossing over an accepted step (a sign change,
or an interior maximum located from the end slopes) is refined by safeguarded Newton **on the
integrator itself**: ``g(s) = c . Phi_s(y_n)`` where ``Phi_s`` is one DOP853 step of size ``s``
from the step's start, so the event state is the integrator's own solution at the event time
(no interpolant in between). The stroke's and the force's extrema inside a step are located
the same way (their rates ``v_b - v_f`` and ``cu . y'`` change sign).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import ENTRY, HORIZON, JIT, STEP_BUDGET
from softlanding.simulation.kernel.dop853 import E3 as DE3
from softlanding.simulation.kernel.dop853 import E5 as DE5
from softlanding.simulation.kernel.dop853 import A as DA
from softlanding.simulation.kernel.dop853 import B as DB
from softlanding.simulation.kernel.events import step_to
from softlanding.simulation.kernel.groundlaw import (
    G_LOCK,
    NY,
    Y_ACT,
    Y_DRAG,
    Y_GRAIN,
    Y_PLAST,
    control_at,
    yield_rhs,
)
from softlanding.simulation.kernel.linalg import bracketed_step

# ext layout (as in .landing)
X_SMIN, X_SMAX, X_UMIN, X_UMAX, X_ACT, X_WORK = range(6)
# ledger accumulators of a non-affine landing
A_DRAG, A_GRAIN, A_PLAST = range(3)
# ws_nl cells
H_LAST, H_RTOL = 0, 1

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERR_EXP = -1.0 / 8.0  # DOP853's error estimator is of order 7


@njit(**ENTRY)
def workspace_nl(rtol):
    """Work arrays of the yielding march: stages ``K`` and ``K2`` (trial steps), states, the
    law's output buffer, and cells ``[last step, rtol]``."""
    return (np.zeros((13, NY)), np.zeros((13, NY)), np.zeros(NY), np.zeros(NY), np.zeros(NY),
            np.zeros(NY), np.zeros(5), np.array([np.nan, rtol]))


@njit(**JIT)
def dop_step(A, cu, G, fp, buf, y, h, K, Yt, ynew):
    """One DOP853 step of size ``h`` from ``y`` (``K[0]`` must hold ``f(y)``); ``ynew`` gets the
    result and ``K[12]`` its slope ``f(ynew)``."""
    for s in range(1, 12):
        for i in range(NY):
            acc = 0.0
            for j in range(s):
                a = DA[s, j]
                if a != 0.0:
                    acc += a * K[j, i]
            Yt[i] = y[i] + h * acc
        yield_rhs(A, cu, G, fp, buf, Yt, K, s)
    for i in range(NY):
        acc = 0.0
        for j in range(12):
            acc += DB[j] * K[j, i]
        ynew[i] = y[i] + h * acc
    yield_rhs(A, cu, G, fp, buf, ynew, K, 12)


@njit(**JIT)
def error_norm(K, y, ynew, h, rtol):
    """Hairer's DOP853 error norm of the step just taken (``K`` its 13 slopes)."""
    e5 = 0.0
    e3 = 0.0
    n = 0
    for i in range(NY):
        if i == 4:
            continue
        n += 1
        sc = rtol + rtol * max(abs(y[i]), abs(ynew[i]))
        a5 = 0.0
        a3 = 0.0
        for j in range(13):
            a5 += DE5[j] * K[j, i]
            a3 += DE3[j] * K[j, i]
        e5 += (a5 / sc) ** 2
        e3 += (a3 / sc) ** 2
    den = e5 + 0.01 * e3
    if den == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt(den * n)


@njit(**JIT, inline="always")
def cdot(c, y):
    """``c . z`` of a 5-tuple functional on the state part of ``y``."""
    return c[0] * y[0] + c[1] * y[1] + c[2] * y[2] + c[3] * y[3] + c[4] * y[4]


@njit(**JIT, inline="always")
def _g(c, y, K2, slope):
    return cdot(c, K2[12]) if slope else cdot(c, y)


@njit(**JIT)
def trial(sysd, y, K, s, K2, Yt, yt):
    """``yt = Phi_s(y)`` (one DOP853 step of size ``s``; ``K2[12]`` gets its slope)."""
    A, cu, G, fp, buf = sysd
    for i in range(NY):
        K2[0, i] = K[0, i]
    dop_step(A, cu, G, fp, buf, y, s, K2, Yt, yt)


@njit(**JIT)
def refine_nl(sysd, y, K, c, slope, a, b, ga, gb, rtol, s0, K2, Yt, yt):
    """First ``s`` in ``(a, b]`` with ``g(s) > 0``, given ``g(a) <= 0 < g(b)``, where
    ``g(s) = c . Phi_s(y)`` (``slope``: ``c . f(Phi_s(y))``). Newton on the integrator
    (slope from ``f``) or the Illinois method (for a slope functional), safeguarded by
    the bracket; returns the far side of the crossing (the event has happened) with
    ``yt``, ``K2[12]`` its state and slope."""
    s = s0 if a < s0 < b else (a - ga * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b))
    side = 0
    for _ in range(200):
        trial(sysd, y, K, s, K2, Yt, yt)
        g = _g(c, yt, K2, slope)
        if g > 0.0:
            b, gb = s, g
            if side == 1:
                ga *= 0.5
            side = 1
        else:
            a, ga = s, g
            if side == -1:
                gb *= 0.5
            side = -1
        if b - a <= rtol * max(1.0, abs(b)):
            break
        if slope:
            sn = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
        else:
            dg = cdot(c, K2[12])
            sn = s - g / dg if dg != 0.0 else 0.5 * (a + b)
        sn, stalled = bracketed_step(sn, s, g, a, b, 0.25 * rtol * max(1.0, abs(s)))
        if stalled:
            break
        s = sn
    if s != b:
        trial(sysd, y, K, b, K2, Yt, yt)
    return b


@njit(**JIT, inline="always")
def hermite_guess(g0, d0, g1, d1, h):
    """Root of the cubic Hermite interpolant in (0, h) (a starting guess), by bisection."""
    c2 = (3.0 * (g1 - g0) / h - 2.0 * d0 - d1) / h
    c3 = (d0 + d1 - 2.0 * (g1 - g0) / h) / (h * h)
    lo, hi = 0.0, h
    for _ in range(40):
        s = 0.5 * (lo + hi)
        if g0 + s * (d0 + s * (c2 + s * c3)) > 0.0:
            hi = s
        else:
            lo = s
    return 0.5 * (lo + hi)


@njit(**JIT)
def crossing_nl(sysd, y, K, ynew, h, c, rtol, K2, Yt, yt):
    """First time in (0, h] at which ``c . z`` turns positive over the accepted step
    ``y -> ynew`` (slopes ``K[0]``, ``K[12]``), or -1."""
    g0, g1 = cdot(c, y), cdot(c, ynew)
    d0, d1 = cdot(c, K[0]), cdot(c, K[12])
    if g0 <= 0.0 < g1:
        return refine_nl(sysd, y, K, c, np.bool_(False), 0.0, h, g0, g1, rtol,
                         hermite_guess(g0, d0, g1, d1, h), K2, Yt, yt)
    if g1 <= 0.0 and d0 > 0.0 and d1 < 0.0:  # a maximum inside the step
        cneg = (-c[0], -c[1], -c[2], -c[3], -c[4])
        se = refine_nl(sysd, y, K, cneg, np.bool_(True), 0.0, h, -d0, -d1, 1e-12, -1.0, K2, Yt, yt)
        ge = cdot(c, yt)
        if ge > 0.0:
            return refine_nl(sysd, y, K, c, np.bool_(False), 0.0, se, g0, ge, rtol, -1.0, K2, Yt,
                             yt)
    return -1.0


@njit(**JIT)
def fold_extrema(sysd, y, K, yend, fend, h, ext, K2, Yt, yt):
    """Fold the stroke's and the force's values over ``(0, h]`` of a step into ``ext``
    (interior turning points located on the integrator, to 1e-10 in time)."""
    A, cu, G, fp, buf = sysd
    cs = (1.0, 0.0, -1.0, 0.0, 0.0)
    crate = (0.0, 1.0, 0.0, -1.0, 0.0)
    r0, r1 = cdot(crate, y), cdot(crate, yend)
    if (r0 > 0.0 > r1) or (r0 < 0.0 < r1):
        sg = 1.0 if r0 < 0.0 else -1.0
        c = (0.0, sg, 0.0, -sg, 0.0)
        refine_nl(sysd, y, K, c, np.bool_(False), 0.0, h, sg * r0, sg * r1, 1e-10, -1.0, K2, Yt, yt)
        sv = cdot(cs, yt)
        ext[X_SMIN], ext[X_SMAX] = min(ext[X_SMIN], sv), max(ext[X_SMAX], sv)
    d0, d1 = cdot(cu, K[0]), cdot(cu, fend)
    lock = G[G_LOCK] == 1.0  # the lock's force: folded at the steps only
    if not lock and ((d0 > 0.0 > d1) or (d0 < 0.0 < d1)):
        sg = 1.0 if d0 < 0.0 else -1.0
        c = (sg * cu[0], sg * cu[1], sg * cu[2], sg * cu[3], sg * cu[4])
        refine_nl(sysd, y, K, c, np.bool_(True), 0.0, h, sg * d0, sg * d1, 1e-10, -1.0, K2, Yt, yt)
        uv = cdot(cu, yt)
        ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], uv), max(ext[X_UMAX], uv)
    sv = cdot(cs, yend)
    ext[X_SMIN], ext[X_SMAX] = min(ext[X_SMIN], sv), max(ext[X_SMAX], sv)
    uv = control_at(G, fp, buf, cu, yend)
    ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], uv), max(ext[X_UMAX], uv)


@njit(**JIT)
def initial_step(sysd, y, K, rtol, K2, Yt, yt):
    """Hairer's starting step for order 8 (as SciPy's ``select_initial_step``)."""
    d0 = 0.0
    d1 = 0.0
    for i in range(NY):
        sc = rtol + rtol * abs(y[i])
        d0 += (y[i] / sc) ** 2
        d1 += (K[0, i] / sc) ** 2
    d0, d1 = math.sqrt(d0 / NY), math.sqrt(d1 / NY)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    A, cu, G, fp, buf = sysd
    for i in range(NY):
        Yt[i] = y[i] + h0 * K[0, i]
    yield_rhs(A, cu, G, fp, buf, Yt, K2, 12)
    d2 = 0.0
    for i in range(NY):
        sc = rtol + rtol * abs(y[i])
        d2 += ((K2[12, i] - K[0, i]) / sc) ** 2
    d2 = math.sqrt(d2 / NY) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1)


@njit(**JIT)
def _event_in_step(sysd, y, K, ynew, h, C, ne, rtol, K2, Yt, yt):
    """Earliest event over an accepted step: ``(time, index)`` (index -1 if none)."""
    sbest = np.inf
    hit = -1
    for k in range(ne):
        c = (C[k, 0], C[k, 1], C[k, 2], C[k, 3], C[k, 4])
        sk = crossing_nl(sysd, y, K, ynew, h, c, rtol, K2, Yt, yt)
        if 0.0 <= sk < sbest:
            sbest, hit = sk, k
    return sbest, hit


@njit(**JIT)
def march_yield(sysd, z, t, t_next, t_max, max_steps, C, ne, ext, acc, wsn):
    """Integrate a yielding segment from ``z`` (updated in place) to its first event, the
    schedule switch ``t_next`` or the horizon.

    ``sysd = (A, cu, G, fp, buf)``: closed loop (flat 25-tuple), control functional, the
    ground law. Adds the segment's actuator work to ``ext[X_ACT]`` and its drag, grain and
    plastic work to ``acc``. Returns ``(t, hit, time_event, stop)`` as :func:`.landing.march`.
    """
    K, K2, y, ynew, Yt, yt, buf, cells = wsn
    rtol = cells[H_RTOL]
    for i in range(5):
        y[i] = z[i]
    for i in range(5, NY):
        y[i] = 0.0
    A, cu, G, fp, _ = sysd
    yield_rhs(A, cu, G, fp, buf, y, K, 0)
    h = cells[H_LAST]
    if not h > 0.0:
        h = initial_step(sysd, y, K, rtol, K2, Yt, yt)
    rejected = False
    hit, time_event, stop = -1, False, -1
    while True:
        hs, time_event = step_to(t, h, t_next)
        dop_step(A, cu, G, fp, buf, y, hs, K, Yt, ynew)
        ext[X_WORK] += 1.0
        err = error_norm(K, y, ynew, hs, rtol)
        if not err < 1.0:
            h = hs * max(MIN_FACTOR, SAFETY * err**ERR_EXP) if err == err else 0.2 * hs
            rejected = True
            if ext[X_WORK] >= max_steps:
                stop = STEP_BUDGET
                break
            continue
        factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**ERR_EXP)
        if rejected:
            factor = min(1.0, factor)
        rejected = False
        sbest, hit = _event_in_step(sysd, y, K, ynew, hs, C, ne, rtol, K2, Yt, yt)
        if hit >= 0:
            trial(sysd, y, K, sbest, K2, Yt, yt)
            for i in range(NY):
                ynew[i] = yt[i]
                K[12, i] = K2[12, i]
            fold_extrema(sysd, y, K, ynew, K[12], sbest, ext, K2, Yt, yt)
            for i in range(NY):
                y[i] = ynew[i]
            t += sbest
            time_event = False
            cells[H_LAST] = hs
            break
        fold_extrema(sysd, y, K, ynew, K[12], hs, ext, K2, Yt, yt)
        for i in range(NY):
            y[i] = ynew[i]
            K[0, i] = K[12, i]
        t += hs
        if not time_event:
            h = hs * factor
            cells[H_LAST] = h
        if time_event:
            break
        if t > t_max:
            stop = HORIZON
            break
        if ext[X_WORK] >= max_steps:
            stop = STEP_BUDGET
            break
    for i in range(5):
        z[i] = y[i]
    ext[X_ACT] += y[Y_ACT]
    acc[A_DRAG] += y[Y_DRAG]
    acc[A_GRAIN] += y[Y_GRAIN]
    acc[A_PLAST] += y[Y_PLAST]
    return t, hit, time_event, stop


@njit(**JIT)
def advance(sysd, y, span, wsn):
    """Integrate ``y`` (in place) over ``span`` >= 0 with the adaptive DOP853 steps (no events;
    used to sample a yielding segment between its recorded ends)."""
    K, K2, _, ynew, Yt, _, buf, cells = wsn
    A, cu, G, fp, _ = sysd
    rtol = cells[H_RTOL]
    if not span > 0.0:
        return
    yield_rhs(A, cu, G, fp, buf, y, K, 0)
    h = cells[H_LAST]
    if not h > 0.0:
        h = initial_step(sysd, y, K, rtol, K2, Yt, ynew)
    done = 0.0
    for _ in range(10_000_000):
        hs = min(h, span - done)
        last = hs == span - done
        dop_step(A, cu, G, fp, buf, y, hs, K, Yt, ynew)
        err = error_norm(K, y, ynew, hs, rtol)
        if not err < 1.0:
            h = hs * max(MIN_FACTOR, SAFETY * err**ERR_EXP) if err == err else 0.2 * hs
            continue
        for i in range(NY):
            y[i] = ynew[i]
            K[0, i] = K[12, i]
        done = span if last else done + hs
        if last:
            break
        h = hs * (MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**ERR_EXP))
        cells[H_LAST] = h


@njit(**ENTRY)
def fixed_steps(sysd, y, span, n, wsn):
    """``n`` equal DOP853 steps over ``span`` (no error control): the method's order shows in
    the error's decrease with ``n`` (used by the tests and the benchmark)."""
    K, _, _, ynew, Yt, _, buf, _ = wsn
    A, cu, G, fp, _ = sysd
    h = span / n
    for _ in range(n):
        yield_rhs(A, cu, G, fp, buf, y, K, 0)
        dop_step(A, cu, G, fp, buf, y, h, K, Yt, ynew)
        for i in range(NY):
            y[i] = ynew[i]
