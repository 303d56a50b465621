"""Where a transcribed solution sits: the controls' bounds at its values, which path
constraints are at which limit at every node, and where a state constraint at a limit is
not held there because no admissible control could cross it."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.solution import along
from .arc_structure import SolutionLike, TranscribedSolution, transcribed
from .constraint_kinds import KINDS, path_kinds

__all__ = ["active_path_constraints", "control_bounds_at", "drop_uncrossable", "known_values",
           "no_control_crosses", "path_activity"]


def control_bounds_at(problem: OptimalControlProblem, name: str,
                      params: dict[str, float]) -> tuple[float, float]:
    """Numeric ``(lower, upper)`` bounds of control ``name`` at the values ``params``.

    The control's limits (``problem.control_limits``, :mod:`ocp.definition.normal_form`)
    may involve decision variables (``u <= peak``), and in a problem derived for the
    refinement, the states that stand for them: their values are looked up by name in
    ``params`` too (:func:`known_values` of a solution has them).

    Parameters
    ----------
    problem : OptimalControlProblem
    name : str
        A control's name.
    params : dict
        A value for every parameter of the problem (and for every decision variable
        or state the limits involve).

    Returns
    -------
    (float, float)

    Raises
    ------
    ValueError
        When the limits involve a variable whose value ``params`` does not give.
    """
    lo, hi = problem.control_limits[name]
    both = ca.vertcat(lo, hi)
    if both.is_constant():
        return float(ca.DM(lo)), float(ca.DM(hi))
    syms, vals = [], []
    for names, vec in ((problem.param_names, problem.p), (problem.var_names, problem.v),
                       (problem.state_names, problem.x)):
        for i, n in enumerate(names):
            if ca.depends_on(both, vec[i]):
                if n not in params:
                    raise ValueError(f"the bounds of control {name!r} depend on {n!r}: "
                                     "its value is needed")
                syms.append(vec[i])
                vals.append(float(params[n]))
    f = ca.Function("b", [ca.vertcat(*syms)], [lo, hi])
    a, b = (float(v) for v in f(vals))
    return a, b


def known_values(sol: SolutionLike) -> dict[str, float]:
    """A solution's parameter values and its decision variables' optimised values.

    Parameters
    ----------
    sol : Solution
        A transcribed (or refined) solution.
    """
    return {**transcribed(sol).params, **(getattr(sol, "variables", None) or {})}


def path_activity(sol: SolutionLike, tol: float,
                  kinds: tuple[str, ...] = KINDS) -> tuple[np.ndarray, np.ndarray]:
    """Which path constraints sit at which limit at every node.

    Parameters
    ----------
    sol : Solution
        A transcribed solution.
    tol : float
        Relative distance to a limit that counts as at it.
    kinds : tuple of str
        Which kinds of constraint to report (:func:`ocp.structure.constraint_kinds.constraint_kind`:
        ``"state"``, ``"mixed"``, ``"control"``); the columns of the others are False.

    Returns
    -------
    at_lower, at_upper : bool arrays (N+1, n_path)
        Within ``tol * max(1, |value|)`` of the lower (upper) limit.
    """
    tsol = transcribed(sol)
    pr = tsol.problem
    n = tsol.N + 1
    if not pr.structure_path:
        return np.zeros((n, 0), dtype=bool), np.zeros((n, 0), dtype=bool)
    pv = [tsol.params[k] for k in pr.param_names]
    lows, ups = [], []
    for c, kind in zip(pr.structure_path, path_kinds(pr), strict=True):
        if kind not in kinds:
            lows.append(np.zeros(n, dtype=bool))
            ups.append(np.zeros(n, dtype=bool))
            continue
        vals = tsol.evaluate(c.expr)
        lo, hi = (float(v) for v in ca.Function("b", [pr.p], [c.lower, c.upper])(pv))
        scale = tol * np.maximum(1.0, np.abs(vals))
        lows.append(np.abs(vals - lo) <= scale)
        ups.append(np.abs(vals - hi) <= scale)
    return np.column_stack(lows), np.column_stack(ups)


def active_path_constraints(sol: SolutionLike, tol: float,
                            kinds: tuple[str, ...] = KINDS,
                            crossable: bool = False) -> np.ndarray:
    """Which path constraints are active (at either limit) at every node.

    Parameters
    ----------
    sol : Solution
        A transcribed solution.
    tol : float
        As in :func:`path_activity`.
    kinds : tuple of str
        As in :func:`path_activity`.
    crossable : bool
        Count a state constraint at a limit only where some admissible control could
        cross it (:func:`no_control_crosses`).

    Returns
    -------
    ndarray of bool (N+1, n_path)
    """
    tsol = transcribed(sol)
    lo, up = path_activity(tsol, tol, kinds)
    if crossable:
        drop_uncrossable(tsol, lo, up)
    return lo | up


def no_control_crosses(pr: OptimalControlProblem, c: Any, side: str, x: np.ndarray,
                       los: np.ndarray, his: np.ndarray, pv: np.ndarray,
                       tol: float = 1e-9) -> np.ndarray:
    """Where no admissible control could push state constraint ``c`` across its ``side``
    limit: ``dc/dt = a(x) + b(x) u`` is on the feasible side for every ``u`` in the box.

    A state at such a limit is not held there by the constraint (``m <= 1`` while
    ``m' = -u/E`` with ``u >= 0``): touching it is no constrained arc, and the costate
    does not jump there. A constraint whose first derivative does not involve the
    controls (relative degree 2 or more), or involves them nonlinearly, can always be
    crossed here (False).

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint
        A state constraint (no control in it).
    side : {"lower", "upper"}
    x : ndarray (m, nx)
        States at the samples.
    los, his : ndarray (m, nu)
        The control set's box at the samples.
    pv : ndarray
        Parameter values.
    tol : float
        Allowed push across, relative to the size of the terms.

    Returns
    -------
    ndarray of bool (m,)
    """
    dc = ca.jtimes(c.expr, pr.x, pr.rhs)
    b = ca.jacobian(dc, pr.u)
    if pr.nu == 0 or ca.depends_on(b, pr.u) or not ca.depends_on(dc, pr.u) \
            or ca.depends_on(dc, ca.vertcat(pr.t, pr.t0, pr.T, pr.v)):
        return np.zeros(len(x), dtype=bool)
    a = ca.substitute(dc, pr.u, ca.DM.zeros(pr.nu))
    av, bv = along(ca.Function("ab", [pr.x, pr.p], [a, b.T]), x, pv)
    av = av.ravel()
    with np.errstate(invalid="ignore"):
        ends = np.stack([bv * los, bv * his])  # (2, m, nu); 0 * inf is nan: no push
    ends = np.where(bv[None] == 0.0, 0.0, ends)
    push = av + (np.sum(np.max(ends, axis=0), axis=1) if side == "upper"
                 else np.sum(np.min(ends, axis=0), axis=1))
    size = np.abs(av) + np.sum(np.abs(np.where(np.isfinite(ends), ends, 0.0)), axis=(0, 2))
    scale = tol * np.maximum(1.0, size)
    ok = push <= scale if side == "upper" else push >= -scale
    return np.isfinite(push) & ok


def drop_uncrossable(sol: TranscribedSolution, at_lo: np.ndarray, at_up: np.ndarray) -> None:
    """Clear the nodes where a state constraint sits at a limit no admissible control
    could cross there (:func:`no_control_crosses`): not held by the constraint.

    Parameters
    ----------
    sol : TranscribedSolution
        A transcribed solution.
    at_lo, at_up : bool arrays (N+1, n_path)
        As :func:`path_activity` returns them; cleared in place.
    """
    pr = sol.problem
    if not (at_lo.any() or at_up.any()):
        return
    values = known_values(sol)
    box = [control_bounds_at(pr, n, values) for n in pr.control_names]
    x = np.asarray(sol.x, dtype=float)
    los = np.tile([b[0] for b in box], (len(x), 1))
    his = np.tile([b[1] for b in box], (len(x), 1))
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    for i, c in enumerate(pr.structure_path):
        for side, at in (("lower", at_lo), ("upper", at_up)):
            if at[:, i].any() and not ca.depends_on(c.expr, pr.u):
                at[:, i] &= ~no_control_crosses(pr, c, side, x, los, his, pv)
