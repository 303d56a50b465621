"""Exceptions and warnings of the ocp package."""

from __future__ import annotations

from collections.abc import Callable
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
    diagnose : callable, optional
        ``() -> diagnosis``: what is wrong at the last iterate
        (:class:`ocp.transcriptions.diagnosis.Diagnosis`), run when first asked for;
        its one line ends the message.

    Attributes
    ----------
    diagnosis : Diagnosis or None
        The analysis of the last iterate (None without ``diagnose``).
    """

    def __init__(self, status: str, iterate: Any = None, message: str | None = None,
                 diagnose: Callable[[], Any] | None = None) -> None:
        self.status = status
        self.iterate = iterate
        self._text = message or f"Ipopt failed: {status}"
        self._diagnose = diagnose
        self._diagnosis: Any = None
        super().__init__(self._text)

    @property
    def diagnosis(self) -> Any:
        """The analysis of the last iterate (computed on first access)."""
        if self._diagnosis is None and self._diagnose is not None:
            try:
                self._diagnosis = self._diagnose()
            except Exception as exc:  # noqa: BLE001 (an analysis must not hide the failure)
                self._diagnosis = f"no diagnosis ({type(exc).__name__}: {exc})"[:200]
            self._diagnose = None
        return self._diagnosis

    def __reduce__(self) -> tuple[Any, ...]:
        # the analysis is a closure over the transcription: pickled as its result, if any
        state = {k: v for k, v in self.__dict__.items() if k != "_diagnose"}
        return self.__class__, self.args, state

    def __str__(self) -> str:
        d = self.diagnosis
        return self._text if d is None else f"{self._text}: {d}"


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


class ScalingFallbackWarning(UserWarning):
    """The scaled NLP failed and the NLP as posed (``scaling="none"``) solved."""


class DroppedConditionWarning(UserWarning):
    """A dependent end condition was left out of the solve (``drop_dependent=True``)."""


class ConvergenceWarning(UserWarning):
    """Mesh refinement did not converge, with what the problem suggests as the cause."""
