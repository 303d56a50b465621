"""Small helpers on CasADi symbols and bounds shared by the problem classes."""

from __future__ import annotations

import math
import numbers
import operator
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

from .errors import ProblemDefinitionError

INF = float("inf")


@dataclass
class Constraint:
    """``lower <= expr <= upper`` (bounds: numbers or parameter expressions).

    Attributes
    ----------
    expr : casadi.SX
        The constrained expression.
    lower, upper : casadi.SX
        Bounds (numbers or parameter expressions).
    name : str
        Name in messages and multipliers.
    ref : float or None
        Typical size: the NLP row is divided by it (:mod:`ocp.definition.scaling`).
    """

    expr: ca.SX
    lower: ca.SX
    upper: ca.SX
    name: str
    ref: float | None = None  # typical size: the NLP row is divided by it (ocp.definition.scaling)


def to_sx(value: object, what: str) -> ca.SX:
    """``value`` as a CasADi SX, or a :class:`ProblemDefinitionError` naming ``what``.

    Parameters
    ----------
    value : object
        A number, an SX, or something CasADi turns into one.
    what : str
        Named in the error.
    """
    if isinstance(value, ca.SX):
        return value
    if isinstance(value, ca.MX):
        raise ProblemDefinitionError(f"{what}: MX expressions are not supported; use the "
                                     "problem's SX symbols")
    try:
        return ca.SX(value)  # type: ignore[call-overload]
    except (NotImplementedError, TypeError, RuntimeError) as err:
        raise ProblemDefinitionError(f"{what}: {value!r} is not a number or expression") from err


def constant(value: ca.SX) -> float | None:
    """The float of a constant scalar SX, else None.

    Parameters
    ----------
    value : SX
        A scalar expression.
    """
    if value.numel() == 1 and value.is_constant():
        return float(value)  # the same double as through DM, without making one (~30 us)
    return None


def check_bounds(lower: ca.SX, upper: ca.SX, what: str) -> None:
    """Reject NaN bounds and numeric ``lower > upper`` (naming ``what``).

    Parameters
    ----------
    lower, upper : SX
        The bounds.
    what : str
        Named in the error.
    """
    lo, hi = constant(lower), constant(upper)
    for v, side in ((lo, "lower"), (hi, "upper")):
        if v is not None and math.isnan(v):
            raise ProblemDefinitionError(f"{what}: {side} bound is NaN")
    if lo is not None and hi is not None and lo > hi:
        raise ProblemDefinitionError(f"{what}: lower bound {lo:g} exceeds upper bound {hi:g}")
    if lo == INF or hi == -INF:
        raise ProblemDefinitionError(f"{what}: bounds ({lo}, {hi}) leave no feasible value")


def free_names(expr: ca.SX, allowed: Sequence[ca.SX]) -> list[str]:
    """Names of the symbols in ``expr`` that are not among ``allowed``.

    Parameters
    ----------
    expr : SX
        The expression.
    allowed : sequence of SX
        The symbols it may use.
    """
    if expr.numel() == 0 or expr.is_constant():
        return []
    allowed_v = ca.vertcat(*allowed) if allowed else ca.SX(0, 1)
    f = ca.Function("chk", [allowed_v], [expr], {"allow_free": True})
    return [str(s) for s in f.free_sx()]


def require_only(expr: ca.SX, allowed: Sequence[ca.SX], what: str, hint: str = "") -> None:
    """Raise a :class:`ProblemDefinitionError` if ``expr`` uses symbols outside ``allowed``.

    Parameters
    ----------
    expr : SX
        The expression.
    allowed : sequence of SX
        The symbols it may use.
    what : str
        Named in the error.
    hint : str
        Appended to the error.
    """
    bad = free_names(expr, allowed)
    if bad:
        raise ProblemDefinitionError(f"{what} depends on {sorted(set(bad))}, which it may not"
                                     + (f" ({hint})" if hint else ""))


def finite_number(value: object, what: str) -> float:
    """``value`` as a finite float, or a :class:`ProblemDefinitionError` naming ``what``.

    Parameters
    ----------
    value : object
        The value.
    what : str
        Named in the error.
    """
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as err:
        raise ProblemDefinitionError(f"{what} must be a number, got {value!r}") from err
    if not math.isfinite(v):
        raise ProblemDefinitionError(f"{what} must be finite, got {v}")
    return v


def positive_number(value: object, what: str) -> float:
    """``value`` as a finite float > 0, or a :class:`ProblemDefinitionError` naming ``what``.

    Parameters
    ----------
    value : object
        The value.
    what : str
        Named in the error.
    """
    v = finite_number(value, what)
    if v <= 0.0:
        raise ProblemDefinitionError(f"{what} must be > 0, got {v!r}")
    return v


def positive_int(value: object, what: str, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``; rejects floats (even 2.0) and bools.

    Parameters
    ----------
    value : object
        The value.
    what : str
        Named in the error.
    minimum : int
        Smallest allowed value.
    """
    if isinstance(value, bool):
        raise ProblemDefinitionError(f"{what} must be an integer, got {value!r}")
    try:
        v = operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise ProblemDefinitionError(f"{what} must be an integer, got {value!r}") from None
    if v < minimum:
        raise ProblemDefinitionError(f"{what} must be >= {minimum}, got {v}")
    return v


def relative_tolerance(value: object, what: str, allow_inf: bool = False) -> float:
    """``value`` as a relative tolerance in (0, 1), or a :class:`ProblemDefinitionError`.

    A tolerance of 0 or below can never be met, NaN compares false with everything
    (it would switch a check off silently), and 1 or more is no accuracy at all.

    Parameters
    ----------
    value : object
        The value.
    what : str
        Named in the error.
    allow_inf : bool
        Accept ``math.inf`` (documented as switching a criterion off).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ProblemDefinitionError(f"{what} must be a number, got {value!r}")
    v = float(value)
    if allow_inf and v == math.inf:
        return v
    if not (math.isfinite(v) and 0.0 < v < 1.0):
        extra = " (math.inf switches it off)" if allow_inf else ""
        raise ProblemDefinitionError(f"{what} must be a relative tolerance in (0, 1){extra}, "
                                     f"got {v!r}")
    return v
