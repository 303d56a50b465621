"""Solve, refine and re-solve a multi-phase landing problem: the steps the variants share.

* :func:`transcribed_solve`: the transcribed NLP from a guess or a neighbour's solution
  (a transcription that violates a path constraint between its nodes is noted);
* :func:`refined_phases`: the arc structure of every phase refined with exact arcs
  (None, with a note, when a phase is not bang-bang or the refinement fails);
* :func:`structure_resolve`: a neighbour's refined structure re-solved directly for new
  parameters (Newton or a small NLP, no transcription), kept only while it still holds;
* :func:`phase_guess`: an exact-simulator trajectory cut into phases at given times, as a
  starting guess for a transcription.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ocp import MultipleShooting, Solution, SolveError, Trajectory
from ocp.errors import PathViolationWarning
from ocp.phase_refinement import RefinedPhases, refine_phase_structure, refine_phases


def transcribed_solve(tr: MultipleShooting, params: dict[str, float], guess: Any,
                      warm_start: Solution | None, notes: list[str]) -> Solution:
    """Solve the transcription: from ``warm_start`` if given (falling back to ``guess``).

    Parameters
    ----------
    tr : MultipleShooting
        The (cached) transcription.
    params : dict
        Parameter values.
    guess : Trajectory, Solution or array
        Cold-start guess.
    warm_start : Solution, optional
        A neighbouring solution of the same transcription.
    notes : list of str
        Receives a note when the solution violates a path constraint between nodes.

    Raises
    ------
    ocp.SolveError
        From the cold start (InfeasibleError when Ipopt finds the problem infeasible).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PathViolationWarning)
        sol = None
        if warm_start is not None:
            try:
                sol = tr.solve(params, warm_start=warm_start)
            except SolveError:
                sol = None
        if sol is None:
            sol = tr.solve(params, guess=guess)
    notes += [f"transcription: {w.message}".split("; refine the grid")[0] for w in caught
              if issubclass(w.category, PathViolationWarning)]
    return sol


def refined_phases(sol: Solution, notes: list[str],
                   structures: list | None = None) -> RefinedPhases | None:
    """Refine every phase's switching times (None and a note when that is not possible).

    Parameters
    ----------
    sol : Solution
        A transcribed multi-phase solution.
    notes : list of str
        Receives why the refinement was not done.
    structures : list of ArcStructure, optional
        Per phase (default: detected).
    """
    try:
        return refine_phases(sol, structures)
    except ValueError as err:
        notes.append(f"not refined: {err}")
    except SolveError as err:
        notes.append(f"switching-time refinement failed ({err.status}); reporting the "
                     "transcribed solution")
    return None


def structure_resolve(prev: RefinedPhases, params: dict[str, float],
                      x0s: list[np.ndarray] | None = None) -> RefinedPhases | None:
    """A neighbour's refined structure re-solved for new parameters (None if it fails, an
    arc collapses or a path constraint is violated between the samples).

    Parameters
    ----------
    prev : RefinedPhases
        The neighbour's refinement.
    params : dict
        The new parameter values.
    x0s : list of ndarray, optional
        Guesses of every phase's start (default: the neighbour's).
    """
    starts = x0s if x0s is not None else [r.x0 for r in prev.phases]
    try:
        r = refine_phase_structure(prev.problem, prev.modes, prev.durations, starts, params,
                                   variables=prev.variables)
    except SolveError:
        return None
    horizon = max(r.T, 1.0)
    if any(float(np.min(d)) <= 1e-9 * horizon for d in r.durations if len(d)):
        return None
    if r.path_violation(2000) > 1e-9:
        return None
    return r


def phase_guess(traj: Trajectory, edges: list[float]) -> Trajectory:
    """``traj`` cut into phases at the times ``edges`` (one fewer than the phases), the
    junction samples repeated so each phase has its own ends; a phase of zero length
    gets its junction state twice.

    Parameters
    ----------
    traj : Trajectory
        States and control ``u`` sampled over the whole landing.
    edges : list of float
        Phase boundaries (increasing).
    """
    bounds = [float(traj.t[0]), *[float(e) for e in edges], float(traj.t[-1])]
    ts, xs, us, ph = [], [], [], []
    for i, (a, b) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
        inside = (traj.t > a) & (traj.t < b)
        t = np.r_[a, traj.t[inside], max(b, a)]
        x = np.column_stack([np.interp(t, traj.t, traj.x[:, j])
                             for j in range(traj.x.shape[1])])
        u = np.column_stack([np.interp(t, traj.t, traj.u[:, j])
                             for j in range(traj.u.shape[1])])
        ts.append(t)
        xs.append(x)
        us.append(u)
        ph.append(np.full(len(t), i))
    return Trajectory(np.concatenate(ts), np.vstack(xs), np.vstack(us), traj.state_names,
                      traj.control_names, phase=np.concatenate(ph))


__all__ = ["phase_guess", "refined_phases", "structure_resolve", "transcribed_solve"]
