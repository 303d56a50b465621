"""Where the objective's error lies, for the refinement rounds driven by the objective.

The local error estimates of :mod:`ocp.transcriptions.mesh` see the dynamics only. Imposing
the constraints at the Bernstein control points (``inner_constraints``) has a cost they do
not see (:func:`conservatism`): a polynomial whose control point sits on the bound is held
below it by the gap between its control points and its own maximum, which costs the
objective about the rows' multipliers (their sensitivity) times that gap. Refinement
shrinks those intervals, where the gap shrinks with the square of their length.
"""

from __future__ import annotations

import numpy as np

from .extrema import check_at
from .solution import Solution

CURVE_SAMPLES = 24
"""Samples of a flagged interval's rows along the polynomial for :func:`conservatism`."""


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
    n_in = disc.inner_theta.size
    lam = ph.multipliers["path_inner"].reshape(idx.size, n_in, len(rows)).sum(axis=1)
    nodes = disc.node_values(data)[idx]
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
