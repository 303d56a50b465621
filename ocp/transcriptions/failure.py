"""What a transcription does when Ipopt fails: retry the NLP as posed, say why it failed,
and (on request) leave out a dependent end condition.

* **Never worse than no scaling.** A scaled solve that fails is retried from the same
  start on the NLP exactly as posed (``D = 1, c = 0, r = 1``, objective unscaled: the
  NLP of ``scaling="none"``, through the same solver, no rebuild). If that solves,
  the solution says so (``sol.scaling_fallback``) and a
  :class:`~ocp.ScalingFallbackWarning` is issued; else the scaled failure is raised.
  ``scaling={"fallback": False}`` turns the retry off.
* **Failures that name their cause.** The :class:`~ocp.SolveError` raised carries
  ``diagnosis`` (:mod:`ocp.transcriptions.diagnosis`), computed when first read, whose
  one line ends the message.
* **Dependent end conditions.** ``solve(drop_dependent=True)`` looks for dependent end
  conditions at the start and, failing that, after a failed solve at its last iterate;
  it loosens the terminal row of largest weight in the dependence (:func:`loosened`:
  ``e = b`` becomes ``|e - b| <= |b| / 2``, inactive at the solution) and solves again,
  then measures how well the solution meets the row as posed (``sol.dropped_residual``,
  relative to ``max(1, |b|)``: the discretisation's drift of the conserved quantity) and
  warns (:class:`~ocp.DroppedConditionWarning`). Left out entirely, the row would leave
  its value free up to a branch (``x = +-sqrt(r^2 - y^2)``); the loose band keeps the
  branch (``-b`` lies outside it), and the row of largest weight is the one whose value
  is largest, so the band is widest. A row the solution misses by more than the
  transcription's ``verify_tol`` (rows dependent by themselves, met exactly when they agree)
  or by more than :data:`DRIFT` (rows fixing a conserved quantity twice, met to the
  discretisation's drift) contradicts the others: :class:`~ocp.InfeasibleError` with the
  status :data:`DROPPED_VIOLATED` (Ipopt solved the loosened NLP; the problem as posed has
  no solution).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from ..definition.errors import (
    ConvergenceWarning,
    DroppedConditionWarning,
    InfeasibleError,
    ScalingFallbackWarning,
    SolveError,
)
from .diagnosis import (
    Diagnosis,
    conserved_quantity,
    dependent_ends,
    diagnose,
    periodic_states,
)
from .labels import row_labels

INFEASIBLE_STATUSES = {"Infeasible_Problem_Detected", "Restoration_Failed"}
DROPPED_VIOLATED = "Dropped_Condition_Violated"
"""The status of the error when a left-out end condition is missed (its conditions
contradict)."""
DRIFT = 1e-2
"""The largest miss of a left-out row fixing a conserved quantity that is taken for the
discretisation's drift of it (relative); beyond, the end conditions contradict."""


def failure_error(tr: Any, sol: Any) -> SolveError:
    """The exception for a failed solve: Ipopt's status, the iterate, and its diagnosis
    (computed when first read).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    sol : Solution
        The failed solve's last iterate.
    """
    cls = InfeasibleError if sol.status in INFEASIBLE_STATUSES else SolveError
    text = f"Ipopt failed: {sol.status} after {sol.iterations} iterations"
    if cls is InfeasibleError:  # (Ipopt's restoration stops at a local minimum of violation)
        text += " (a local verdict: from another guess a feasible problem may solve)"
    if getattr(sol, "scaling_fallback", None):
        text += f" ({sol.scaling_fallback})"
    pv = np.array(list(sol.params.values()), dtype=float)
    return cls(sol.status, sol, text, diagnose=lambda: diagnose(tr, sol.w, pv, sol.scaling))


def after_failure(tr: Any, sol: Any, args: dict[str, Any],
                  unscaled: Callable[[], Any]) -> Any:
    """The solution of the NLP as posed where a scaled solve failed and it succeeds,
    else the scaled failure raised (see the module).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    sol : Solution
        The failed scaled solve.
    args : dict
        Its arguments (unused but for their start; kept for the message).
    unscaled : callable
        ``() -> Solution``: the same solve on the NLP as posed.
    """
    sc = sol.scaling
    scaled = sol.objective_scale != 1.0 or not sc.is_identity()
    if not scaled or not tr.scaling_options.get("fallback", True):
        raise failure_error(tr, sol)
    plain = unscaled()
    if not plain.success:
        raise failure_error(tr, sol)
    note = (f"the scaled NLP failed ({sol.status} after {sol.iterations} iterations); "
            f"solved as posed (scaling='none') in {plain.iterations}")
    plain.scaling_fallback = note
    warnings.warn(note, ScalingFallbackWarning, stacklevel=4)
    return plain


def solve_dropping_dependent(tr: Any, params: Any, guess: Any, warm_start: Any) -> Any:
    """``solve(drop_dependent=True)`` (see the module).

    Parameters
    ----------
    tr : Transcription
        The transcription (its ``solve_once(params, guess, warm_start, dropped)``).
    params, guess, warm_start
        As for ``solve``.
    """
    solve_once = tr.solve_once
    found = _row_to_drop_at_start(tr, params, guess, warm_start)
    if found is None:
        try:
            sol = solve_once(params, guess, warm_start, {})
            sol.dropped_residual = math.nan
            return sol
        except SolveError as e:
            d = e.diagnosis
            if not isinstance(d, Diagnosis) or not d.dependent_rows:
                raise
            found = _choose(tr, d.dependent_rows, d.weights), d.conserved
    row, conserved = found
    labels = row_labels(tr)
    sol = solve_once(params, guess, warm_start, {row: labels[row]})
    pv = tr.param_vector({} if params is None else params)
    _, _, lbg, ubg = tr.bounds_at(pv)
    g = float(np.array(tr.nlp_function()(sol.w, pv)[1], dtype=float).ravel()[row])
    bound = lbg[row] if math.isfinite(lbg[row]) else ubg[row]
    excess = max(lbg[row] - g, g - ubg[row], 0.0)
    sol.dropped_residual = excess / max(1.0, abs(bound))
    # rows that fix a conserved quantity twice are met to the discretisation's drift of it
    # (1e-3 with RK4 on 10 nodes); rows dependent by themselves (one expression fixed twice)
    # are met exactly when they agree: missed by more, they contradict, and the problem as
    # posed has no solution, whatever Ipopt said of the loosened one
    tol = DRIFT if conserved else float(getattr(tr, "verify_tol", 1e-6))
    if not sol.dropped_residual <= tol:  # (NaN included)
        why = f"more than {conserved}'s drift bound {tol:g}" if conserved else \
            f"more than verify_tol {tol:g}"
        raise InfeasibleError(
            DROPPED_VIOLATED, sol,
            f"the end conditions contradict: with {labels[row]} left out, the solution "
            f"misses it by {sol.dropped_residual:.3g} (relative, {why}); they cannot all "
            "hold")
    warnings.warn(f"left out the dependent end condition {labels[row]}; the solution "
                  f"meets it to {sol.dropped_residual:.1e}", DroppedConditionWarning,
                  stacklevel=3)
    return sol


def loosened(lbg: np.ndarray, ubg: np.ndarray, rows: list[int],
             r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds with the equality rows ``rows`` (``e = b``) loosened to ``|e - b| <= |b| / 2``
    (``|b|`` replaced by the row's typical size ``1 / r`` where larger; a band wide enough
    to be inactive, narrow enough to exclude the other branch ``-b``).

    Parameters
    ----------
    lbg, ubg : ndarray
        The rows' bounds.
    rows : list of int
        The rows to loosen.
    r : ndarray
        The rows' scaling (``g_s = r g``).
    """
    lo, hi = lbg.copy(), ubg.copy()
    for k in rows:
        b = lbg[k]
        half = 0.5 * abs(b) if b != 0.0 else 0.5 / r[k]
        lo[k], hi[k] = b - half, b + half
    return lo, hi


def _row_to_drop_at_start(tr: Any, params: Any, guess: Any,
                          warm_start: Any) -> tuple[int, str | None] | None:
    """A dependent end row found at the start and the conserved quantity the dependence
    fixes twice (None: the rows are dependent by themselves), or None."""
    pv = tr.param_vector({} if params is None else params)
    x0 = np.asarray(tr.start_vector(pv, params or {}, guess, warm_start), dtype=float)
    with np.errstate(all="ignore"):
        dep = dependent_ends(tr, x0, pv, tr.bounds_at(pv), tr.scaling)
        if dep is None:
            return None
        return _choose(tr, dep[2], dep[3]), conserved_quantity(tr, x0, pv, dep[3])


def _choose(tr: Any, rows: list[int], weights: dict[int, float]) -> int:
    """The terminal row of largest weight (an initial condition is usually physics)."""
    labels = row_labels(tr)
    terminal = [k for k in rows if "terminal" in labels[k]] or rows
    return max(terminal, key=lambda k: abs(weights.get(k, 0.0)))


def warn_unconverged(sol: Any) -> None:
    """After a mesh refinement that did not converge: warn, naming the periodic unbounded
    states if there are any (they let the solver wind and refinement chase windings).

    Parameters
    ----------
    sol : Solution
        The refinement's last solution.
    """
    names = [n for ph in sol.transcription.multiphase.phases for n in periodic_states(ph)]
    if not names:
        return
    warnings.warn(f"mesh refinement did not converge; state {', '.join(map(repr, names))} "
                  "enters only through 2*pi-periodic functions and is unbounded: bound it "
                  "(e.g. within [-2*pi, 2*pi]) or wrap it", ConvergenceWarning, stacklevel=3)
