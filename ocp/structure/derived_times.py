"""The final time of a problem derived for the refinement (costate copies, decision variables
as states): the original's, on the refinement's clock, which starts at 0."""

from __future__ import annotations

from ..definition.problem import OptimalControlProblem


def same_final_time(q: OptimalControlProblem, pr: OptimalControlProblem) -> None:
    """Give ``q`` the final time of ``pr``: fixed, free within its bounds, or a duration's
    (fixed or free; with time from 0 a duration is the final time).

    Parameters
    ----------
    q : OptimalControlProblem
        The derived problem (modified).
    pr : OptimalControlProblem
        The original (its initial time 0: :func:`~ocp.structure.refinement.refuse_shifted_time`).
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


__all__ = ["same_final_time"]
