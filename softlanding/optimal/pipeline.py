"""The solve pipeline every landing variant plugs into.

A variant is a problem (an ``ocp`` multi-phase problem and its transcription) plus a small
:class:`PhasedVariant` subclass filling these hooks:

* :meth:`PhasedVariant.parameters` -- the NLP's parameter values;
* :meth:`PhasedVariant.transcription` and :meth:`PhasedVariant.guess` -- what to solve, and
  from where when no neighbour's solution is at hand;
* :meth:`PhasedVariant.assemble` -- the result (a :class:`~softlanding.optimal.result.
  PhasedLanding` subclass) from a transcription and/or refined phases;
* optionally :meth:`PhasedVariant.accepts` (which neighbours' structures may be re-solved),
  :meth:`PhasedVariant.bound` (a depth no re-solved structure may exceed),
  :meth:`PhasedVariant.refinement` and :meth:`PhasedVariant.resolve` (a one-phase problem
  refines one switching structure, :func:`~softlanding.optimal.phase_solve.
  refined_switching`, instead of phases), :attr:`PhasedVariant.default_start` (Ipopt's
  default start after a failed guess),
  :meth:`PhasedVariant.explain` (an infeasible problem, in words),
  :meth:`PhasedVariant.retry` (a second attempt when refinement fails),
  :meth:`PhasedVariant.smooth` (a smooth optimum: converged on a refined collocation mesh
  and certified arc by arc, :mod:`softlanding.optimal.smooth`),
  :meth:`PhasedVariant.finish` and :meth:`PhasedVariant.replay`.

:func:`solve_phased` runs the steps they share: re-solve a neighbour's refined structure
directly (no transcription), else transcribe (warm from the neighbour's transcription),
refine the switching times of every phase with exact arcs, assemble, replay in the exact
simulator. :func:`continuation` runs a sweep over impact velocities, each solve warm from
the last, keeping the last transcription for warm starts across structure re-solves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from functools import cache
from typing import Any, ClassVar, Generic, Protocol, TypeVar

from ocp import InfeasibleError, MultipleShooting, Solution, SolveError
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.limits import force_limit
from softlanding.optimal.phase_solve import refined_phases, structure_resolve, transcribed_solve
from softlanding.optimal.smooth import SmoothOptimum, is_smooth, solve_smooth
from softlanding.util.progress import progress as show_progress
from softlanding.util.signals import raise_if_interrupted

R = TypeVar("R")


class Solved(Protocol):
    """What :func:`solve_phased` reads and sets on a result (a neighbour's, or its own)."""

    refined: Any
    transcribed: Solution | None
    refine_requested: bool


L = TypeVar("L", bound=Solved)


def landing_parameters(robot: Robot, impact: Impact) -> dict[str, float]:
    """The parameter values every landing OCP takes: ``r_m, s, v0, u_max, l0``.

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit, see :func:`force_limit`).
    impact : Impact
        The impact.
    """
    return {"r_m": robot.r_m, "s": robot.s, "v0": impact.v0, "u_max": force_limit(robot),
            "l0": robot.rest_length}


def continuation(impacts: Iterable[Impact], solve_one: Callable[[Impact, R | None], R],
                 progress: bool | None, desc: str) -> list[R]:
    """Solve in order, each from the last result (continuation); the results in order.

    A result without a transcription (a structure re-solve) passes the last transcription
    on, so that the next solve can still warm-start its NLP.

    Parameters
    ----------
    impacts : iterable of Impact
        In the order to solve (start from the easy end).
    solve_one : callable
        ``solve_one(impact, previous) -> result``; ``previous`` is None the first time.
    progress : bool or None
        Progress bar (None: only on a terminal).
    desc : str
        The progress bar's label.
    """
    out: list[R] = []
    prev: Any = None
    for imp in show_progress(list(impacts), progress, desc, "solve"):
        res: Any = solve_one(imp, prev)
        out.append(res)
        if getattr(res, "transcribed", None) is None and \
                getattr(prev, "transcribed", None) is not None:  # (a user's result may have none)
            res = dataclasses.replace(res, transcribed=prev.transcribed)
        prev = res
    return out


class PhasedVariant(Generic[L]):
    """One landing problem to solve through :func:`solve_phased` (fill the hooks), whose
    result is an ``L`` (a :class:`~softlanding.optimal.result.PhasedLanding` unless the
    variant says otherwise).

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit).
    impact : Impact
        The impact.
    """

    default_start: ClassVar[bool] = False
    """When the start from :meth:`guess` fails too, start once more from Ipopt's default
    (for a guess that may mislead, e.g. one from a state far from any solved one)."""

    def __init__(self, robot: Robot, impact: Impact) -> None:
        self.robot, self.impact = robot, impact

    def parameters(self) -> dict[str, float]:
        """The NLP's parameter values (default: :func:`landing_parameters`)."""
        return landing_parameters(self.robot, self.impact)

    def transcription(self) -> MultipleShooting:
        """The (cached) transcription to solve."""
        raise NotImplementedError

    def guess(self) -> Any:
        """The cold-start guess (a trajectory cut into the phases)."""
        raise NotImplementedError

    def assemble(self, sol: Solution | None, ref: Any, notes: list[str], path: str) -> L:
        """The result.

        Parameters
        ----------
        sol : ocp.Solution or None
            The transcription (None on the structure path).
        ref : RefinedPhases or None
            The refinement (None when it was off or failed): what :meth:`refinement` or
            :meth:`resolve` gave.
        notes : list of str
            What the solve noticed.
        path : str
            ``"transcription"`` or ``"structure"``.
        """
        raise NotImplementedError

    def accepts(self, neighbour: L) -> bool:
        """Whether ``neighbour``'s refined structure may be re-solved for this problem.

        Parameters
        ----------
        neighbour : PhasedLanding
            The warm start.
        """
        return True

    def refinement(self, sol: Solution, notes: list[str]) -> Any:
        """The switching times refined with exact arcs, or None (default: every phase's,
        :func:`~softlanding.optimal.phase_solve.refined_phases`).

        Parameters
        ----------
        sol : ocp.Solution
            The transcription.
        notes : list of str
            Receives why there is no refinement, or what was repaired.
        """
        return refined_phases(sol, notes)

    def smooth(self, sol: Solution, params: dict[str, float],
               notes: list[str]) -> SmoothOptimum | None:
        """A smooth optimum (interior arcs, no switching times) converged on a refined
        mesh and certified arc by arc, or None with a note (default:
        :func:`~softlanding.optimal.smooth.solve_smooth`).

        Parameters
        ----------
        sol : ocp.Solution
            The transcription (the problem and the first guess).
        params : dict
            Parameter values.
        notes : list of str
            Receives what was done, or why it failed.
        """
        return solve_smooth(sol, params, notes)

    def resolve(self, neighbour: L, params: dict[str, float]) -> Any:
        """``neighbour``'s refined structure re-solved directly for ``params``, or None when
        it does not hold here (default: :func:`~softlanding.optimal.phase_solve.
        structure_resolve` under :meth:`bound`).

        Parameters
        ----------
        neighbour : PhasedLanding
            The warm start (refined, and accepted).
        params : dict
            This problem's parameter values.
        """
        return structure_resolve(neighbour.refined, params, bound=self.bound())

    def bound(self) -> float | None:
        """A depth that a re-solved structure must not exceed (None: no bound)."""
        return None

    def explain(self, err: SolveError, guess: Any) -> Exception:
        """The error to raise for an infeasible transcription (default: ``err`` itself).

        Parameters
        ----------
        err : ocp.SolveError
            Ipopt's verdict.
        guess : object
            The guess it started from.
        """
        return err

    def retry(self, sol: Solution, ref: Any, guess: Any,
              notes: list[str]) -> tuple[Solution, Any]:
        """A second attempt when the refinement failed (default: none).

        Parameters
        ----------
        sol : ocp.Solution
            The first transcription, whose refinement ``ref`` may have failed (None).
        ref : RefinedPhases or None
            The refinement of ``sol``.
        guess : object
            The cold-start guess behind ``sol``, for a second start.
        notes : list of str
            Receives a line on what the second attempt did.
        """
        return sol, ref

    def finish(self, result: L) -> L:
        """Last changes to a transcribed result before the replay (default: none).

        Parameters
        ----------
        result : PhasedLanding
            The assembled result.
        """
        return result

    def replay(self, result: L) -> None:
        """Replay ``result`` in the exact simulator, in place (default: none).

        Parameters
        ----------
        result : PhasedLanding
            The result.
        """


def solve_phased(variant: PhasedVariant[L], warm_start: L | Solution | None = None, *,
                 refine: bool = True, replay: bool = True) -> L:
    """Solve a phased landing: structure re-solve or transcription, refinement, replay.

    A smooth optimum (a running cost curved in the force, interior arcs:
    :func:`~softlanding.optimal.smooth.is_smooth`) has no switching times: it is converged
    on a refined collocation mesh and certified arc by arc instead
    (:meth:`PhasedVariant.smooth`), with or without ``refine``, and the result's ``smooth``
    holds that.

    Parameters
    ----------
    variant : PhasedVariant
        The problem and its hooks.
    warm_start : PhasedLanding or ocp.Solution, optional
        A neighbouring solution: its refined structure is re-solved directly first (when
        ``variant.accepts`` it), then its transcription warm-starts the NLP (a bare
        transcription only warm-starts the NLP).
    refine : bool
        Refine the switching times of every phase with exact arcs.
    replay : bool
        Replay the result in the exact simulator.

    Raises
    ------
    Exception
        What ``variant.explain`` makes of an infeasible transcription; ``ocp.SolveError``
        for any other solver failure.
    """
    params = variant.parameters()
    out = None
    neighbour: L | None = None
    warm: Solution | None = None
    if isinstance(warm_start, Solution):
        warm = warm_start
    elif warm_start is not None:
        neighbour, warm = warm_start, warm_start.transcribed
    if neighbour is not None and neighbour.refined is not None and refine and \
            variant.accepts(neighbour):
        r = variant.resolve(neighbour, params)
        if r is not None:
            out = variant.assemble(None, r, [], "structure")
    if out is None:
        notes: list[str] = []
        # computed when used: not for a warm start that converges unless the refinement
        # is on (its second attempt, retry, takes the guess)
        guess = cache(variant.guess)
        try:
            sol = transcribed_solve(variant.transcription(), params, guess, warm, notes,
                                    default_start=variant.default_start)
        except InfeasibleError as err:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            raise variant.explain(err, guess()) from None
        smooth = variant.smooth(sol, params, notes) if is_smooth(sol) else None
        ref = variant.refinement(sol, notes) if refine and smooth is None else None
        if refine and smooth is None:
            sol, ref = variant.retry(sol, ref, guess(), notes)
        if smooth is not None:  # (no switching times: the same with or without refine)
            sol = smooth.solution
            if not refine:
                notes.append("refine=False (--no-refine) skips switching-time refinement; "
                             "this smooth optimum has no switching times, and its mesh is "
                             "refined either way")
        out = variant.finish(variant.assemble(sol, ref, notes, "transcription"))
        if smooth is not None:  # (a result without the field is never smooth)
            out.smooth = smooth  # type: ignore[attr-defined]
    out.refine_requested = refine
    if replay:
        variant.replay(out)
    return out


__all__ = ["PhasedVariant", "continuation", "landing_parameters",
           "solve_phased"]
