"""Exact linear algebra of the affine modes: matrix exponential, propagation of a
state, event-time refinement on the exact solution, Van Loan Gramians.

Everything works on the augmented state ``z = [x_b, v_b, x_f, v_f, 1]`` and a
5x5 closed-loop matrix ``A`` whose last row is zero.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

from softlanding.simulation.kernel.const import JIT, MAX_SUBSTEPS

# BLAS dgemv through numba's own C helper: the call numba's ``M @ x`` makes for a C-ordered
# square ``M`` (``DGEMV(KIND_D, TRANS, n, n, alpha, M, n, x, beta, y)`` with ``alpha = 1``,
# ``beta = 0``: the transposed product on the Fortran view), so bitwise its result, without
# compiling ``np.dot``'s generic wrapper. Returns 0 on success.
DGEMV = types.ExternalFunction("numba_xxgemv", types.intc(
    types.char, types.char, types.intp, types.intp, types.voidptr, types.voidptr, types.intp,
    types.voidptr, types.voidptr, types.voidptr))
KIND_D, TRANS = ord("d"), ord("t")  # float64; the C-ordered matrix as its transpose


@njit(**JIT)
def norm_inf4(A):
    m = 0.0
    for i in range(4):
        r = 0.0
        for j in range(4):
            r += abs(A[i, j])
        m = max(m, r)
    return m


@njit(**JIT)
def expm(M, h):
    """exp(M h) by scaling and squaring of a Taylor series (M small and square)."""
    n = M.shape[0]
    nrm = 0.0
    for i in range(n):
        r = 0.0
        for j in range(n):
            r += abs(M[i, j])
        nrm = max(nrm, r)
    nrm *= abs(h)
    if not nrm < 1e300:
        out = np.empty((n, n))
        out[:, :] = np.nan
        return out  # no finite step map: the march will run out of budget
    sq = 0
    while nrm > 0.5:
        nrm *= 0.5
        sq += 1
    sc = h / 2.0**sq
    out = np.zeros((n, n))
    term = np.zeros((n, n))
    for i in range(n):
        out[i, i] = term[i, i] = 1.0
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
        out, tmp = tmp, out
    return out


@njit(**JIT, forceinline=True)
def dot(c, z):
    """``c . z`` for 5-vectors (arrays or tuples), summed in index order."""
    acc = 0.0
    acc += c[0] * z[0]
    acc += c[1] * z[1]
    acc += c[2] * z[2]
    acc += c[3] * z[3]
    acc += c[4] * z[4]
    return acc


@njit(**JIT, forceinline=True)
def row(C, k):
    """Row ``k`` of a (n, 5) array as a tuple (no array view, no reference counting)."""
    return (C[k, 0], C[k, 1], C[k, 2], C[k, 3], C[k, 4])


@njit(**JIT, forceinline=True)
def scaled(c, s):
    """The functional ``s c`` as a tuple."""
    return (s * c[0], s * c[1], s * c[2], s * c[3], s * c[4])


@njit(**JIT, forceinline=True)
def hermite_root(g0, d0, g1, d1, h):
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


@njit(**JIT)
def gram(A, Q, h):
    """int_0^h exp(A^T t) Q exp(A t) dt by Van Loan's block exponential."""
    C = np.zeros((10, 10))
    for i in range(5):
        for j in range(5):
            C[i, j] = -A[j, i]
            C[i, 5 + j] = Q[i, j]
            C[5 + i, 5 + j] = A[i, j]
    F = expm(C, h)
    G = np.zeros((5, 5))
    for i in range(5):
        for j in range(5):
            acc = 0.0
            for k in range(5):
                acc += F[5 + k, 5 + i] * F[k, 5 + j]
            G[i, j] = acc
    return G


@njit(**JIT)
def hull(lo, hi, v):
    return min(lo, v), max(hi, v)


# ---------------------------------------------------------- the march, on tuples
# The march and the event refinement run on tuples (a closed-loop matrix as a
# flat row-major 25-tuple, states and functionals as 5-tuples): numba passes
# them by value, so the innermost loops do no reference counting (which cost
# a third of the time when they ran on arrays).


@njit(**JIT, forceinline=True)
def flat25(A):
    """A 5x5 array as a flat row-major 25-tuple."""
    return (A[0, 0], A[0, 1], A[0, 2], A[0, 3], A[0, 4], A[1, 0], A[1, 1], A[1, 2], A[1, 3],
            A[1, 4], A[2, 0], A[2, 1], A[2, 2], A[2, 3], A[2, 4], A[3, 0], A[3, 1], A[3, 2],
            A[3, 3], A[3, 4], A[4, 0], A[4, 1], A[4, 2], A[4, 3], A[4, 4])


@njit(**JIT, forceinline=True)
def row5(v):
    """A 5-vector (array or tuple) as a 5-tuple."""
    return (v[0], v[1], v[2], v[3], v[4])


@njit(**JIT, forceinline=True)
def quad_t(G, z):
    """``z . G z`` for a flat 25-tuple ``G``."""
    acc = 0.0
    for i in range(5):
        for j in range(5):
            acc += z[i] * G[5 * i + j] * z[j]
    return acc


@njit(**JIT, forceinline=True)
def norm_rows4(A):
    """Largest absolute row sum (affine column included) of the first four rows of a flat
    25-tuple: sets the substeps of :func:`prop4_t`."""
    nrm = 0.0
    for i in range(4):
        r = 0.0
        for j in range(5):
            r += abs(A[5 * i + j])
        nrm = max(nrm, r)
    return nrm


@njit(**JIT, forceinline=True)
def matvec_t(M, z):
    """``M z`` for a flat 25-tuple ``M``, as a 5-tuple (each row summed as :func:`dot`)."""
    return (dot(M[0:5], z), dot(M[5:10], z), dot(M[10:15], z), dot(M[15:20], z),
            dot(M[20:25], z))


@njit(**JIT, forceinline=True)
def prop4_t(A, nrm, z, h):
    """the Taylor series on a flat 25-tuple ``A`` with its :func:`norm_rows4` ``nrm``."""
    if not nrm * abs(h) <= MAX_SUBSTEPS:
        return (np.nan, np.nan, np.nan, np.nan, z[4])  # scales beyond any sensible landing
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
            n0 = (A[0] * t0 + A[1] * t1 + A[2] * t2 + A[3] * t3
                  + (A[4] * x4 if k == 1 else 0.0)) * f
            n1 = (A[5] * t0 + A[6] * t1 + A[7] * t2 + A[8] * t3
                  + (A[9] * x4 if k == 1 else 0.0)) * f
            n2 = (A[10] * t0 + A[11] * t1 + A[12] * t2 + A[13] * t3
                  + (A[14] * x4 if k == 1 else 0.0)) * f
            n3 = (A[15] * t0 + A[16] * t1 + A[17] * t2 + A[18] * t3
                  + (A[19] * x4 if k == 1 else 0.0)) * f
            t0, t1, t2, t3 = n0, n1, n2, n3
            a0 += t0
            a1 += t1
            a2 += t2
            a3 += t3
            if abs(t0) + abs(t1) + abs(t2) + abs(t3) <= 1e-17 * scale:
                break
        x0, x1, x2, x3 = a0, a1, a2, a3
    return (x0, x1, x2, x3, x4)


@njit(**JIT, forceinline=True)
def covector_t(c, A):
    """The row vector ``c A`` for a flat 25-tuple ``A`` (:func:`flat25`), as a tuple: the
    functional giving d/dt (c . z) when z' = A z."""
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    d3 = 0.0
    d4 = 0.0
    for i in range(5):
        d0 += c[i] * A[5 * i]
    for i in range(5):
        d1 += c[i] * A[5 * i + 1]
    for i in range(5):
        d2 += c[i] * A[5 * i + 2]
    for i in range(5):
        d3 += c[i] * A[5 * i + 3]
    for i in range(5):
        d4 += c[i] * A[5 * i + 4]
    return (d0, d1, d2, d3, d4)


@njit(**JIT, forceinline=True)
def refine_t(A, nrm, z, c, a, b, ga, gb, rtol=2e-15, s0=-1.0):
    """First time s in (a, b] with g(s) = c . exp(A s) z > 0, given g(a) <= 0 < g(b).

    Newton on the exact solution, safeguarded by the bracket, converged to
    about 1e-15; the returned time lies on the far side of the crossing (the
    event has happened), so the next segment starts strictly inside its regime.
    ``A`` is a flat 25-tuple with norm ``nrm``; ``z`` and ``c`` are 5-tuples.
    """
    dc = covector_t(c, A)
    if a < s0 < b:
        s = s0
    else:
        s = a - ga * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
    for _ in range(100):
        xs = prop4_t(A, nrm, z, s)
        g = dot(c, xs)
        if g > 0.0:
            b = s
        else:
            a = s
        if b - a <= rtol * max(1.0, abs(b)):
            break
        dg = dot(dc, xs)
        sn = s - g / dg if dg != 0.0 else 0.5 * (a + b)
        sn, stalled = bracketed_step(sn, s, g, a, b, 0.5 * rtol * max(1.0, abs(s)))
        if stalled:
            break
        s = sn
    return b


@njit(**JIT, forceinline=True)
def bracketed_step(sn, s, g, a, b, tol):
    """The next iterate of a root search safeguarded by the bracket ``(a, b)``: ``sn``, or
    the bisection where ``sn`` leaves the bracket; where it moves from ``s`` by at most
    ``tol`` (converged), a step just past the root (``g``: the value at ``s``) to close
    the bracket. Returns the iterate and whether the search stalls (that step is ``s``)."""
    if not (a < sn < b):
        sn = 0.5 * (a + b)
    if abs(sn - s) <= tol:
        step = 1e-15 * max(1.0, abs(sn))
        sn = sn + step if g <= 0.0 else sn - step
        sn = min(max(sn, a), b)
        if sn == s:
            return sn, True
    return sn, False


@njit(**JIT, forceinline=True)
def interior_extremum_t(A, nrm, z, z1, h, c, dc, ddc):
    """Value of q = c . z at its turning point inside (0, h), or NaN if none.

    A turning point is a sign change of q' = dc . z; its time is refined from a
    Hermite starting guess (q'' = ddc . z) to 1e-9: the value's error is
    quadratic in the time's. All arguments are tuples (see :func:`refine_t`).
    """
    d0 = dot(dc, z)
    d1 = dot(dc, z1)
    if d0 == 0.0 and h > 0.0:
        # q' is exactly 0 at the step's start (the stroke rate at impact, v_b = v_f); a
        # turning point inside the step is bracketed from a hair inside it instead (the
        # start's own value the caller counts already)
        e = 1e-9 * h
        z = prop4_t(A, nrm, z, e)
        h = h - e
        d0 = dot(dc, z)
    if not ((d0 > 0.0 and d1 < 0.0) or (d0 < 0.0 and d1 > 0.0)):
        return np.nan
    sg = 1.0 if d0 < 0.0 else -1.0
    s0 = hermite_root(sg * d0, sg * dot(ddc, z), sg * d1, sg * dot(ddc, z1), h)
    se = refine_t(A, nrm, z, scaled(dc, sg), 0.0, h, sg * d0, sg * d1, 1e-9, s0)
    return dot(c, prop4_t(A, nrm, z, se))
