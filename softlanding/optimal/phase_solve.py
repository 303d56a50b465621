"""Solve, refine and re-solve a landing problem: the steps the variants share.

* :func:`transcribed_solve`: the transcribed NLP from a neighbour's solution, else a guess
  (else, if asked, Ipopt's default start); a transcription that violates a path constraint
  between its nodes is noted;
* :func:`refined_phases`: the arc structure of every phase refined with exact arcs
  (None, with a note, when a phase is not bang-bang or the refinement fails);
  :func:`refined_switching` the same for a one-phase problem (one switching structure);
* :func:`structure_resolve`: a neighbour's refined structure re-solved directly for new
  parameters (Newton or a small NLP, no transcription), kept only while it still holds;
  :func:`switching_resolve` the same for a one-phase structure;
* :func:`phase_guess`: an exact-simulator trajectory cut into phases at given times, as a
  starting guess for a transcription.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ocp import MultipleShooting, Solution, SolveError, Trajectory
from ocp.definition.errors import PathViolationWarning
from ocp.structure.arcs import ArcStructure
from ocp.structure.flows import Mode
from ocp.structure.phase_refinement import (
    RefinedPhases,
    detect_phase_structures,
    local_phase,
    refine_phase_structure,
    refine_phases,
)
from ocp.structure.switching import (
    RefinedSwitching,
    detect_arcs,
    refine_structure,
    refine_switching,
)
from softlanding.optimal.stance_phases import CRATER, STROKE
from softlanding.util.signals import raise_if_interrupted


def transcribed_solve(tr: MultipleShooting, params: dict[str, float], guess: Any,
                      warm_start: Solution | None, notes: list[str], *,
                      default_start: bool = False) -> Solution:
    """Solve the transcription: from ``warm_start`` if given, falling back to ``guess``
    (then, with ``default_start``, to Ipopt's default start).

    Parameters
    ----------
    tr : MultipleShooting
        The (cached) transcription.
    params : dict
        Parameter values.
    guess : Trajectory, Solution or array, or a callable returning one
        Cold-start guess (a callable is called only when there is no warm start or it
        fails: a warm sweep does not compute it).
    warm_start : Solution, optional
        A neighbouring solution of the same transcription.
    notes : list of str
        Receives a note when the solution violates a path constraint between nodes.
    default_start : bool
        When the start from ``guess`` fails too, solve once more from the transcription's
        default guess (a guess from a state far from any solved one can mislead Ipopt).

    Raises
    ------
    ocp.SolveError
        From the last start (InfeasibleError when Ipopt finds the problem infeasible).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PathViolationWarning)
        sol = None
        if warm_start is not None:
            try:
                sol = tr.solve(params, warm_start=warm_start)
            except (SolveError, ValueError):  # failed, or a solution of another problem
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                sol = None
        if sol is None and callable(guess):
            guess = guess()
        if sol is None and default_start and guess is not None:
            try:
                sol = tr.solve(params, guess=guess)
            except SolveError:
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                sol = None
                guess = None
        if sol is None:
            sol = tr.solve(params, guess=guess)
    notes += [f"transcription: {w.message}".split("; refine the grid")[0] for w in caught
              if issubclass(w.category, PathViolationWarning)]
    for w in caught:  # the rest as they came (recording caught them all)
        if not issubclass(w.category, PathViolationWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return sol


def refined_phases(sol: Solution, notes: list[str],
                   structures: list | None = None) -> RefinedPhases | None:
    """Refine every phase's switching times (None and a note when that is not possible).

    The detected structures are tried first, then the repairs of
    :func:`repaired_structures` (grid artefacts: a touch point of the stroke limit
    read as an arc or missed, a static phase that is not one clean arc); a refinement
    is kept only if its arcs keep every path constraint between the samples (1e-9).

    Parameters
    ----------
    sol : Solution
        A transcribed multi-phase solution.
    notes : list of str
        Receives why the refinement was not done, or which repair was used.
    structures : list of ArcStructure, optional
        Per phase (default: detected).
    """
    first = structures if structures is not None else detect_phase_structures(sol)
    tried = [(first, "")] + repaired_structures(sol, first)
    why = ""
    for sts, label in tried:
        try:
            r = refine_phases(sol, sts)
        except ValueError as err:
            why = f"not refined: {err}"
            continue
        except SolveError as err:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            why = f"switching-time refinement failed ({err.status})"
            continue
        viol = r.path_violation(4000)
        if viol > 1e-9:  # e.g. a touch point between the samples of an interval
            why = f"the refined arcs violate a path constraint by {viol:.1e} between samples"
            continue
        if label:
            notes.append(f"refined with {label}")
        return r
    notes.append(why + "; reporting the transcribed solution")
    return None


def refined_switching(sol: Solution, notes: list[str], extra_arcs: int = 0
                      ) -> tuple[RefinedSwitching | None, Any]:
    """A one-phase transcription's switching structure detected and refined with exact arcs
    (:func:`ocp.refine_switching`), and the structure; None and a note when it has arcs that
    are neither bang nor on a constraint, or the refinement fails.

    A final constrained arc after the last bang arc (the foot already stopped, the force
    holding the crater's yield load: the body-arrest phase, which the terminal conditions
    account for) is dropped, with a note.

    Parameters
    ----------
    sol : Solution
        A transcribed one-phase solution.
    notes : list of str
        Receives what was dropped, or why there is no refinement.
    extra_arcs : int
        Also try this many more bang arcs.

    Returns
    -------
    (RefinedSwitching or None, SwitchingStructure)
    """
    st = detect_arcs(sol)
    trimmed = st.without_trailing_constrained()
    if trimmed is not st and trimmed.refinable:
        notes.append(
            f"dropped the final {st.arcs[-1].duration:.4g}-long arc on which "
            f"{' and '.join(st.arcs[-1].active)} is active: the foot has already stopped "
            "and the force holds the crater's yield load, which is the body-arrest phase")
        st = trimmed
    if not st.refinable:
        notes.append(f"structure {st.kinds} has arcs that are neither bang nor on a "
                     "constraint; not refined")
        return None, st
    try:
        return refine_switching(sol, st, extra_arcs=extra_arcs), st
    except SolveError as err:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        notes.append(f"switching-time refinement failed ({err.status}); "
                     "reporting the transcribed solution")
        return None, st


def second_start(inner: MultipleShooting, tr: MultipleShooting, params: dict[str, float],
                 guess: Any, sol: Solution, notes: list[str]
                 ) -> tuple[Solution, RefinedPhases | None]:
    """A second start for a transcription whose structure could not be refined.

    A solution that dives through a path constraint between the nodes can show
    interior arcs there, and the refinement then gives up. Solve once more with
    ``inner`` (the same problem with the path constraints imposed at the inner
    integrator steps), polish on ``tr`` from there, and keep that if it refines.

    Parameters
    ----------
    inner, tr : MultipleShooting
        The transcription with inner constraints, and the plain one.
    params : dict
        Parameter values.
    guess : Trajectory, Solution or array
        The first start's guess.
    sol : Solution
        The first start's solution (returned unchanged if the second start fails).
    notes : list of str
        Replaced by the second start's notes when it succeeds.

    Returns
    -------
    (Solution, RefinedPhases or None)
    """
    try:
        start = transcribed_solve(inner, params, guess, None, [])
        again: list[str] = []
        sol2 = transcribed_solve(tr, params, start, None, again)
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return sol, None
    ref2 = refined_phases(sol2, again)
    if ref2 is None:
        return sol, None
    notes[:] = [*again, "the first transcription could not be refined; solved again from a "
                "start with the path constraints imposed between the nodes"]
    return sol2, ref2


def _split_at(st: ArcStructure, t: float, mode: Mode) -> ArcStructure:
    """``st`` (one control) with a zero-length ``mode`` arc inserted at time ``t``."""
    modes: list[tuple[Mode, ...]] = []
    durs: list[float] = []
    for iv in st.intervals:
        if iv.start < t < iv.end and mode not in iv.modes:
            modes += [iv.modes, (mode,), iv.modes]
            durs += [t - iv.start, 0.0, iv.end - t]
        else:
            modes.append(iv.modes)
            durs.append(iv.duration)
    return ArcStructure.from_modes(st.controls, modes, durs)


def _by_sign(loc: Solution) -> ArcStructure:
    """Bang arcs from the sign of the (single) control of a transcribed phase."""
    u = loc.u[:, 0]
    h = float(loc.T) / loc.N
    modes: list[tuple[Mode, ...]] = []
    durs: list[float] = []
    for uk in u:
        m = (Mode("max" if uk >= 0 else "min"),)
        if modes and modes[-1] == m:
            durs[-1] += h
        else:
            modes.append(m)
            durs.append(h)
    return ArcStructure.from_modes(("u",), modes, durs)


def _crater_arc(ph: Solution) -> ArcStructure:
    dur = float(ph.T - ph.t0)
    return ArcStructure.from_modes(("u",), [(Mode("boundary", CRATER, "upper"),)], [dur])


def repaired_structures(sol: Solution, structures: list[ArcStructure]
                        ) -> list[tuple[list[ArcStructure], str]]:
    """Alternative structures repairing the transcription's grid artefacts, with labels.

    * a static phase whose arcs are not refinable or not a single arc becomes one
      boundary arc on the crater's capacity (the arrest that uses the whole capacity);
    * a yielding or flight phase whose leg reaches the upper stroke limit (to 1e-7) gets
      a zero-length boundary arc there, a *touch point* (entry conditions stroke = s and
      relative velocity 0, imposed exactly): inserted into the detected arcs when they
      hold no stroke arc, else into bang arcs read off the sign of the control;
    * a phase that is not refinable is also read with a looser tolerance.

    Parameters
    ----------
    sol : Solution
        The transcribed multi-phase solution.
    structures : list of ArcStructure
        The detected structures, per phase.
    """
    from ocp.structure.arcs import detect_structure

    s = float(sol.params["s"])
    variants: list[tuple[list[ArcStructure], list[str]]] = [([], []), ([], [])]
    for i, st in enumerate(structures):
        ph = sol.phases[i]
        loc = local_phase(sol, i)
        names = [c.name for c in ph.problem.path]
        leg = ph.x[:, 0] - ph.x[:, 2]
        touches = STROKE in names and float(np.max(leg)) >= s * (1 - 1e-7)
        t_touch = float(loc.t[int(np.argmax(leg))])
        touch = Mode("boundary", STROKE, "upper")
        held = {m.constraint for iv in st.intervals for m in iv.modes}
        for k, (sts, labels) in enumerate(variants):
            if CRATER in names:
                if not st.refinable or len(st.intervals) != 1:
                    sts.append(_crater_arc(ph))
                    labels.append(f"phase {ph.problem.name!r} as one crater-capacity arc")
                else:
                    sts.append(st)
                continue
            base = st
            if k == 0 and not st.refinable and ph.problem.nu:
                loose = detect_structure(loc, tol=1e-2, max_transition=3)
                if loose.refinable:
                    base = loose
                    labels.append(f"phase {ph.problem.name!r} read with a looser tolerance")
            if k == 1 and touches and ph.problem.nu == 1:
                signed = _by_sign(loc)
                if len(signed.intervals) > 4:  # not a clean bang-bang phase: no repair
                    sts.append(st)
                    continue
                base = signed
                labels.append(f"phase {ph.problem.name!r} as bang arcs by the control's sign")
            if touches and base.refinable and (k == 1 or STROKE not in held):
                base = _split_at(base, t_touch, touch)
                labels.append(f"a touch point of the stroke limit in phase "
                              f"{ph.problem.name!r}")
            sts.append(base)
    return [(sts, "; ".join(labels)) for sts, labels in variants if labels]


def structure_resolve(prev: RefinedPhases, params: dict[str, float],
                      x0s: list[np.ndarray] | None = None,
                      bound: float | None = None) -> RefinedPhases | None:
    """A neighbour's refined structure re-solved for new parameters (None if it fails, an
    arc of positive length collapses, or a path constraint is violated between the samples).

    Parameters
    ----------
    prev : RefinedPhases
        The neighbour's refinement.
    params : dict
        The new parameter values.
    x0s : list of ndarray, optional
        Guesses of every phase's start (default: the neighbour's).
    bound : float, optional
        An objective value known to be achievable (e.g. a special case's optimum): a
        re-solve above it has landed on another local solution, and is not kept.
    """
    starts = x0s if x0s is not None else [r.x0 for r in prev.phases]
    try:
        r = refine_phase_structure(prev.problem, prev.modes, prev.durations, starts, params,
                                   variables=prev.variables)
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return None
    tiny = 1e-9 * max(r.T, 1.0)
    for new, old in zip(r.durations, prev.durations, strict=True):
        if np.any((new <= tiny) & (old > tiny)):
            return None  # an arc collapsed: the structure changed (touch points may stay)
    if bound is not None and r.objective > bound + 1e-9 * max(1.0, abs(bound)):
        return None
    if r.path_violation(2000) > 1e-9:
        return None
    return r


def switching_resolve(prev: RefinedSwitching, problem: Any, x0: np.ndarray,
                      params: dict[str, float]) -> RefinedSwitching | None:
    """A neighbour's refined one-phase structure re-solved for new parameters
    (:func:`ocp.refine_structure`; None if it fails or an arc collapses: the structure is
    then no longer the optimum's, and the caller transcribes). Path constraints are checked
    inside every arc by the re-solve.

    Parameters
    ----------
    prev : RefinedSwitching
        The neighbour's refinement.
    problem : ocp.OptimalControlProblem
        The problem it refined.
    x0 : array
        The start.
    params : dict
        The new parameter values.
    """
    try:
        r = refine_structure(problem, prev.modes, prev.durations, x0, params)
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return None
    if min(r.durations) <= 1e-9 * r.T:
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


__all__ = ["phase_guess", "refined_phases", "refined_switching", "repaired_structures",
           "structure_resolve", "switching_resolve", "transcribed_solve"]
