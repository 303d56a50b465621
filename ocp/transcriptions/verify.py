"""Post-solve check of path constraints and state bounds between the nodes.

A transcription imposes path constraints at finitely many points (shooting
nodes, integrator steps, collocation points). Between them the trajectory can
leave the feasible set while Ipopt reports success: a state that must stay
outside a band can dive through it between two nodes. After every solve the
trajectory is therefore sampled on a fine grid (multiple shooting: re-integrated
from each node with the interval's constant control; collocation: the state
polynomials) and every path constraint and state bound is evaluated there.

With collocation, a constraint that involves a control and a state (a heating
limit ``q(h, v, alpha) <= 70``) is checked between the points with the
method's own control there, never extrapolated: the Lagrange polynomial
through the interval's values at its collocation points (the one the state
polynomial is collocated with) from its first point on, a straight line from
the previous interval's last point before it
(:meth:`ocp.transcriptions.collocation.CollocationPhase.check_samples`), held
within the control's bounds. A constraint on the controls alone
(``u1 + u2 <= 1``) bounds the control set, and between the points there is no
other control than that interpolant, which at a switch inside an interval
swings across it: such a row is checked at the collocation points only, where
it is imposed, and named in ``sol.unchecked`` -- the verdict does not cover it
between the points.
"""

from __future__ import annotations

import warnings
import weakref
from typing import Any

import numpy as np

from ..definition.errors import PathViolationError, PathViolationWarning

VERIFY_MODES = ("warn", "raise", "off")


_ROWS: weakref.WeakKeyDictionary[Any, tuple[set[int], list[int]]] = \
    weakref.WeakKeyDictionary()
"""Per discretisation: its control-only rows and the rows checked between the points
(they depend on the compiled phase only: derived once, not at every solve)."""

_BOUNDS: weakref.WeakKeyDictionary[Any, tuple[bytes, tuple[np.ndarray, ...]]] = \
    weakref.WeakKeyDictionary()
"""Per compiled phase: the last parameter values' control bounds and check-row bounds."""


def _rows(disc: Any) -> tuple[set[int], list[int]]:
    """The control-only rows of a discretisation and the rows it checks between points."""
    if disc not in _ROWS:
        only_u = _control_only(disc)
        _ROWS[disc] = (only_u, [i for i in range(disc.cp.ncheck) if i not in only_u])
    return _ROWS[disc]


def _check_bounds(cp: Any, params: dict[str, float]) -> tuple[np.ndarray, ...]:
    """``(ulo, uhi, clo, chi)`` of a compiled phase at these parameter values (the last
    values' kept: a re-solve at the same values does not evaluate them again)."""
    pv = np.array([params[k] for k in cp.phase.param_names], dtype=float)
    key = pv.tobytes()
    last = _BOUNDS.get(cp)
    if last is None or last[0] != key:
        b = cp.bounds(pv)
        arrays = tuple(np.array(b[i], dtype=float).ravel() for i in (4, 5, 6, 7))
        for a in arrays:
            a.setflags(write=False)
        last = _BOUNDS[cp] = (key, arrays)
    return last[1]


def _phase_excess(ph: Any, params: dict[str, float],
                  per_interval: int) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Relative excess (rows, points) of one phase's checked rows, the times, the rows."""
    disc = ph.discretization
    rows = _rows(disc)[1]
    if not rows:
        t = disc.check_points(ph.data, per_interval)
        return np.zeros((0, t.size)), t, rows
    t, x, u = disc.check_samples(ph.data, per_interval)
    ulo, uhi, clo, chi = _check_bounds(disc.cp, params)
    if disc.method != "multiple_shooting" and u.size:  # the interpolant, within the bounds
        u = np.clip(u, ulo, uhi)
    vals = disc.check_values(t, x, u, ph.data.s)[rows]
    lo = clo[rows, None]
    hi = chi[rows, None]
    with np.errstate(invalid="ignore"):
        excess = np.maximum(np.maximum(lo - vals, vals - hi), 0.0)
        scale = np.maximum(1.0, np.where(vals < lo, np.abs(lo), np.abs(hi)))
        rel = np.where(np.isfinite(vals), excess / np.where(np.isfinite(scale), scale, 1),
                       np.inf)
    return rel, t, rows


def control_only_rows(disc: Any) -> set[int]:
    """Rows of a collocation phase's check that depend on the controls and not on the
    states: checked at the collocation points only (see the module; empty for shooting).

    Parameters
    ----------
    disc : PhaseDiscretization
        The phase's discretisation.
    """
    return set(_rows(disc)[0])


def _control_only(disc: Any) -> set[int]:
    cp = disc.cp
    if disc.method == "multiple_shooting" or cp.nu == 0:
        return set()
    on_x = set(cp.check.jac_sparsity(0, 1).get_triplet()[0])
    return {i for i in range(cp.ncheck) if not cp.check_u_free[i] and i not in on_x}


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
        out += [prefix + disc.cp.check_names[i] for i in sorted(control_only_rows(disc))]
    return out


def path_excess(sol: Any, per_interval: int = 10) -> dict[str, tuple[float, float]]:
    """Largest relative violation of each path constraint and state bound on a fine grid.

    Parameters
    ----------
    sol : Solution
        A solution (single- or multi-phase).
    per_interval : int
        Check points per shooting interval or collocation mesh interval.

    Returns
    -------
    dict
        ``name -> (violation, time)`` for every violated row, where the
        violation is the excess over the bound divided by ``max(1, |bound|)``
        (infinite where the trajectory is not finite).
    """
    out: dict[str, tuple[float, float]] = {}
    for ph in sol.phases:
        rel, t, rows = _phase_excess(ph, sol.params, per_interval)
        prefix = f"{ph.problem.name}: " if sol.is_multiphase else ""
        for r, i in enumerate(rows):
            j = int(np.argmax(rel[r]))
            if rel[r, j] > 0:
                out[prefix + ph.discretization.cp.check_names[i]] = (float(rel[r, j]),
                                                                     float(t[j]))
    return out


def interval_excess(ph: Any, params: dict[str, float], per_interval: int = 10) -> np.ndarray:
    """Largest relative path violation inside each mesh interval of one phase, shape (N,).

    Parameters
    ----------
    ph : Solution
        One phase of a solution.
    params : dict
        The parameter values.
    per_interval : int
        Check points per mesh interval.
    """
    rel, t, _ = _phase_excess(ph, params, per_interval)
    n = t.size - 1
    worst = rel.max(axis=0) if rel.size else np.zeros(t.size)
    inner = worst[:n].reshape(-1, per_interval).max(axis=1)
    inner[-1] = max(inner[-1], worst[-1])
    return inner


def verify(sol: Any, mode: str, tol: float, per_interval: int) -> None:
    """Set ``sol.path_violation``, ``sol.violations`` and ``sol.verified``; warn or raise.

    Parameters
    ----------
    sol : Solution
        A converged solution.
    mode : {"warn", "raise", "off"}
        What to do when a violation exceeds ``tol``.
    tol : float
        Allowed relative violation.
    per_interval : int
        Check points per interval.
    """
    if mode == "off":
        return
    viol = path_excess(sol, per_interval)
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
           "refine the grid, impose constraints at the inner steps (inner_constraints=True) "
           "or use collocation with mesh refinement")
    if mode == "raise":
        raise PathViolationError("Path_Violated_Between_Nodes", sol, msg)
    warnings.warn(msg, PathViolationWarning, stacklevel=3)
