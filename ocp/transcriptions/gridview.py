"""How a transcribed solution's grid is read: shooting nodes, or collocation points and mesh.

A multiple-shooting solution holds one control per shooting interval and the
states at the nodes. A Radau collocation solution (:class:`ocp.Collocation`)
holds, on each of its ``N`` mesh intervals, ``d`` collocation points
``c_1 < ... < c_d = 1``: ``sol.t`` and ``sol.x`` are the start and every
collocation point (``N d + 1`` rows), ``sol.u`` the control at every
collocation point (``N d`` rows), and the multipliers include one block of
``N d`` collocation defects.

:func:`mesh_level` reads a collocation solution on its mesh, one control per
mesh interval as a shooting solution has: the quadrature average of the
control over the interval (exact for the Radau control polynomial), so that a
switch inside an interval shows as an average between the two bounds (its
position is where that average puts it), whatever the control does at the
individual points. :func:`collocation_costates` turns the defect multipliers
into costates at the collocation points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["MeshLevel", "collocation_costates", "is_collocation", "mesh_indices", "mesh_level",
           "quadrature_weights"]


def is_collocation(sol: Any) -> bool:
    """True when ``sol`` is a phase of a collocation solution (its points are not nodes).

    Parameters
    ----------
    sol : Solution
    """
    disc = getattr(sol, "discretization", None)
    return getattr(disc, "method", None) == "collocation"


def mesh_indices(sol: Any) -> np.ndarray:
    """Rows of ``sol.t`` that are mesh points (every ``d``-th: the last point ``c_d = 1``
    of each interval is the next mesh point); all rows for multiple shooting.

    Parameters
    ----------
    sol : Solution
    """
    if not is_collocation(sol):
        return np.arange(len(sol.t))
    return np.arange(0, len(sol.t), sol.discretization.d)


def quadrature_weights(sol: Any) -> np.ndarray:
    """Radau quadrature weight of every collocation point, on each interval normalised to
    length 1 (``B_j``, summing to 1 per interval), ``(N d,)``.

    Parameters
    ----------
    sol : Solution
        A collocation solution.
    """
    disc = sol.discretization
    return np.tile(np.asarray(disc.B, dtype=float), disc.N)


def collocation_costates(sol: Any) -> np.ndarray:
    """Costates at the collocation points of a Radau collocation solution, ``(N d, nx)``.

    The defect of point j of interval k is ``sum_r C_rj Z_kr - h_k f(Z_kj, U_kj)``
    with multiplier ``mu_kj`` in CasADi's Lagrangian ``J + lam_g^T g``; the cost
    enters as ``h_k B_j L(Z_kj, U_kj)``. Stationarity in ``Z_ki``, divided by
    ``h_k B_i``, is the adjoint equation ``lambda' = -L_x - f_x^T lambda`` at ``c_i``
    for ``lambda_ki = -mu_ki / B_i`` (Radau quadrature turns ``sum_j C_ij B_j
    lambda_j`` into ``-B_i lambda'(c_i)``, plus the end value at ``c_d = 1``,
    which the continuity multiplier cancels): the ``h_k`` of the dynamics and of
    the quadrature cancel. The continuity multipliers are then the same
    costate at the mesh points, as for multiple shooting.

    Parameters
    ----------
    sol : Solution
        A collocation solution.
    """
    mu = np.asarray(sol.multipliers["collocation"], dtype=float)
    return -mu / quadrature_weights(sol)[:, None]


@dataclass
class MeshLevel:
    """A collocation solution read on its mesh (the protocol :mod:`ocp.structure.arcs` reads).

    Attributes
    ----------
    source : Solution
        The collocation solution.
    t, x : ndarray
        Mesh times ``(N + 1,)`` and the states there.
    u : ndarray (N, nu)
        Per mesh interval, the quadrature average of the control over it.
    """

    source: Any
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray

    @property
    def problem(self) -> Any:
        """The phase's problem."""
        return self.source.problem

    @property
    def transcription(self) -> Any:
        """The transcription that solved it."""
        return self.source.transcription

    @property
    def T(self) -> float:
        """Final time."""
        return float(self.source.T)

    @property
    def N(self) -> int:
        """Mesh intervals."""
        return len(self.t) - 1

    @property
    def params(self) -> dict[str, float]:
        """Parameter values."""
        return self.source.params

    @property
    def multipliers(self) -> dict[str, np.ndarray]:
        """The source's multipliers (``continuity`` is per mesh interval)."""
        return self.source.multipliers

    @property
    def objective(self) -> float:
        """The objective."""
        return float(self.source.objective)

    def control(self, name: str) -> np.ndarray:
        """Interval averages of control ``name``.

        Parameters
        ----------
        name : str
        """
        return self.u[:, self.problem.control_names.index(name)]

    def evaluate(self, expr: ca.SX) -> np.ndarray:
        """``expr`` at the mesh points (the collocated control there; extrapolated at t0).

        Parameters
        ----------
        expr : SX
        """
        return np.asarray(self.source.evaluate(expr))[mesh_indices(self.source)]


def mesh_level(sol: Any) -> Any:
    """``sol`` read on its mesh (:class:`MeshLevel`) when it is a collocation solution;
    ``sol`` itself otherwise.

    Parameters
    ----------
    sol : Solution
    """
    if not is_collocation(sol):
        return sol
    d, N = sol.discretization.d, sol.discretization.N
    U = np.asarray(sol.u, dtype=float).reshape(N, d, -1)
    avg = np.einsum("j,kji->ki", np.asarray(sol.discretization.B, dtype=float), U)
    idx = mesh_indices(sol)
    return MeshLevel(sol, np.asarray(sol.t)[idx], np.asarray(sol.x)[idx], avg)


def grid_spacing(sol: Any) -> float:
    """The mean spacing of ``sol``'s grid: shooting intervals, or collocation *mesh*
    intervals (not collocation points), over the duration ``T - t0``.

    Parameters
    ----------
    sol : Solution
        A single-phase transcribed solution.

    Returns
    -------
    float
    """
    t0 = float(getattr(sol, "t0", 0.0) or 0.0)
    return (float(sol.T) - t0) / int(mesh_level(sol).N)
