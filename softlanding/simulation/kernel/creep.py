"""Proof that a yielding foot creeps toward a limit depth forever (it never stops).

When neither the dynamics nor the force depend on the body height ``x_b`` (no
stiffness: ``k_p = 0``), the yielding mode restricted to ``y = (v_b, x_f, v_f)``
is an autonomous affine system ``y' = M y + b``. If every eigenvalue of ``M``
has a negative real part, ``y`` tends to the equilibrium ``y*`` (with
``v_f* = 0``: ``x_f' = v_f`` is one of the rows) and every linear functional is

    g(t) = g* + sum_i a_i exp(lambda_i t),   a_i = (c . V_i) (V^-1 (y - y*))_i.

The proof is the closed form read with a margin:

* the foot never stops: the slowest eigenvalue ``lambda_1`` is real, strictly
  slower than the others, ``a_1 < 0`` for ``v_f`` and ``|a_1| > sum_{i>1} |a_i|``;
  then ``v_f(t) = exp(lambda_1 t) (a_1 + sum_{i>1} a_i exp((lambda_i - lambda_1) t)) < 0``
  for all ``t >= 0``, so the depth rises monotonically to ``L = -x_f*`` and never
  reaches it;
* no other event (saturation) can fire: ``g* + sum_i |a_i| < 0``;
* the stroke rate ``v_b - v_f`` keeps one sign forever (``|w*| > sum_i |a_i|``), so
  the stroke is monotone and unbounded (``v_b* != 0``: the body falls at a terminal
  speed): its future range is ``(-inf, now]`` or ``[now, inf)``;
* the force's future range ``[u* - sum |b_i|, u* + sum |b_i|]`` lies inside the hull
  of its past extrema and its limit ``u*``, so the force extrema are exact.

Every inequality must hold with a relative margin well above the rounding of
the eigen-decomposition (``1e-12`` times its condition number); otherwise the
march goes on and the proof is tried again one step later (the transients decay).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.np.linalg import F_INT_nptype

from softlanding.simulation.kernel.const import JIT

MARGIN = 1e-12  # relative margin per unit condition number of the eigenvectors

# LAPACK's zgeev, zgetrf and zgetri through numba's own C helpers, the calls np.linalg.eig,
# det and inv make (same routines, arguments and workspace queries: bitwise the same
# results), without compiling np.linalg's generic wrappers (finite checks, Fortran copies,
# error paths): they were about 2 s of the simulator's first compile. Each returns LAPACK's
# info (0: success).
_C, _N, _P = types.char, types.intp, types.voidptr
ZGEEV = types.ExternalFunction("numba_ez_cgeev", types.intc(_C, _C, _C, _N, _P, _N, _P, _P, _N,
                                                             _P, _N))
ZGETRF = types.ExternalFunction("numba_xxgetrf", types.intc(_C, _N, _N, _P, _N, _P))
ZGETRI = types.ExternalFunction("numba_ez_xxgetri", types.intc(_C, _N, _P, _N, _P))
KIND, NO, YES = ord("z"), ord("N"), ord("V")  # complex128; left vectors no, right yes


@njit(**JIT)
def _lt(a, b):
    """NumPy's sort order of floats (NaN last)."""
    return a < b or (np.isnan(b) and not np.isnan(a))


@njit(**JIT)
def _slowest_first(lam):
    """``np.argsort(-lam.real)`` of three eigenvalues, as NumPy's and numba's quicksort
    orders three items (an insertion sort)."""
    order = np.zeros(3, dtype=np.int64)
    order[1], order[2] = 1, 2
    for i in range(1, 3):
        k = order[i]
        v = -lam[k].real
        j = i
        while j > 0 and _lt(v, -lam[order[j - 1]].real):
            order[j] = order[j - 1]
            j -= 1
        order[j] = k
    return order[0], order[1], order[2]


@njit(**JIT)
def _norm_inf3(M):
    """``np.abs(M).sum(axis=1).max()`` of a complex 3 x 3 matrix (same sums, NaN first)."""
    big = 0.0
    for i in range(3):
        r = 0.0
        for j in range(3):
            r += abs(M[i, j])
        if np.isnan(r):
            return r
        if i == 0 or r > big:
            big = r
    return big


@njit(**JIT)
def eig3(A):
    """Eigenvalues and right eigenvectors of the 3 x 3 block ``A[1:4, 1:4]`` (as
    ``np.linalg.eig``): ``(info, w, vr)`` with eigenvector ``k`` in ``vr[3 k:3 k + 3]``."""
    a = np.empty(9, dtype=np.complex128)  # Fortran order
    for i in range(3):
        for j in range(3):
            a[3 * j + i] = A[1 + i, 1 + j]
    w = np.empty(3, dtype=np.complex128)
    vl = np.empty(3, dtype=np.complex128)  # not referenced (no left vectors)
    vr = np.empty(9, dtype=np.complex128)
    info = ZGEEV(KIND, NO, YES, 3, a.ctypes, 3, w.ctypes, vl.ctypes, 1, vr.ctypes, 3)
    return info, w, vr


@njit(**JIT)
def det_inv3(V):
    """Determinant and inverse of a complex 3 x 3 matrix by one LU factorisation, as
    ``np.linalg.det`` (the sign of the pivots times ``exp`` of the sum of the logs of the
    diagonal's moduli) and ``np.linalg.inv`` compute them: ``(info, det, inverse)``."""
    lu = np.empty(9, dtype=np.complex128)  # Fortran order
    for i in range(3):
        for j in range(3):
            lu[3 * j + i] = V[i, j]
    ipiv = np.empty(3, dtype=F_INT_nptype)
    inv = np.empty((3, 3), dtype=np.complex128)
    info = ZGETRF(KIND, 3, 3, lu.ctypes, 3, ipiv.ctypes)
    if info != 0:
        return info, 0.0j, inv
    swaps = 1
    for k in range(3):
        swaps = swaps + (ipiv[k] != (k + 1))
    csgn = 1.0 + 0.0j if swaps & 1 else -1.0 + 0.0j
    acc = 0.0
    for k in range(3):
        p = lu[4 * k]
        absel = np.abs(p)
        # p / absel as numba divides by the complex absel + 0j (CPython's algorithm, its
        # steps written out: numba's division, with its error paths, compiles slowly)
        ratio = 0.0 / absel
        den = absel + 0.0 * ratio
        csgn = csgn * complex((p.real + p.imag * ratio) / den, (p.imag - p.real * ratio) / den)
        acc = acc + np.log(absel)
    det = csgn * np.exp(acc)
    info = ZGETRI(KIND, 3, lu.ctypes, 3, ipiv.ctypes)
    for i in range(3):
        for j in range(3):
            inv[i, j] = lu[3 * j + i]
    return info, det, inv


@njit(**JIT)
def creep_candidate(A, cu, C, ne):
    """The first checks of :func:`creep_setup`: the yielding subsystem is free of ``x_b``
    and its eigenvalues have negative real parts. Returns ``(ok, eigenvalues,
    eigenvectors)`` as :func:`eig3` gives them (empty when not ``ok``)."""
    no = np.empty(0, dtype=np.complex128)
    for i in range(1, 4):
        if A[i, 0] != 0.0:
            return False, no, no
    if A[1, 1] == 0.0 and A[1, 2] == 0.0 and A[1, 3] == 0.0:
        return False, no, no  # the body's velocity is not restored: eigenvalue 0
    if A[2, 1] != 0.0 or A[2, 2] != 0.0 or A[2, 3] != 1.0 or A[2, 4] != 0.0:
        return False, no, no
    if cu[0] != 0.0:
        return False, no, no
    for k in range(ne):
        if C[k, 0] != 0.0:
            return False, no, no
    for i in range(3):
        for j in range(3):
            if not np.isfinite(A[1 + i, 1 + j]):
                return False, no, no
    info, lam0, V0 = eig3(A)
    if info != 0:
        return False, no, no
    for i in range(3):
        if not lam0[i].real < 0.0:
            return False, no, no
    return True, lam0, V0


@njit(**JIT)
def creep_setup(A, cu, C, ne, data):
    """Eigen-data of the ``x_b``-free yielding subsystem; returns False if not applicable.

    ``data`` (complex, 3 x 8) receives: column 0 the eigenvalues (slowest first),
    columns 1-3 the eigenvectors, columns 4-6 the inverse's rows (as columns of
    rows), column 7 the equilibrium ``y*`` and, in ``data[0, 7].imag``, the
    condition number of the eigenvectors.
    """
    ok, lam0, V0 = creep_candidate(A, cu, C, ne)
    if not ok:
        return False
    order = _slowest_first(lam0)
    lam = np.empty(3, dtype=np.complex128)
    V = np.empty((3, 3), dtype=np.complex128)
    for k in range(3):
        lam[k] = lam0[order[k]]
        for i in range(3):
            V[i, k] = V0[3 * order[k] + i]
    info, det, Vi = det_inv3(V)
    if info != 0 or not abs(det) > 1e-8:
        return False
    kappa = _norm_inf3(V) * _norm_inf3(Vi)
    # equilibrium: v_f* = 0 exactly (x_f' = v_f); then v_b*, x_f* from the other two rows
    # M[0,0] vb + M[0,1] xf = -b0 ; M[2,0] vb + M[2,1] xf = -b2
    a00, a01, a20, a21 = A[1, 1], A[1, 2], A[3, 1], A[3, 2]
    den = a00 * a21 - a01 * a20
    if den == 0.0 or not np.isfinite(den):
        return False
    b0, b2 = -A[1, 4], -A[3, 4]
    vb_eq = (b0 * a21 - a01 * b2) / den
    xf_eq = (a00 * b2 - b0 * a20) / den
    for i in range(3):
        data[i, 0] = lam[i]
        for j in range(3):
            data[i, 1 + j] = V[i, j]
            data[i, 4 + j] = Vi[i, j]
    data[0, 7] = complex(vb_eq, kappa)
    data[1, 7] = xf_eq
    data[2, 7] = 0.0
    return True


@njit(**JIT)
def _coeffs(data, z):
    """Modal coordinates ``V^-1 (y - y*)`` of the current state."""
    w0 = z[1] - data[0, 7].real
    w1 = z[2] - data[1, 7].real
    w2 = z[3]
    alpha = np.empty(3, dtype=np.complex128)
    for i in range(3):
        alpha[i] = data[i, 4] * w0 + data[i, 5] * w1 + data[i, 6] * w2
    return alpha


@njit(**JIT)
def _terms(data, alpha, c1, c2, c3):
    """Modal amplitudes ``a_i`` of the functional ``c1 v_b + c2 x_f + c3 v_f``."""
    a = np.empty(3, dtype=np.complex128)
    for i in range(3):
        a[i] = (c1 * data[0, 1 + i] + c2 * data[1, 1 + i] + c3 * data[2, 1 + i]) * alpha[i]
    return a


@njit(**JIT)
def _equilibrium_value(data, c):
    return c[1] * data[0, 7].real + c[2] * data[1, 7].real + c[4]


@njit(**JIT)
def creep_proof(data, z, C, ne, cu, ext_u, smin_smax):
    """True if, from ``z``, the foot creeps forever (see the module docstring).

    ``ext_u`` = (umin, umax) so far; ``smin_smax`` receives the stroke's future
    range folded in (``-inf`` or ``inf`` on the side it runs away to) and the
    force's limit, as ``[smin_new, smax_new, u_limit]`` (NaN if not proven).
    """
    kappa = data[0, 7].imag
    tol = MARGIN * max(kappa, 1.0)
    lam1 = data[0, 0]
    # a gap to the other eigenvalues makes lambda_1 real (its conjugate would share it)
    gap = lam1.real - max(data[1, 0].real, data[2, 0].real)
    if not (gap > 1e-9 * abs(lam1.real) and abs(lam1.imag) <= 1e-12 * abs(lam1.real)):
        return False
    alpha = _coeffs(data, z)
    # the foot never stops: v_f = sum a_i e^{lambda_i t}, dominated by a real a_1 < 0
    a = _terms(data, alpha, 0.0, 0.0, 1.0)
    rest = abs(a[1]) + abs(a[2])
    if not (a[0].real < 0.0 and abs(a[0].imag) <= tol * abs(a[0].real)
            and -a[0].real > rest + tol * (abs(a[0]) + rest)):
        return False
    # no other event can fire
    for k in range(1, ne):
        ck = C[k]
        a = _terms(data, alpha, ck[1], ck[2], ck[3])
        bound = abs(a[0]) + abs(a[1]) + abs(a[2])
        gs = _equilibrium_value(data, ck)
        if not gs + bound < -tol * (abs(gs) + bound):
            return False
    # the stroke rate keeps its sign: the stroke is monotone and unbounded
    a = _terms(data, alpha, 1.0, 0.0, -1.0)
    bound = abs(a[0]) + abs(a[1]) + abs(a[2])
    ws = data[0, 7].real
    if not abs(ws) > bound + tol * (abs(ws) + bound):
        return False
    # the force: inside the hull of its past extrema and its limit, or on one side of
    # its limit (dominant real term) and inside the hull on the other
    a = _terms(data, alpha, cu[1], cu[2], cu[3])
    bound = (abs(a[0]) + abs(a[1]) + abs(a[2])) * (1.0 + tol)
    us = _equilibrium_value(data, cu)
    lo, hi = min(ext_u[0], us), max(ext_u[1], us)
    if not (us - bound >= lo and us + bound <= hi):
        rest = abs(a[1]) + abs(a[2])
        if not (abs(a[0].real) > rest + tol * (abs(a[0]) + rest)):
            return False
        if a[0].real > 0.0 and not us + bound <= ext_u[1]:
            return False
        if a[0].real < 0.0 and not us - bound >= ext_u[0]:
            return False
    smin_smax[0] = -np.inf if ws < 0.0 else np.nan
    smin_smax[1] = np.inf if ws > 0.0 else np.nan
    smin_smax[2] = us
    return True


@njit(**JIT)
def creep_limit_depth(data):
    """The limit depth ``L = -x_f*`` of a proven creep."""
    return -data[1, 7].real
