"""Exceptions and warnings of the ocp package."""

from __future__ import annotations

from typing import Any


class ProblemDefinitionError(ValueError):
    """The problem is incompletely or inconsistently defined, or an argument is invalid.

    Raised at definition time (when the offending call is made) wherever the
    mistake can be seen then; the message names the argument.
    """


class GuessError(ProblemDefinitionError):
    """The initial guess makes an expression of the problem non-finite (before any solve)."""


class SolveError(RuntimeError):
    """Ipopt did not converge to a solution.

    Parameters
    ----------
    status : str
        Ipopt's return status (e.g. ``"Infeasible_Problem_Detected"``,
        ``"Maximum_Iterations_Exceeded"``, ``"Restoration_Failed"``).
    iterate : Any
        The last iterate, as a :class:`ocp.Solution` (not an optimum).
    message : str, optional
        The text (default: ``"Ipopt failed: STATUS"``).
    """

    def __init__(self, status: str, iterate: Any = None, message: str | None = None) -> None:
        self.status = status
        self.iterate = iterate
        super().__init__(message or f"Ipopt failed: {status}")


class InfeasibleError(SolveError):
    """Ipopt reports the problem (locally) infeasible.

    Parameters
    ----------
    status : str
        Ipopt's return status.
    iterate : Any
        The last iterate, as a :class:`ocp.Solution` (infeasible: not a candidate).
    message : str, optional
        The text.
    """


class PathViolationError(SolveError):
    """Ipopt converged, but a path constraint or state bound is violated between nodes.

    Parameters
    ----------
    status : str
        ``"Path_Violated_Between_Nodes"``.
    iterate : Any
        The converged :class:`ocp.Solution` (its ``path_violation`` says by how much).
    message : str, optional
        The text.
    """


class PathViolationWarning(UserWarning):
    """A converged solution violates a path constraint between its nodes."""
