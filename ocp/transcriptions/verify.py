"""Post-solve check of path constraints and state bounds between the nodes.

A transcription imposes path constraints at finitely many points (shooting
nodes, integrator steps, collocation points). Between them the trajectory can
leave the feasible set while Ipopt reports success: a state that must stay
outside a band can dive through it between two nodes. After every solve the
largest value of every path constraint and state bound along the solution's own
interpolant -- the one ``sol.sample`` returns (multiple shooting: the dynamics
integrated from each node with the interval's constant control; collocation: the
state polynomials and the control interpolant of
:meth:`ocp.transcriptions.collocation.CollocationPhase.interpolate`) -- is located in
every mesh interval (:mod:`ocp.transcriptions.extrema`: exact for a row that is a
polynomial along the interpolant, such as a state bound of a collocation solution,
resolved to a thousandth of ``verify_tol`` otherwise), not sampled.

With collocation, a constraint on the controls alone (``u1 + u2 <= 1``) bounds the
control set, and between the points there is no other control than that
interpolant, which at a switch inside an interval swings across it: such a row is
checked at the collocation points only, where it is imposed, and named in
``sol.unchecked`` -- the verdict does not cover it between the points.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..definition.errors import PathViolationError, PathViolationWarning
from . import extrema
from .extrema import PhaseExtrema

VERIFY_MODES = ("warn", "raise", "off")


ACCURACY = 1e-3
"""The maxima are located to this fraction of the check's tolerance (relative to the bound)."""


def phase_extrema(ph: Any, params: dict[str, float], points: int,
                  tol: float) -> PhaseExtrema:
    """The largest relative excess of every checked row of one phase in each interval.

    Parameters
    ----------
    ph : Solution
        One phase of a solution.
    params : dict
        The parameter values.
    points : int
        Chebyshev points per piece of an interval (the transcription's ``verify_points``).
    tol : float
        The check's tolerance: the maxima are located to :data:`ACCURACY` times it.
    """
    disc = ph.discretization
    rows = disc.checked_rows()
    pv = np.array([params[k] for k in disc.cp.phase.param_names], dtype=float)
    clo, chi = disc.check_bounds(pv)[2:]
    return extrema.phase_extrema(disc, ph.data, rows, clo[rows], chi[rows], max(points, 4),
                                 ACCURACY * tol)


def unchecked_rows(sol: Any) -> list[str]:
    """Names of the path constraints checked at the collocation points only (see the module).

    Parameters
    ----------
    sol : Solution
        A solution (single- or multi-phase).
    """
    out = []
    for ph in sol.phases:
        prefix = f"{ph.problem.name}: " if sol.is_multiphase else ""
        disc = ph.discretization
        out += [prefix + disc.cp.check_names[i] for i in disc.control_only_rows()]
    return out


def path_excess(sol: Any, points: int = 10,
                tol: float = 1e-6) -> dict[str, tuple[float, float]]:
    """Largest relative violation of each path constraint and state bound along the
    solution's interpolant (see the module).

    Parameters
    ----------
    sol : Solution
        A solution (single- or multi-phase).
    points : int
        Chebyshev points per piece of an interval (:mod:`ocp.transcriptions.extrema`).
    tol : float
        The tolerance the violations are judged by: they are located to
        :data:`ACCURACY` times it.

    Returns
    -------
    dict
        ``name -> (violation, time)`` for every violated row, where the
        violation is the excess over the bound divided by ``max(1, |bound|)``
        (infinite where the trajectory is not finite).
    """
    out: dict[str, tuple[float, float]] = {}
    for ph in sol.phases:
        ext = phase_extrema(ph, sol.params, points, tol)
        prefix = f"{ph.problem.name}: " if sol.is_multiphase else ""
        for r, i in enumerate(ext.rows):
            j = int(np.argmax(ext.excess[r]))
            if ext.excess[r, j] > 0:
                out[prefix + ph.discretization.cp.check_names[i]] = (
                    float(ext.excess[r, j]), float(ext.time[r, j]))
    return out


def interval_excess(ph: Any, params: dict[str, float], points: int = 10,
                    tol: float = 1e-6) -> np.ndarray:
    """Largest relative path violation inside each mesh interval of one phase, shape (N,).

    Parameters
    ----------
    ph : Solution
        One phase of a solution.
    params : dict
        The parameter values.
    points : int
        Chebyshev points per piece of an interval.
    tol : float
        The tolerance the violations are judged by (see :func:`path_excess`).
    """
    ext = phase_extrema(ph, params, points, tol)
    if not ext.rows:
        return np.zeros(ph.data.mesh.size - 1)
    return ext.excess.max(axis=0)


def verify(sol: Any, mode: str, tol: float, points: int) -> None:
    """Set ``sol.path_violation``, ``sol.violations`` and ``sol.verified``; warn or raise.

    Parameters
    ----------
    sol : Solution
        A converged solution.
    mode : {"warn", "raise", "off"}
        What to do when a violation exceeds ``tol``.
    tol : float
        Allowed relative violation.
    points : int
        Chebyshev points per piece of an interval.
    """
    if mode == "off":
        return
    viol = path_excess(sol, points, tol)
    worst = max((v for v, _ in viol.values()), default=0.0)
    bad = {k: v for k, v in viol.items() if v[0] > tol}
    sol.path_violation = worst
    sol.violations = bad
    sol.verified = not bad
    sol.unchecked = unchecked_rows(sol)
    if not bad or not sol.success:
        return
    what = "; ".join(f"{k} by {v:.3g} at t={t:.6g}" for k, (v, t) in
                     sorted(bad.items(), key=lambda kv: -kv[1][0])[:3])
    msg = (f"Ipopt reports {sol.status}, but between the nodes {what} (tolerance {tol:g}); "
           "refine the grid, impose constraints between the points (inner_constraints=True) "
           "or use collocation with mesh refinement")
    if mode == "raise":
        raise PathViolationError("Path_Violated_Between_Nodes", sol, msg)
    warnings.warn(msg, PathViolationWarning, stacklevel=3)
