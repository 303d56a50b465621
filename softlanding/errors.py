"""Exceptions raised by the toolkit.

Every bad input raises a :class:`ParameterError` naming the offending parameter,
so callers can catch one type and the CLI can print one line.
"""

from __future__ import annotations

import math


class ParameterError(ValueError):
    """A model or simulation parameter is out of its valid range.

    Attributes
    ----------
    parameter : str
        Name of the offending parameter (as the user wrote it, e.g. ``"v0"``).
    """

    def __init__(self, parameter: str, message: str) -> None:
        self.parameter = parameter
        super().__init__(f"{parameter}: {message}")


def check_finite(name: str, value: float) -> float:
    """Return ``float(value)`` or raise :class:`ParameterError` if it is not finite."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ParameterError(name, f"must be finite, got {value!r}")
    return x


def check_positive(name: str, value: float) -> float:
    """Finite and strictly positive."""
    x = check_finite(name, value)
    if x <= 0.0:
        raise ParameterError(name, f"must be > 0, got {value!r}")
    return x


def check_nonnegative(name: str, value: float) -> float:
    """Finite and >= 0."""
    x = check_finite(name, value)
    if x < 0.0:
        raise ParameterError(name, f"must be >= 0, got {value!r}")
    return x


def check_impact_velocity(name: str, value: float) -> float:
    """Finite and <= 0 (heights are measured upward, so a landing has v0 <= 0)."""
    x = check_finite(name, value)
    if x > 0.0:
        raise ParameterError(
            name, f"must be <= 0 (negative = moving down onto the ground), got {value!r}"
        )
    return x
