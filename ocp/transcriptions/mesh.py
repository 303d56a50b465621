"""Mesh refinement for collocation: an error estimate per interval and an h-method.

Error estimate (after Patterson, Hager and Rao's ph method in GPOPS-II): on
every mesh interval, evaluate the solution's state and control polynomials at
the ``d + 1`` Radau points of one degree higher, evaluate the dynamics there,
and integrate them with that higher-degree quadrature from the interval's
start. The largest difference between this integral and the state polynomial,
relative to ``1 + max |x_i|`` over the phase, is the interval's error; the
same comparison of the running cost's and integrals' quadratures (relative to
``1 + |their total|``) is added.

Objective error: the comparison above sees only quadrature error, and a
collocated solution can be exact for its own piecewise-polynomial control yet
sub-optimal: a control that jumps inside an interval (bang-bang, an L1 cost)
is represented by a polynomial there, the states and the cost quadrature
agree with it, and the objective is still off by more than the state
tolerance (measured: 7.9e-6 on the minimum-fuel double integrator with every
interval's estimate below 1e-6). Only a comparison between meshes sees it,
so :func:`objective_change` takes the change of the objective between
successive meshes (a Cauchy estimate: for a converging sequence it bounds the
error of the coarser mesh's value and usually over-estimates the finer one's;
the larger of the last two changes, since one alone can miss an unrefined
interval), and
:func:`objective_threshold` picks the intervals to split when the objective,
not the states, is what misses its tolerance: those whose local estimate is
within the factor ``target / change`` (between 1/100 and 1/2) of the largest (the objective's error
is assumed to come from where the local errors are largest; measured on
bang-bang and L1 problems, the switching intervals).

Refinement (h): every interval whose error exceeds the tolerance is split into
``n = clip(ceil((e / tol)^(1 / (d + 1))), 2, max_split)`` equal parts (the
local error of a degree-``d`` interpolant scales as ``h^(d+1)``); a new NLP
is built on the new mesh and solved from the previous solution resampled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from .collocation import CollocationPhase, radau_points


@dataclass
class MeshRound:
    """One solve of a mesh-refinement run.

    ``objective_error`` is the estimate of :func:`objective_change` (``inf``
    on the first mesh: nothing to compare with); ``refined_for`` says which
    criterion made the refinement go on after this round: ``"state"`` (an
    interval's estimate above ``tol``), ``"objective"`` (the states met
    ``tol``, the objective's estimate did not meet ``objective_tol``) or
    ``""`` (the last round).

    Attributes
    ----------
    intervals : list of int
        Mesh intervals per phase.
    max_error : float
        Largest interval error estimate.
    objective : float
        The round's objective.
    iterations, solve_time
        Ipopt's iterations and time.
    objective_error, refined_for
        As above.
    kind : {"refine", "confirm"}
        A refinement round, or the confirmation of the round before on its mesh
        halved (:mod:`ocp.transcriptions.refinement`; its ``objective_error`` is the
        estimate of the previous round's objective error).
    """

    intervals: list[int]  # per phase
    max_error: float
    objective: float
    iterations: int
    solve_time: float
    objective_error: float = math.inf
    refined_for: str = ""
    kind: str = "refine"


ONE_CHANGE_MARGIN = 3.0
"""With two meshes only, the objective's error estimate is this times their change."""


def objective_change(previous: list[float], current: float) -> float:
    """Estimate of the objective's discretisation error from the objectives of the meshes.

    The larger of the last two changes ``|J_r - J_r-1|`` and ``|J_r-1 - J_r-2|``:
    one change can be small because the last round split only some of the
    intervals that carry the error (measured: 2.4e-7 for an error of 6.2e-7),
    two in a row rarely are. With two meshes only, :data:`ONE_CHANGE_MARGIN`
    times their one change.

    Parameters
    ----------
    previous : list of float
        The objectives on the earlier (coarser) meshes, in order.
    current : float
        The objective on this mesh.

    Returns
    -------
    float
        The estimate; ``inf`` on the first mesh (nothing to compare with).
    """
    values = [*previous[-2:], current]
    if len(values) < 2 or not all(math.isfinite(v) for v in values):
        return math.inf
    if len(values) == 2:  # one change only: the under-estimate measured above, with margin
        return ONE_CHANGE_MARGIN * abs(values[1] - values[0])
    return float(np.max(np.abs(np.diff(values))))


def objective_threshold(max_error: float, change: float, target: float) -> float:
    """Local-error threshold above which an interval is split for the objective.

    The largest local error is asked to shrink by the factor the objective's
    error must shrink by (``target / change``), at most 1/2 so that the worst
    intervals are always split (1/2 when the change is unknown) and at least
    1/100 so that one round splits only the two decades of intervals with the
    largest errors: a far-off objective is approached over several rounds
    rather than by refining everywhere at once (measured: 215 intervals
    instead of 1998 on a path constraint touched between nodes, same result).

    Parameters
    ----------
    max_error : float
        The largest interval error estimate.
    change : float
        The objective's error estimate (:func:`objective_change`).
    target : float
        The objective's allowed absolute error.
    """
    factor = 0.5 if not math.isfinite(change) or change <= 0 else min(0.5, target / change)
    return max_error * max(factor, 1e-2)


def integration_matrix(nodes: np.ndarray) -> np.ndarray:
    """``I[l, m] = int_0^{nodes_l} ell_m(s) ds`` for the Lagrange basis on ``nodes``.

    Parameters
    ----------
    nodes : ndarray
        Interpolation nodes in [0, 1].
    """
    n = nodes.size
    out = np.zeros((n, n))
    for m in range(n):
        poly = np.poly1d([1.0])
        for r in range(n):
            if r != m:
                poly *= np.poly1d([1.0, -nodes[r]]) / (nodes[m] - nodes[r])
        out[:, m] = np.polyint(poly)(nodes)
    return out


@cache
def estimate_matrix(d: int) -> tuple[np.ndarray, np.ndarray]:
    """The degree-``d + 1`` Radau points of the error estimate and their
    :func:`integration_matrix` (read-only; computed once per degree ``d``).

    Parameters
    ----------
    d : int
        The collocation degree.
    """
    ch = np.array(radau_points(d + 1))
    Ihat = integration_matrix(ch)
    ch.setflags(write=False)
    Ihat.setflags(write=False)
    return ch, Ihat


def interval_errors(ph: Any) -> np.ndarray:
    """Relative error estimate of every mesh interval of a collocation phase solution.

    Parameters
    ----------
    ph : Solution
        One phase of a collocation solution.

    Returns
    -------
    ndarray, shape (N,)
        The error estimate per mesh interval (see the module docstring).
    """
    disc: CollocationPhase = ph.discretization
    data, N, d = ph.data, disc.N, disc.d
    ch, Ihat = estimate_matrix(d)
    mesh, h = data.mesh, np.diff(data.mesh)
    k = np.repeat(np.arange(N), d + 1)
    theta = np.tile(ch, N)
    x, u = disc.local(data, k, theta)
    t = mesh[k] + h[k] * theta
    f, qd = disc.cp.ode.map(t.size)(t[None, :], x.T, u.T, data.s)
    F = np.array(f, dtype=float).T.reshape(N, d + 1, -1)
    Xint = data.raw["X"][:N, None, :] + h[:, None, None] * np.einsum("lm,kmi->kli", Ihat, F)
    scale = 1.0 + np.max(np.abs(data.x), axis=0)
    err = np.max(np.abs(Xint - x.reshape(N, d + 1, -1)) / scale, axis=(1, 2))
    if disc.cp.nq:
        Q = np.array(qd, dtype=float).T.reshape(N, d + 1, -1)
        q_hat = h[:, None] * np.einsum("m,kmi->ki", Ihat[-1], Q)
        tc = data.t[1:]
        _, qc = disc.cp.ode.map(tc.size)(tc[None, :], data.x[1:].T, data.u.T, data.s)
        Qc = np.array(qc, dtype=float).T.reshape(N, d, -1)
        q_col = h[:, None] * np.einsum("j,kji->ki", disc.B, Qc)
        qscale = 1.0 + np.abs(q_col.sum(axis=0))
        err = np.maximum(err, np.max(np.abs(q_hat - q_col) / qscale, axis=1))
    return err


def mesh_error(sol: Any) -> float:
    """The largest interval error estimate of a collocation solution, over its phases.

    Parameters
    ----------
    sol : Solution
        A collocation solution.
    """
    return float(max(interval_errors(ph).max() for ph in sol.phases))


def refine_mesh(tau: np.ndarray, err: np.ndarray, tol: float, degree: int,
                max_split: int = 8) -> np.ndarray:
    """Split every interval whose error exceeds ``tol`` (normalised mesh in, mesh out).

    Parameters
    ----------
    tau : ndarray, shape (N+1,)
        Normalised mesh points.
    err : ndarray, shape (N,)
        Error estimate per interval.
    tol : float
        Requested accuracy.
    degree : int
        Collocation degree ``d``.
    max_split : int
        Most pieces an interval is split into per round.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.isfinite(err), err / tol, np.inf)
        n = np.ceil(ratio ** (1.0 / (degree + 1)))
    n = np.where(err > tol, np.clip(np.nan_to_num(n, nan=max_split, posinf=max_split), 2,
                                    max_split), 1).astype(int)
    starts = np.repeat(tau[:-1], n)
    widths = np.repeat(np.diff(tau) / n, n)
    frac = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 1
    return np.r_[tau[0], starts + widths * frac]
