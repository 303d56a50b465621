"""Exceptions of the ocp package."""

from __future__ import annotations

from typing import Any


class SolveError(RuntimeError):
    """Ipopt did not converge to a solution.

    Attributes
    ----------
    status : str
        Ipopt's return status (e.g. ``"Infeasible_Problem_Detected"``,
        ``"Maximum_Iterations_Exceeded"``, ``"Restoration_Failed"``).
    iterate : Any
        The last iterate, as a :class:`ocp.Solution` (not an optimum).
    """

    def __init__(self, status: str, iterate: Any = None, message: str | None = None) -> None:
        self.status = status
        self.iterate = iterate
        super().__init__(message or f"Ipopt failed: {status}")


class InfeasibleError(SolveError):
    """Ipopt reports the problem (locally) infeasible."""
