"""The scaling references a user gives (``ref``/``ref0`` of a variable, ``ref`` of a
constraint or of the objective), checked (:mod:`ocp.definition.scaling` uses them)."""

from __future__ import annotations

from .errors import ProblemDefinitionError
from .symbols import finite_number

__all__ = ["constraint_ref", "objective_ref", "scale_ref"]


def scale_ref(ref: float | None, ref0: float | None, what: str) -> tuple[float, float] | None:
    """``(ref0, ref)`` checked (finite, ``ref > 0``), or None if neither is given.

    As in dymos, the NLP sees ``(value - ref0) / ref``: ``ref0`` maps to 0 and
    ``ref0 + ref`` to 1 (``ref0`` defaults to 0, ``ref`` to 1).

    Parameters
    ----------
    ref, ref0 : float or None
        The reference values.
    what : str
        Named in the error.
    """
    if ref is None and ref0 is None:
        return None
    r = 1.0 if ref is None else finite_number(ref, f"{what}: ref")
    r0 = 0.0 if ref0 is None else finite_number(ref0, f"{what}: ref0")
    if not r > 0:
        raise ProblemDefinitionError(f"{what}: ref must be positive, got {r:g}")
    return r0, r


def objective_ref(ref: float | None) -> float | None:
    """A checked objective reference (finite, positive) or None.

    Parameters
    ----------
    ref : float or None
        The objective's typical magnitude.
    """
    return constraint_ref(ref, "minimize")


def constraint_ref(ref: float | None, what: str) -> float | None:
    """A checked constraint reference (finite, positive) or None.

    Parameters
    ----------
    ref : float or None
        The constraint's typical size.
    what : str
        Named in the error.
    """
    if ref is None:
        return None
    r = finite_number(ref, f"{what}: ref")
    if not r > 0:
        raise ProblemDefinitionError(f"{what}: ref must be positive, got {r:g}")
    return r
