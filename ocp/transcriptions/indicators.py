"""Where the objective's error lies, for the refinement rounds driven by the objective.

The local error estimates of :mod:`ocp.transcriptions.mesh` see the dynamics only. Two
other sources are located here:

* :func:`discrepancy` -- where a solution differs from another mesh's solution (the
  confirmation's, on the mesh halved): the coarser mesh's error lies there, whatever its
  kind (a control that kinks inside an interval, a junction);
* :func:`conservatism` -- what imposing the constraints at the Bernstein control points
  costs (``inner_constraints``): a polynomial whose control point sits on the bound is
  held below it by the gap between its control points and its own maximum, which costs
  the objective about the rows' multipliers times that gap (their sensitivity). The
  refinement shrinks those intervals, where the gap shrinks with their length.
"""

from __future__ import annotations

import numpy as np

from .discretization import segment_index
from .extrema import check_at
from .solution import Solution

CURVE_SAMPLES = 24
"""Samples of a flagged interval's rows along the polynomial for :func:`conservatism`."""


def discrepancy(sol: Solution, other: Solution) -> np.ndarray:
    """Per mesh interval of one phase of ``sol``, the largest difference between its states
    and those of the same phase of ``other`` (another mesh's solution) at both solutions'
    points, relative to ``1 + max |x|``.

    Parameters
    ----------
    sol, other : Solution
        One phase of each.
    """
    t = np.union1d(sol.t, other.t)
    x = sol.at(t)[0]
    worst = np.max(np.abs(other.at(t)[0] - x) / (1.0 + np.max(np.abs(x), axis=0)), axis=1)
    out = np.zeros(sol.mesh.size - 1)
    np.maximum.at(out, segment_index(sol.mesh, t), worst)
    return out


def conservatism(ph: Solution) -> np.ndarray:
    """Per mesh interval of one collocation phase, the objective's cost of imposing the
    constraints at the Bernstein control points (see the module; zero elsewhere).

    Parameters
    ----------
    ph : Solution
        One phase of a collocation solution.
    """
    disc, data = ph.discretization, ph.data
    out = np.zeros(data.mesh.size - 1)
    if getattr(disc, "Gin", None) is None:
        return out
    rows, idx = disc.checked_rows(), np.flatnonzero(disc.inner)
    n_in, N, d = disc.inner_theta.size, disc.N, disc.d
    lam = ph.multipliers["path_inner"].reshape(idx.size, n_in, len(rows)).sum(axis=1)
    nodes = np.concatenate([data.raw["X"][:N, None, :],
                            data.raw["Z"].reshape(N, d, -1)], axis=1)[idx]
    xc = np.einsum("ir,nrj->nij", disc.inner_states, nodes).reshape(idx.size * n_in, -1)
    at_cp = _rows_at(disc, data, idx, disc.inner_theta, xc, rows)
    on_curve = _rows_at(disc, data, idx, np.linspace(0.0, 1.0, CURVE_SAMPLES), None, rows)
    u_free = np.array([disc.cp.check_u_free[r] for r in rows])
    at_cp[~u_free] = -np.inf  # a row with controls is imposed on the curve: held at no cost
    with np.errstate(invalid="ignore"):
        upper = at_cp.max(axis=2) - on_curve.max(axis=2)
        lower = on_curve.min(axis=2) - np.where(np.isinf(at_cp), np.inf, at_cp).min(axis=2)
    gap = np.where(lam.T > 0, upper, np.where(lam.T < 0, lower, 0.0))  # (rows, flagged)
    out[idx] = np.sum(np.abs(lam.T) * np.maximum(gap, 0.0), axis=0)
    return out


def _rows_at(disc, data, idx: np.ndarray, theta: np.ndarray, x: np.ndarray | None,
             rows: list[int]) -> np.ndarray:
    """The checked rows at the fractions ``theta`` of the intervals ``idx``, with the
    interpolant's states or the states ``x``: shape (rows, len(idx), len(theta))."""
    k = np.repeat(idx, theta.size)
    th = np.tile(theta, idx.size)
    xi, u = disc.interpolate(data, k, th)
    t = data.mesh[k] + np.diff(data.mesh)[k] * th
    vals = check_at(disc, t, xi if x is None else x, u, data.s)[rows]
    return vals.reshape(len(rows), idx.size, theta.size)


def largest_share(e: np.ndarray, budget: float) -> np.ndarray:
    """The intervals that carry all of ``e``'s total but a part below ``budget`` (the
    smallest contributions are left out while they sum below it).

    Parameters
    ----------
    e : ndarray
        Nonnegative contributions.
    budget : float
        What may be left out.
    """
    order = np.argsort(e)
    left = np.cumsum(e[order]) <= budget
    out = np.ones(e.size, bool)
    out[order[left]] = False
    return out & (e > 0)
