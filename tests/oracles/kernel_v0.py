"""Compiled core of the exact event-driven hybrid simulator.

Each (ground mode, control regime) pair is an affine system ``z' = A z`` in the
augmented state ``z = [x_b, v_b, x_f, v_f, 1]``. Within a segment the solution
is ``z(t) = exp(A t) z0``; we march with the exact step map ``exp(A h)`` on a
grid fine enough (``||A|| h <= 0.5``) that no event can hide between two grid
points without a sign change of the event function or of its derivative, then
locate the event time by safeguarded Newton iteration on the exact solution.
There is no ODE tolerance anywhere: errors are rounding only.

Everything here works on plain arrays prepared by :mod:`softlanding.simulation.simulator`
from :func:`softlanding.model.dynamics.mode_matrices`; this module knows no physics
beyond the mode logic of the paper's finite state machine.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# ground modes
YIELDING, STATIC, FLIGHT = 0, 1, 2
# control regimes
LINEAR, SAT_HIGH, SAT_LOW, OPEN_LOOP = 0, 1, 2, 3
# event codes
EV_STOP, EV_YIELD, EV_LIFT, EV_LAND, EV_SAT_HIGH, EV_SAT_LOW, EV_UNSAT = range(7)
# status codes
REST_PROVEN, HORIZON, TOO_MANY_SEGMENTS = 0, 1, 2

# output layout
O_DEPTH, O_STEPS, O_TSTOP, O_T, O_UPEAK, O_SMIN, O_SMAX, O_FEAS, O_STATUS = range(9)
O_E0, O_ET, O_EGND, O_EACT, O_NSEG, O_UMIN, O_UMAX = range(9, 16)
N_OUT = 16

THETA = 1.0  # ||A|| h (or omega h in the static mode) bound for the marching grid
TIE = 1e-12  # relative tolerance on the ground's yield threshold
FEAS_TOL = 1e-9  # tolerance on the stroke limits (rounding at an exact boundary)
SMALL = 1e-12  # what counts as zero drift in the rest proof


@njit(cache=True)
def _norm_inf4(A):
    m = 0.0
    for i in range(4):
        r = 0.0
        for j in range(4):
            r += abs(A[i, j])
        m = max(m, r)
    return m


@njit(cache=True)
def _expm(M, h):
    """exp(M h) by scaling and squaring of a Taylor series (M small and square)."""
    n = M.shape[0]
    nrm = 0.0
    for i in range(n):
        r = 0.0
        for j in range(n):
            r += abs(M[i, j])
        nrm = max(nrm, r)
    nrm *= abs(h)
    sq = 0
    while nrm > 0.5:
        nrm *= 0.5
        sq += 1
    sc = h / 2.0**sq
    out = np.eye(n)
    term = np.eye(n)
    tmp = np.empty((n, n))
    for k in range(1, 30):
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for m in range(n):
                    acc += term[i, m] * M[m, j]
                tmp[i, j] = acc * sc / k
        big = 0.0
        size = 0.0
        for i in range(n):
            for j in range(n):
                term[i, j] = tmp[i, j]
                out[i, j] += tmp[i, j]
                big = max(big, abs(tmp[i, j]))
                size = max(size, abs(out[i, j]))
        if big <= 1e-17 * size:
            break
    for _ in range(sq):
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for m in range(n):
                    acc += out[i, m] * out[m, j]
                tmp[i, j] = acc
        out[:, :] = tmp
    return out


@njit(cache=True)
def _matvec(M, z):
    n = M.shape[0]
    out = np.empty(n)
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += M[i, j] * z[j]
        out[i] = acc
    return out


@njit(cache=True)
def _dot(c, z):
    acc = 0.0
    for i in range(z.shape[0]):
        acc += c[i] * z[i]
    return acc


@njit(cache=True)
def _propagate(A, z, h):
    """exp(A h) z by Taylor series on the vector, substepped so ||A h|| <= 0.5.

    Written on scalars (no temporaries): this is the innermost loop of the
    event refinement.
    """
    nrm = 0.0
    for i in range(4):
        r = 0.0
        for j in range(5):
            r += abs(A[i, j])
        nrm = max(nrm, r)
    nsub = max(1, int(math.ceil(nrm * abs(h))))
    dt = h / nsub
    x0, x1, x2, x3 = z[0], z[1], z[2], z[3]
    x4 = z[4]
    for _ in range(nsub):
        t0, t1, t2, t3 = x0, x1, x2, x3
        a0, a1, a2, a3 = x0, x1, x2, x3
        scale = abs(x0) + abs(x1) + abs(x2) + abs(x3) + abs(x4)
        for k in range(1, 40):
            f = dt / k
            n0 = (A[0, 0] * t0 + A[0, 1] * t1 + A[0, 2] * t2 + A[0, 3] * t3
                  + (A[0, 4] * x4 if k == 1 else 0.0)) * f
            n1 = (A[1, 0] * t0 + A[1, 1] * t1 + A[1, 2] * t2 + A[1, 3] * t3
                  + (A[1, 4] * x4 if k == 1 else 0.0)) * f
            n2 = (A[2, 0] * t0 + A[2, 1] * t1 + A[2, 2] * t2 + A[2, 3] * t3
                  + (A[2, 4] * x4 if k == 1 else 0.0)) * f
            n3 = (A[3, 0] * t0 + A[3, 1] * t1 + A[3, 2] * t2 + A[3, 3] * t3
                  + (A[3, 4] * x4 if k == 1 else 0.0)) * f
            t0, t1, t2, t3 = n0, n1, n2, n3
            a0 += t0
            a1 += t1
            a2 += t2
            a3 += t3
            if abs(t0) + abs(t1) + abs(t2) + abs(t3) <= 1e-17 * scale:
                break
        x0, x1, x2, x3 = a0, a1, a2, a3
    out = np.empty(5)
    out[0], out[1], out[2], out[3], out[4] = x0, x1, x2, x3, x4
    return out


@njit(cache=True)
def _covector_times(c, A):
    """The row vector ``c A``: the functional of z giving d/dt (c . z) when z' = A z."""
    out = np.empty(5)
    for j in range(5):
        acc = 0.0
        for i in range(5):
            acc += c[i] * A[i, j]
        out[j] = acc
    return out


@njit(cache=True)
def _hermite_root(g0, d0, g1, d1, h):
    """Root in (0, h) of the cubic Hermite interpolant of g (g0 <= 0 < g1): a
    starting guess for Newton on the exact solution (error O(h^4))."""
    c2 = (3.0 * (g1 - g0) / h - 2.0 * d0 - d1) / h
    c3 = (d0 + d1 - 2.0 * (g1 - g0) / h) / (h * h)
    lo, hi = 0.0, h
    s = -g0 * h / (g1 - g0)
    for _ in range(30):
        p = g0 + s * (d0 + s * (c2 + s * c3))
        if p > 0.0:
            hi = s
        else:
            lo = s
        dp = d0 + s * (2.0 * c2 + 3.0 * s * c3)
        sn = s - p / dp if dp != 0.0 else 0.5 * (lo + hi)
        if not (lo < sn < hi):
            sn = 0.5 * (lo + hi)
        if abs(sn - s) <= 1e-14 * h:
            return sn
        s = sn
    return s


@njit(cache=True)
def _refine(A, z, c, a, b, ga, gb, rtol=2e-15, s0=-1.0):
    """First time s in (a, b] with g(s) = c . exp(A s) z > 0, given g(a) <= 0 < g(b).

    Newton on the exact solution, safeguarded by the bracket, converged to
    about 1e-15; the returned time lies on the far side of the crossing (the
    event has happened), so the next segment starts strictly inside its regime.
    """
    dc = _covector_times(c, A)
    if a < s0 < b:
        s = s0
    else:
        s = a - ga * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
    for _ in range(100):
        zs = _propagate(A, z, s)
        g = _dot(c, zs)
        if g > 0.0:
            b = s
        else:
            a = s
        if b - a <= rtol * max(1.0, abs(b)):
            break
        dg = _dot(dc, zs)
        sn = s - g / dg if dg != 0.0 else 0.5 * (a + b)
        if not (a < sn < b):
            sn = 0.5 * (a + b)
        if abs(sn - s) <= 0.5 * rtol * max(1.0, abs(s)):
            # converged: step just past the root to close the bracket
            step = 1e-15 * max(1.0, abs(sn))
            sn = sn + step if g <= 0.0 else sn - step
            sn = min(max(sn, a), b)
            if sn == s:
                break
        s = sn
    return b


@njit(cache=True)
def _interior_extremum(A, z, z1, h, c, dc, ddc):
    """Value of q = c . z at its turning point inside (0, h), or NaN if none.

    A turning point is a sign change of q' = dc . z; its time is refined from a
    Hermite starting guess (q'' = ddc . z) to 1e-9: the value's error is
    quadratic in the time's.
    """
    d0 = _dot(dc, z)
    d1 = _dot(dc, z1)
    if not ((d0 > 0.0 and d1 < 0.0) or (d0 < 0.0 and d1 > 0.0)):
        return np.nan
    sg = 1.0 if d0 < 0.0 else -1.0
    s0 = _hermite_root(sg * d0, sg * _dot(ddc, z), sg * d1, sg * _dot(ddc, z1), h)
    se = _refine(A, z, sg * dc, 0.0, h, sg * d0, sg * d1, 1e-9, s0)
    return _dot(c, _propagate(A, z, se))


@njit(cache=True)
def _closed_loop(Am, Bm, cu):
    """A + B cu^T: the affine closed loop for u = cu . z."""
    A = Am.copy()
    for i in range(5):
        for j in range(5):
            A[i, j] += Bm[i] * cu[j]
    return A


@njit(cache=True)
def _gram(A, Q, h):
    """int_0^h exp(A^T t) Q exp(A t) dt by Van Loan's block exponential."""
    C = np.zeros((10, 10))
    for i in range(5):
        for j in range(5):
            C[i, j] = -A[j, i]
            C[i, 5 + j] = Q[i, j]
            C[5 + i, 5 + j] = A[i, j]
    F = _expm(C, h)
    G = np.zeros((5, 5))
    for i in range(5):
        for j in range(5):
            acc = 0.0
            for k in range(5):
                acc += F[5 + k, 5 + i] * F[k, 5 + j]
            G[i, j] = acc
    return G


@njit(cache=True)
def _quad(G, z):
    acc = 0.0
    for i in range(5):
        for j in range(5):
            acc += z[i] * G[i, j] * z[j]
    return acc


@njit(cache=True)
def _hull(lo, hi, v):
    return min(lo, v), max(hi, v)


@njit(cache=True)
def _future_range(A, z, c):
    """Exact range of q(t) = c . z(t) over t >= 0 in the static mode.

    With the foot pinned, only the body moves: ``x_b' = v_b``,
    ``v_b' = alpha x_b + beta v_b + gamma``. Solved in closed form: damped
    oscillation (turning points alternate and shrink, so the first two bound
    the future), over-damped (at most one turning point, then a limit), pure
    damping without stiffness (drift at a terminal velocity), or constant
    acceleration (a parabola). Returns (lo, hi), possibly infinite.
    """
    alpha, beta = A[1, 0], A[1, 1]
    gamma = A[1, 2] * z[2] + A[1, 3] * z[3] + A[1, 4]
    xb, vb = z[0], z[1]
    p1, p2 = c[0], c[1]
    p0 = c[2] * z[2] + c[3] * z[3] + c[4]
    q0 = p1 * xb + p2 * vb + p0
    acc = alpha * xb + beta * vb + gamma
    q1 = p1 * vb + p2 * acc
    inf = np.inf
    if abs(alpha) > 1e-14:
        if alpha > 0.0 or beta > 1e-14:
            if abs(q1) < SMALL and abs(acc) < SMALL and abs(vb) < SMALL:
                return q0, q0
            return -inf, inf
        xeq = -gamma / alpha
        qeq = p1 * xeq + p0
        w0, w1 = q0 - qeq, q1
        disc = beta * beta + 4.0 * alpha
        lo, hi = w0, w0
        if disc < -1e-12 * (beta * beta + abs(alpha)):
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
                lo, hi = _hull(lo, hi, wk)
        else:
            lo, hi = _hull(lo, hi, 0.0)
            sq = math.sqrt(max(disc, 0.0))
            l1, l2 = 0.5 * (beta + sq), 0.5 * (beta - sq)
            if sq <= 1e-7 * abs(beta):
                lam = 0.5 * beta
                C1, C2 = w0, w1 - lam * w0
                if C2 != 0.0:
                    ts = -(C2 + lam * C1) / (lam * C2)
                    if ts > 0.0:
                        lo, hi = _hull(lo, hi, (C1 + C2 * ts) * math.exp(lam * ts))
            else:
                C1 = (w1 - l2 * w0) / (l1 - l2)
                C2 = w0 - C1
                if l1 * C1 != 0.0:
                    ratio = -l2 * C2 / (l1 * C1)
                    if ratio > 0.0:
                        ts = math.log(ratio) / (l1 - l2)
                        if ts > 0.0:
                            wk = C1 * math.exp(l1 * ts) + C2 * math.exp(l2 * ts)
                            lo, hi = _hull(lo, hi, wk)
        return qeq + lo, qeq + hi
    if beta < -1e-14:
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
                    lo, hi = _hull(lo, hi, qs)
            if drift > 0.0:
                return lo, inf
            return -inf, hi
        qinf = p1 * lim_x + p2 * veq + p0
        return min(q0, qinf), max(q0, qinf)
    if beta > 1e-14:
        return -inf, inf
    # constant acceleration: q = q0 + a1 t + a2 t^2
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


@njit(cache=True)
def _control_vector(mode, regime, Kf, umax, u_ol):
    """The functional cu with u = cu . z for the current mode and regime."""
    cu = np.zeros(5)
    if regime == OPEN_LOOP:
        cu[4] = u_ol
    elif regime == SAT_HIGH:
        cu[4] = umax
    elif regime == SAT_LOW:
        cu[4] = -umax
    else:
        for j in range(5):
            cu[j] = Kf[mode, j]
    return cu


@njit(cache=True)
def _classify(mode, z, Kf, umax):
    ul = _dot(Kf[mode], z)
    if ul > umax:
        return SAT_HIGH
    if ul < -umax:
        return SAT_LOW
    return LINEAR


@njit(cache=True)
def _contact_mode(z, d, Kf, umax, open_loop, u_ol, Fz, Fu):
    """Foot at rest at the crater bottom: static, yielding again, or lifting off."""
    if open_loop:
        u = u_ol
    else:
        u = _dot(Kf[STATIC], z)
        u = min(umax, max(-umax, u))
    freq = _dot(Fz, z) + Fu * u
    tol = TIE * max(1.0, d)
    if freq > d + tol:
        return YIELDING
    if freq < -tol:
        return FLIGHT
    return STATIC


@njit(cache=True)
def simulate_one(A3, B3, Fz, Fu, Ew, Kf, umax, sched_t, sched_u, x0, s_lim, t_max,
                 max_seg, energy, out, rec_t, rec_A, rec_z, rec_cu, rec_mode):
    """Simulate one landing; fill ``out`` (layout O_*) and the segment records.

    Parameters
    ----------
    A3, B3 : (3, 5, 5), (3, 5)
        Open-loop mode matrices (yielding, static, flight).
    Fz, Fu : (5,), float
        Static support force ``F_req = Fz . z + Fu u``.
    Ew : (2,)
        Body and foot mass fractions (energy weights).
    Kf : (3, 5)
        Feedback ``u = Kf[mode] . z`` per ground mode (unused when open loop).
    umax : float
        Saturation of the feedback (``inf`` for none).
    sched_t, sched_u : (m,), (m+1,)
        Open-loop schedule: ``u = sched_u[i]`` on ``[sched_t[i-1], sched_t[i])``;
        empty ``sched_u`` means feedback.
    rec_* : arrays with ``len(rec_t) - 1`` rows or 0 rows
        Segment records (start time, closed-loop matrix, start state, control
        functional, mode); the row after the last holds the end time.
    """
    open_loop = sched_u.shape[0] > 0
    nrec = rec_t.shape[0] - 1
    inf = np.inf
    z = np.empty(5)
    for i in range(4):
        z[i] = x0[i]
    z[4] = 1.0
    z0 = z.copy()
    t = 0.0
    d = max(0.0, -z[2])
    steps = 0
    t_first_stop = np.nan
    T = np.nan
    E_T = np.nan
    act_T = np.nan
    act = 0.0
    status = TOO_MANY_SEGMENTS
    sidx = 0
    u_ol = sched_u[0] if open_loop else 0.0
    smin = z[0] - z[2]
    smax = smin
    umin, umx = inf, -inf

    def energy_of(zz):
        return (0.5 * Ew[0] * zz[1] ** 2 + 0.5 * Ew[1] * zz[3] ** 2
                + Ew[0] * (zz[0] - z0[0]) + Ew[1] * (zz[2] - z0[2]))

    E0 = energy_of(z)

    if z[3] < 0.0:
        mode = YIELDING
    elif z[3] > 0.0:
        mode = FLIGHT
    else:
        mode = _contact_mode(z, d, Kf, umax, open_loop, u_ol, Fz, Fu)
    if mode == YIELDING:
        steps = 1
    elif mode == STATIC:
        T = 0.0
        E_T = E0
        act_T = 0.0
    regime = OPEN_LOOP if open_loop else _classify(mode, z, Kf, umax)

    cs = np.zeros(5)  # stroke x_b - x_f
    cs[0], cs[2] = 1.0, -1.0
    cv = np.zeros(5)  # stroke rate v_b - v_f
    cv[1], cv[3] = 1.0, -1.0
    C = np.zeros((4, 5))
    codes = np.zeros(4, dtype=np.int64)
    nseg = 0
    done = False
    shift = 0.0  # in flight, heights are measured from the crater bottom (see below)
    while nseg < max_seg and not done:
        cu = _control_vector(mode, regime, Kf, umax, u_ol)
        A = _closed_loop(A3[mode], B3[mode], cu)
        if mode == FLIGHT and shift == 0.0 and d > 0.0:
            # Without ground force the dynamics depend on heights only through the
            # stroke, so measure heights from the crater bottom: the landing function
            # x_f + d is then computed without cancellation, which matters at a
            # grazing landing (its time error is sqrt(rounding of x_f)).
            invariant = True
            for i in range(4):
                if A[i, 0] + A[i, 2] != 0.0:
                    invariant = False
            if invariant:
                shift = d
                z[0] += shift
                z[2] += shift
        if nseg < nrec:
            rec_t[nseg] = t
            rec_mode[nseg] = mode
            for i in range(5):
                rec_z[nseg, i] = z[i]
                rec_cu[nseg, i] = cu[i]
                for j in range(5):
                    rec_A[nseg, i, j] = A[i, j]
            rec_z[nseg, 0] -= shift
            rec_z[nseg, 2] -= shift
        nseg += 1
        u_now = _dot(cu, z)
        umin, umx = min(umin, u_now), max(umx, u_now)
        t_next = sched_t[sidx] if (open_loop and sidx < sched_t.shape[0]) else inf

        # events of this segment: event when C[k] . z crosses 0 upward
        ne = 0
        C[:, :] = 0.0
        if mode == YIELDING:
            C[ne, 3] = 1.0
            codes[ne] = EV_STOP
            ne += 1
        elif mode == STATIC:
            tol = TIE * max(1.0, d)
            for j in range(5):
                C[ne, j] = Fz[j] + Fu * cu[j]
                C[ne + 1, j] = -(Fz[j] + Fu * cu[j])
            C[ne, 4] -= d + tol
            C[ne + 1, 4] -= tol
            codes[ne], codes[ne + 1] = EV_YIELD, EV_LIFT
            ne += 2
        else:
            C[ne, 2] = -1.0
            C[ne, 4] = shift - d
            codes[ne] = EV_LAND
            ne += 1
        if not open_loop and umax < inf:
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

        # rest proof: pinned foot, no more switching, support force stays admissible
        if mode == STATIC and t_next == inf:
            proven = True
            for k in range(ne):
                lo, hi = _future_range(A, z, C[k])
                if hi > 0.0:
                    proven = False
            if proven:
                lo, hi = _future_range(A, z, cs)
                smin, smax = min(smin, lo), max(smax, hi)
                lo, hi = _future_range(A, z, cu)
                umin, umx = min(umin, lo), max(umx, hi)
                status = REST_PROVEN
                if nseg - 1 < nrec:
                    rec_t[nseg] = t
                break

        # derivative functionals: d/dt (c . z) = (c A) . z
        dC = np.zeros((ne, 5))
        for k in range(ne):
            dC[k] = _covector_times(C[k], A)
        dcs = _covector_times(cs, A)
        ddcs = _covector_times(dcs, A)
        dcu = _covector_times(cu, A)
        ddcu = _covector_times(dcu, A)

        # an event already due at the start of the segment fires at once
        hit = -1
        for k in range(ne):
            g0 = _dot(C[k], z)
            if g0 > 0.0 or (g0 == 0.0 and _dot(dC[k], z) > 0.0):
                hit = k
                break
        Qe = np.zeros((5, 5))
        if energy:
            for i in range(5):
                for j in range(5):
                    Qe[i, j] = 0.5 * (cu[i] * cv[j] + cv[i] * cu[j])
        if hit < 0:
            if mode == STATIC:
                # only the body moves: event functions are sums of two exponentials,
                # whose derivative has at most one zero per step when omega h < pi
                rho = math.sqrt(abs(A[1, 0])) + abs(A[1, 1])
                hstep = THETA / max(rho, 1e-2)
            else:
                hstep = THETA / max(_norm_inf4(A), 1e-3)
            Phi = _expm(A, hstep)
            G = _gram(A, Qe, hstep) if energy else Qe
            while True:
                h = hstep
                time_event = False
                if t + h >= t_next:
                    h = t_next - t
                    time_event = True
                if time_event or h != hstep:
                    z1e = _propagate(A, z, h)
                else:
                    z1e = _matvec(Phi, z)
                z1 = z1e
                # earliest event in (0, h]
                sbest = inf
                for k in range(ne):
                    g0 = _dot(C[k], z)
                    g1 = _dot(C[k], z1e)
                    if g0 <= 0.0 < g1:
                        s0 = _hermite_root(g0, _dot(dC[k], z), g1, _dot(dC[k], z1e), h)
                        sk = _refine(A, z, C[k], 0.0, h, g0, g1, 2e-15, s0)
                    elif g1 <= 0.0 and _dot(dC[k], z) > 0.0 and _dot(dC[k], z1e) < 0.0:
                        # a maximum inside the step: does it poke above zero?
                        dg0 = _dot(dC[k], z)
                        dg1 = _dot(dC[k], z1e)
                        ngd = np.empty(5)
                        for j in range(5):
                            ngd[j] = -dC[k, j]
                        se = _refine(A, z, ngd, 0.0, h, -dg0, -dg1)
                        ge = _dot(C[k], _propagate(A, z, se))
                        if ge > 0.0:
                            sk = _refine(A, z, C[k], 0.0, se, g0, ge)
                        else:
                            continue
                    else:
                        continue
                    if sk < sbest:
                        sbest = sk
                        hit = k
                if hit >= 0:
                    h = sbest
                    z1 = _propagate(A, z, h)
                    time_event = False
                # stroke and force extrema inside (0, h]
                se_v = _interior_extremum(A, z, z1, h, cs, dcs, ddcs)
                if se_v == se_v:
                    smin, smax = min(smin, se_v), max(smax, se_v)
                ue = _interior_extremum(A, z, z1, h, cu, dcu, ddcu)
                if ue == ue:
                    umin, umx = min(umin, ue), max(umx, ue)
                if energy:
                    if h == hstep:
                        act -= _quad(G, z)
                    else:
                        act -= _quad(_gram(A, Qe, h), z)
                sv = _dot(cs, z1)
                smin, smax = min(smin, sv), max(smax, sv)
                uv = _dot(cu, z1)
                umin, umx = min(umin, uv), max(umx, uv)
                t += h
                z[:] = z1
                if hit >= 0 or time_event:
                    break
                if t > t_max:
                    status = HORIZON
                    done = True
                    break
            if done:
                break
            if time_event:
                sidx += 1
                u_ol = sched_u[sidx]
                if mode == STATIC:
                    mode = _contact_mode(z, d, Kf, umax, open_loop, u_ol, Fz, Fu)
                    if mode == YIELDING:
                        steps += 1
                continue
        # handle the event
        code = codes[hit]
        prev = mode
        if code == EV_STOP:
            z[3] = 0.0
            d = max(d, -z[2])
            if t_first_stop != t_first_stop:
                t_first_stop = t
            mode = _contact_mode(z, d, Kf, umax, open_loop, u_ol, Fz, Fu)
        elif code == EV_YIELD:
            mode = YIELDING
        elif code == EV_LIFT:
            mode = FLIGHT
        elif code == EV_LAND:
            z[0] -= shift
            z[2] = -d
            shift = 0.0
            if z[3] < 0.0:
                mode = YIELDING
            else:
                z[3] = 0.0
                mode = _contact_mode(z, d, Kf, umax, open_loop, u_ol, Fz, Fu)
        elif code == EV_SAT_HIGH:
            regime = SAT_HIGH
        elif code == EV_SAT_LOW:
            regime = SAT_LOW
        else:
            regime = LINEAR
        if mode != prev:
            if mode == YIELDING:
                steps += 1
            elif mode == STATIC:
                T = t
                E_T = energy_of(z)
                act_T = act
            if not open_loop:
                regime = _classify(mode, z, Kf, umax)

    z[0] -= shift
    z[2] -= shift
    if status != REST_PROVEN and nseg < nrec:
        rec_t[nseg] = t
    out[O_DEPTH] = max(d, -z[2])  # the foot may still be creeping down if rest is unproven
    out[O_STEPS] = steps
    out[O_TSTOP] = t_first_stop
    out[O_T] = T
    out[O_UPEAK] = max(abs(umin), abs(umx))
    out[O_SMIN] = smin
    out[O_SMAX] = smax
    ftol = FEAS_TOL * max(1.0, s_lim)
    feas = status == REST_PROVEN and smin >= -ftol and smax <= s_lim + ftol
    out[O_FEAS] = 1.0 if feas else 0.0
    out[O_STATUS] = status
    out[O_E0] = E0
    out[O_ET] = E_T if status == REST_PROVEN else np.nan
    out[O_EGND] = 0.5 * d * d
    out[O_EACT] = act_T if (energy and status == REST_PROVEN) else np.nan
    out[O_NSEG] = nseg
    out[O_UMIN] = umin
    out[O_UMAX] = umx


@njit(cache=True, parallel=True)
def simulate_batch(A3s, B3s, Fzs, Fus, Ews, ridx, Kfs, umaxs, x0s, s_lims, t_max, max_seg,
                   energy, out):
    """Feedback-policy landings in parallel; row i uses mode matrices ``ridx[i]``."""
    n = x0s.shape[0]
    empty_t = np.zeros(0)
    rt = np.zeros(0)
    rA = np.zeros((0, 5, 5))
    rz = np.zeros((0, 5))
    rc = np.zeros((0, 5))
    rm = np.zeros(0, dtype=np.int64)
    for i in prange(n):
        r = ridx[i]
        simulate_one(A3s[r], B3s[r], Fzs[r], Fus[r], Ews[r], Kfs[i], umaxs[i], empty_t,
                     empty_t, x0s[i], s_lims[i], t_max, max_seg, energy, out[i], rt, rA, rz,
                     rc, rm)


# ------------------------------------------------------------ Python entry points
STATUS_NAMES = {
    REST_PROVEN: "rest proven",
    HORIZON: "horizon reached before rest could be proven",
    TOO_MANY_SEGMENTS: "segment limit reached before rest could be proven",
}
"""Human-readable name of each status code of ``out[O_STATUS]``."""


def run_landing(mats, Kf, umax, sched_t, sched_u, x0, s_lim, t_max, max_seg, energy):
    """One landing; returns the output row (layout ``O_*``) and the segment records.

    Parameters
    ----------
    mats : dict
        :func:`softlanding.model.dynamics.mode_matrices` of the robot and ground.
    Kf : (3, 5) array
        Feedback ``u = Kf[mode] . z`` per ground mode (ignored when open loop).
    umax : float
        Force limit (``inf`` for none).
    sched_t, sched_u : arrays (m,), (m + 1,)
        Open-loop schedule; empty ``sched_u`` means feedback.
    x0 : (4,) array
        Initial state.
    s_lim, t_max, max_seg, energy
        Stroke, horizon, segment limit, whether to compute the energy ledger.

    Returns
    -------
    out : (N_OUT,) array
    segments : dict
        ``t`` (n+1,), ``A`` (n, 5, 5), ``z`` (n, 5), ``cu`` (n, 5), ``mode`` (n,):
        segment start times (and the end time), closed-loop matrices, start
        states, control functionals and ground modes.
    """
    nrec = 32  # segment records; grown and re-run in the rare long case
    while True:
        out = np.zeros(N_OUT)
        rec_t = np.full(nrec + 1, np.nan)
        rec_A = np.empty((nrec, 5, 5))
        rec_z = np.empty((nrec, 5))
        rec_cu = np.empty((nrec, 5))
        rec_mode = np.empty(nrec, dtype=np.int64)
        simulate_one(mats["A"], mats["B"], mats["Fz"], mats["Fu"], mats["E"], Kf, umax, sched_t,
                     sched_u, x0, s_lim, t_max, max_seg, energy, out, rec_t, rec_A, rec_z,
                     rec_cu, rec_mode)
        if out[O_NSEG] < nrec:
            break
        nrec = max_seg + 1
    n = int(out[O_NSEG])
    return out, {"t": rec_t[: n + 1].copy(), "A": rec_A[:n].copy(), "z": rec_z[:n].copy(),
                 "cu": rec_cu[:n].copy(), "mode": rec_mode[:n].copy()}


def run_batch(mats_list, ridx, Kf, umax, x0, s_lim, t_max, max_seg, energy, out):
    """Feedback landings in parallel; row ``i`` uses ``mats_list[ridx[i]]``.

    ``Kf`` (n, 3, 5), ``umax`` (n,), ``x0`` (n, 4), ``s_lim`` (n,); fills ``out`` (n, N_OUT).
    """
    A3s = np.stack([m["A"] for m in mats_list])
    B3s = np.stack([m["B"] for m in mats_list])
    Fzs = np.stack([m["Fz"] for m in mats_list])
    Fus = np.array([m["Fu"] for m in mats_list])
    Ews = np.stack([m["E"] for m in mats_list])
    simulate_batch(A3s, B3s, Fzs, Fus, Ews, np.asarray(ridx, dtype=np.int64), Kf, umax, x0,
                   s_lim, float(t_max), int(max_seg), bool(energy), out)
