"""The largest excess of every path constraint and state bound along a solution's interpolant.

A transcription imposes its path constraints and state bounds at finitely many points;
between them the trajectory is the method's interpolant (collocation: the state
polynomials and the control interpolant of
:meth:`ocp.transcriptions.collocation.CollocationPhase.interpolate`; multiple shooting: the
dynamics integrated from each node with the interval's constant control), and a sampled
check can step over a narrow peak (measured: the speed-limited double integrator's state
polynomial 3.2e-5 above its bound at t = 2.4975, between two of ten samples).

Here every mesh interval is split into pieces on which the interpolant is smooth (the
collocation control is a straight line before the first collocation point, a polynomial
after it), and each constraint row along each piece is interpolated in Chebyshev form at
``points`` Chebyshev-Lobatto points (chebfun's construction). A row that is a polynomial
of degree below ``points - 3`` along the piece -- a state bound or any polynomial
expression of the states of a collocation solution -- is represented exactly; for
another row the last three coefficients measure the representation's error, and a piece
where that error exceeds ``accuracy`` is bisected (at most :data:`MAX_DEPTH` times; kinks,
such as a control clipped at its bound, are resolved so). The maximum of each piece's
series is then located as a zero of its derivative (Newton's method from the best of a
dense sample of the series): rows whose series cannot reach their bound (the sum of the
coefficients' magnitudes bounds the series) are not searched.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.polynomial import chebyshev as C

MAX_DEPTH = 12
"""Most bisections of a piece whose row is not resolved to the accuracy asked for."""

DENSE = 48
"""Points of the dense sample of a piece's series that starts the search of its maximum."""

NEWTON_STEPS = 6
"""Newton steps on the series' derivative from the dense sample's best point."""


@dataclass
class PhaseExtrema:
    """Largest relative excess of each checked row in each mesh interval of one phase.

    Attributes
    ----------
    rows : list of int
        The rows of the phase's check function
        (:attr:`ocp.definition.compiled.CompiledPhase.check`).
    excess : ndarray, shape (len(rows), N)
        The largest excess over the bound along the interpolant, divided by
        ``max(1, |bound|)``; 0 where the row stays within its bounds, ``inf`` where it is
        not finite.
    time : ndarray, shape (len(rows), N)
        Where it is reached.
    """

    rows: list[int]
    excess: np.ndarray
    time: np.ndarray


@cache
def lobatto(points: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev-Lobatto points in [-1, 1] (increasing) and the matrix from values there
    to Chebyshev coefficients (read-only; computed once per count).

    Parameters
    ----------
    points : int
        Number of points (at least 2).
    """
    z = -np.cos(np.pi * np.arange(points) / (points - 1))
    to_coef = np.linalg.inv(C.chebvander(z, points - 1))
    z.setflags(write=False)
    to_coef.setflags(write=False)
    return z, to_coef


@cache
def _dense(points: int) -> np.ndarray:
    zd = -np.cos(np.pi * np.arange(DENSE) / (DENSE - 1))
    out = C.chebvander(zd, points - 1)
    out.setflags(write=False)
    return out


def series_max(coef: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Maximum over [-1, 1] of each Chebyshev series (rows of ``coef``) and where it is.

    Parameters
    ----------
    coef : ndarray, shape (n, K)
        Coefficients, one series per row.

    Returns
    -------
    tuple of ndarray
        ``(value, z)``, each of shape (n,).
    """
    K = coef.shape[1]
    zd = -np.cos(np.pi * np.arange(DENSE) / (DENSE - 1))
    dense = coef @ _dense(K).T
    j = np.argmax(dense, axis=1)
    z, best = zd[j].copy(), dense[np.arange(coef.shape[0]), j]
    d1 = C.chebder(coef, axis=1).T
    d2 = C.chebder(coef, 2, axis=1).T
    zn = z.copy()
    for _ in range(NEWTON_STEPS):  # to the zero of the derivative near the best sample
        g, hss = C.chebval(zn, d1, tensor=False), C.chebval(zn, d2, tensor=False)
        step = np.where(hss < 0, g / np.where(hss < 0, hss, -1.0), 0.0)
        zn = np.clip(zn - step, -1.0, 1.0)
    value = C.chebval(zn, coef.T, tensor=False)
    better = value > best
    return np.where(better, value, best), np.where(better, zn, z)


def phase_extrema(disc: Any, data: Any, rows: list[int], lo: np.ndarray, hi: np.ndarray,
                  points: int, accuracy: float) -> PhaseExtrema:
    """The largest excess of the rows ``rows`` in every mesh interval (see the module).

    Parameters
    ----------
    disc : PhaseDiscretization
        The phase's discretisation (its ``interpolate`` and ``check_values``).
    data : PhaseData
        The phase's solved arrays.
    rows : list of int
        Rows of the check function to search.
    lo, hi : ndarray
        Their bounds (``-inf``/``inf`` where none).
    points : int
        Chebyshev points per piece (at least 4).
    accuracy : float
        Error of a row's representation, relative to ``max(1, |bound|)``, above which a
        piece near its bound is bisected.
    """
    N = data.mesh.size - 1
    nr = len(rows)
    excess, time = np.zeros((nr, N)), np.tile(data.mesh[:-1], (nr, 1))
    if not nr:
        return PhaseExtrema(rows, excess, time)
    sides = _sides(lo, hi)
    k, a, b = disc.pieces(data)
    for depth in range(MAX_DEPTH + 1):
        last = depth == MAX_DEPTH
        split = _search(disc, data, rows, sides, (k, a, b), points, accuracy, last,
                        (excess, time))
        if not split.any():
            break
        k, a, b = k[split], a[split], b[split]
        mid = 0.5 * (a + b)
        k, a, b = np.r_[k, k], np.r_[a, mid], np.r_[mid, b]
    return PhaseExtrema(rows, excess, time)


def _sides(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray]:
    """The one-sided excess functions: (row position, sign, bound, scale) of each finite
    bound (``sign * (value - bound) / scale``)."""
    pos, sign, bound = [], [], []
    for r, (lo_r, hi_r) in enumerate(zip(lo, hi, strict=True)):
        if np.isfinite(hi_r):
            pos.append(r)
            sign.append(1.0)
            bound.append(hi_r)
        if np.isfinite(lo_r):
            pos.append(r)
            sign.append(-1.0)
            bound.append(lo_r)
    bnd = np.array(bound, dtype=float)
    return (np.array(pos, dtype=int), np.array(sign), bnd, np.maximum(1.0, np.abs(bnd)))


def _search(disc: Any, data: Any, rows: list[int], sides: tuple, pieces: tuple,
            points: int, accuracy: float, last: bool,
            out: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """One level: interpolate every piece, record the resolved maxima in ``out``; return
    which pieces must be bisected."""
    k, a, b = pieces
    pos, sign, bound, scale = sides
    z, to_coef = lobatto(points)
    P = k.size
    theta = a[:, None] + (b - a)[:, None] * (0.5 * (z + 1.0))[None, :]
    h = np.diff(data.mesh)
    vals = _values(disc, data, np.repeat(k, points), theta.ravel())[rows]  # (rows, P points)
    g = (sign[:, None] * (vals[pos] - bound[:, None]) / scale[:, None]).reshape(
        pos.size, P, points)
    finite = np.isfinite(g).all(axis=2)
    coef = np.where(finite[..., None], g, 0.0) @ to_coef.T  # (sides, P, points)
    tail = np.abs(coef[..., -3:]).max(axis=2)
    reach = coef[..., 0] + np.abs(coef[..., 1:]).sum(axis=2) + tail >= 0.0
    unresolved = finite & reach & (tail > accuracy)
    split = unresolved.any(axis=0) & (not last)
    settle = (reach | ~finite) & ~split[None, :]
    si, pi = np.nonzero(settle)
    if si.size:
        val = np.full(si.size, np.inf)
        zz = np.full(si.size, -1.0)
        ok = finite[si, pi]
        if ok.any():
            m, zm = series_max(coef[si[ok], pi[ok]])
            nodes = g[si[ok], pi[ok]].max(axis=1)  # the samples themselves, if higher
            val[ok], zz[ok] = np.maximum(m, nodes), zm
        tt = data.mesh[k[pi]] + h[k[pi]] * (a[pi] + (b[pi] - a[pi]) * 0.5 * (zz + 1.0))
        _record(out, pos[si], k[pi], val, tt)
    return split


def _record(out: tuple[np.ndarray, np.ndarray], r: np.ndarray, k: np.ndarray,
            val: np.ndarray, t: np.ndarray) -> None:
    """Keep, per (row, interval), the largest positive value found and its time."""
    excess, time = out
    order = np.argsort(val, kind="stable")  # the largest is written last
    r, k, val, t = r[order], k[order], val[order], t[order]
    keep = val > excess[r, k]
    excess[r[keep], k[keep]] = val[keep]
    time[r[keep], k[keep]] = t[keep]


def _values(disc: Any, data: Any, k: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """The check function along the interpolant at the fractions ``theta`` of intervals
    ``k``, shape (rows, n)."""
    t = data.mesh[k] + np.diff(data.mesh)[k] * theta
    n = k.size
    m = _padded(n)
    kp, thp = np.r_[k, np.repeat(k[-1:], m - n)], np.r_[theta, np.repeat(theta[-1:], m - n)]
    x, u = disc.interpolate(data, kp, thp)
    return check_at(disc, t, x[:n], u[:n], data.s)


def check_at(disc: Any, t: np.ndarray, x: np.ndarray, u: np.ndarray,
             s: np.ndarray) -> np.ndarray:
    """The check function of a phase at n points, shape (rows, n), evaluated on a count
    rounded up to a power of two (the mapped Functions are cached per count: a few serve
    every call).

    Parameters
    ----------
    disc : PhaseDiscretization
        The phase's discretisation.
    t, x, u : ndarray
        Times (n,), states (n, nx) and controls (n, nu).
    s : ndarray
        The phase's static vector.
    """
    n = t.size
    pad = _padded(n) - n
    if pad:
        t = np.r_[t, np.repeat(t[-1:], pad)]
        x = np.vstack([x, np.repeat(x[-1:], pad, axis=0)])
        u = np.vstack([u, np.repeat(u[-1:], pad, axis=0)])
    return disc.check_values(t, x, u, s)[:, :n]


def _padded(n: int) -> int:
    return max(64, 1 << int(np.ceil(np.log2(max(n, 1)))))
