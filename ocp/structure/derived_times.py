"""The refinement's clock, which starts at 0: problems whose time does not are refused, and a
problem derived for the refinement (costate copies, decision variables as states) gets the
original's final time on it."""

from __future__ import annotations

from ..definition.errors import ProblemDefinitionError
from ..definition.problem import OptimalControlProblem


def refuse_shifted_time(pr: OptimalControlProblem) -> None:
    """Refuse a problem whose time does not start at 0 (the refinement's clock).

    The switching-time NLP measures time from 0: its final time is the sum of the arcs'
    durations. A free initial time, or one fixed elsewhere than 0, would be refined on
    another horizon (a silent wrong optimum).

    Parameters
    ----------
    pr : OptimalControlProblem

    Raises
    ------
    ProblemDefinitionError
        If the initial time is free or fixed at a value other than 0 (a ``ValueError``).
    """
    if pr.t0_mode == "free" or (pr.t0_mode == "fixed" and pr.t0_bounds[0] != 0.0):
        what = ("free" if pr.t0_mode == "free" else f"fixed at {pr.t0_bounds[0]:g}")
        raise ProblemDefinitionError(
            f"switching-time refinement: problem {pr.name!r} has its initial time {what}; "
            "the refinement's time starts at 0 (pose the problem on [0, T], or as a phase of "
            "a multi-phase problem, which ocp.structure.phase_refinement.refine_phases refines)")


def same_final_time(q: OptimalControlProblem, pr: OptimalControlProblem) -> None:
    """Give ``q`` the final time of ``pr``: fixed, free within its bounds, or a duration's
    (fixed or free; with time from 0 a duration is the final time).

    Parameters
    ----------
    q : OptimalControlProblem
        The derived problem (modified).
    pr : OptimalControlProblem
        The original (its initial time 0: :func:`refuse_shifted_time`).
    """
    if pr.duration is not None:  # (its T_bounds are infinite: the duration holds the bounds)
        lo, hi = pr.duration
        if lo == hi:
            q.fixed_duration(lo)
        else:
            q.free_duration(lo, hi, guess=pr.duration_guess)
    elif pr.time_free:
        q.free_final_time(*pr.T_bounds, guess=pr.T_guess)
    else:
        q.fixed_final_time(pr.T_bounds[0])


__all__ = ["refuse_shifted_time", "same_final_time"]
