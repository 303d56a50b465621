"""Every exception of the package, and the one place where model numbers are validated.

The CLI turns a :class:`SoftlandingError` into one line on stderr and the
error's :attr:`~SoftlandingError.exit_code` (2: bad input, 1: a well-posed
request that failed); anything else escaping the package is a bug.

Validation rules live in :data:`FIELDS`, keyed by the names the user writes
(``r_m``, ``s``, ``v0``, ...); :func:`check` applies them to a number or to a
whole array, so value objects and batch entry points share one validator.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, overload

import numpy as np


class SoftlandingError(Exception):
    """Base class of the package's own errors (the CLI prints them on one line)."""

    exit_code = 1
    label = "error"


class ParameterError(SoftlandingError, ValueError):
    """A model or simulation parameter is out of its valid range (bad input).

    Parameters
    ----------
    parameter : str
        Name of the offending parameter, as the user wrote it (e.g. ``"v0"``).
    message : str
        What is wrong with it.

    Attributes
    ----------
    parameter : str
        Name of the offending parameter.
    """

    exit_code = 2

    def __init__(self, parameter: str, message: str) -> None:
        self.parameter = parameter
        super().__init__(f"{parameter}: {message}")


class InfeasibleLandingError(SoftlandingError, ValueError):
    """A well-posed landing problem has no solution; the message names the condition."""

    exit_code = 1
    label = "infeasible"


class RestNotProvenError(SoftlandingError):
    """A landing whose rest could not be proven was asked for a figure that needs rest."""


class ClusterError(SoftlandingError):
    """A Dask cluster stopped delivering results (no worker left, or none for too long)."""

    exit_code = 1
    label = "cluster"


class ExportError(SoftlandingError):
    """The exported C controller did not compile, or does not compute what the Python one does
    (``softlanding export-controller --check``)."""

    exit_code = 1
    label = "export"


class DiskFullError(SoftlandingError):
    """An output could not be written: its disk is full (or the user's quota is used up).

    The run's outputs are removed (nothing half-written is left); the message names the
    folder. A failed run (exit 1), not bad input: the same command succeeds with space.
    """

    exit_code = 1
    label = "error"


def plain(value: Any) -> str:
    """A number as a user typed it (no numpy repr such as ``np.float64(nan)``).

    Parameters
    ----------
    value : Any
        Usually a number (Python or numpy).
    """
    if isinstance(value, bool | str) or value is None:
        return repr(value)
    try:
        x = float(value)
    except (TypeError, ValueError):
        return repr(value)
    if math.isfinite(x) and x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    return repr(x)  # the shortest string that reads back as x: 0.5, 1e+300, nan


# ----------------------------------------------------------------- the rules
Rule = tuple[Callable[[np.ndarray], np.ndarray], str]

POSITIVE: Rule = (lambda x: x > 0.0, "must be > 0")
NONNEGATIVE: Rule = (lambda x: x >= 0.0, "must be >= 0")
FINITE: Rule = (lambda x: np.isfinite(x), "must be finite")


def within(lo: float, hi: float, open_lo: bool = False, why: str = "") -> Rule:
    """A rule ``lo <(=) x <= hi``, with the reason for the range in its message.

    Parameters
    ----------
    lo, hi : float
        The range.
    open_lo : bool
        Exclude ``lo``.
    why : str
        What the number is, for the message.
    """
    left = "(" if open_lo else "["
    msg = f"must be in {left}{lo:g}, {hi:g}]" + (f" ({why})" if why else "")
    if open_lo:
        return (lambda x: (x > lo) & (x <= hi), msg)
    return (lambda x: (x >= lo) & (x <= hi), msg)


#: What the model and double precision can serve: beyond these, event times and depths lose
#: their meaning (a body 1000 times lighter than its foot is not a legged robot, and an impact
#: at 1000 velocity units buries the robot a thousand times its weight depth).
LIMITS = {"r_m": (1e-3, 1e3), "s": (1e-3, 1e4), "u_max": (0.0, 1e4), "v0": (-1e3, 0.0),
          "gain": (0.0, 1e6)}

FIELDS: dict[str, Rule] = {
    # dimensionless model
    "r_m": within(*LIMITS["r_m"], why="mass ratio m_b / m_f"),
    "s": within(*LIMITS["s"], why="stroke S / x_s"),
    "u_max": within(*LIMITS["u_max"], open_lo=True, why="force limit / (m_t g)"),
    "l0": NONNEGATIVE,
    "v0": within(*LIMITS["v0"], why="negative = moving down onto the ground"),
    "k_p": within(*LIMITS["gain"], why="stiffness K_p / k_g"),
    "k_d": within(*LIMITS["gain"], why="damping K_d / sqrt(m_t k_g)"),
    "times": FINITE, "values": FINITE, "durations": POSITIVE,
    # ground models
    "c_d": within(0.0, 1e3, why="drag number b x_s / m_t"), "pi_a": within(0.0, 1e3),
    "radius": POSITIVE, "kappa": POSITIVE, "b": NONNEGATIVE,
    "stiffness": within(1e-3, 1e3, why="ground stiffness factor K (f = K d; 1: the paper's)"),
    # SI (their dimensionless images are checked against the limits above)
    "m_b": POSITIVE, "m_f": POSITIVE, "m_t": POSITIVE, "k_g": POSITIVE, "stroke": POSITIVE,
    "g": POSITIVE, "U_max": POSITIVE, "V0": (lambda x: x <= 0.0, "must be <= 0 (downward)"),
    "K_p": NONNEGATIVE, "K_d": NONNEGATIVE, "rest_length": NONNEGATIVE,
    # run settings
    "t_max": POSITIVE, "factor": POSITIVE,
    "rtol": within(1e-15, 1e-3, why="integrator tolerance of a non-affine ground"),
    "foot_diameter": POSITIVE, "exponent": within(0.0, 10.0, open_lo=True, why="f = d^n"),
}
"""The validation rule of every named model number (finiteness is always required)."""


@overload
def check(name: str, value: float, rule: Rule | None = None) -> float: ...
@overload
def check(name: str, value: np.ndarray, rule: Rule | None = None) -> np.ndarray: ...
@overload
def check(name: str, value: Sequence[Any], rule: Rule | None = None) -> np.ndarray: ...


def check(name: str, value: Any, rule: Rule | None = None) -> Any:
    """Validate a number (returned as ``float``) or an array (returned as a float array).

    Parameters
    ----------
    name : str
        The field's name; its rule is ``FIELDS[name]`` unless ``rule`` is given.
    value : float or array_like
        What the user gave.
    rule : (predicate, message), optional
        Overrides the rule looked up by name.

    Raises
    ------
    ParameterError
        Naming the field and the first offending value.
    """
    test, what = rule if rule is not None else FIELDS[name]
    if type(value) is float or type(value) is int:  # the common case, without numpy
        try:
            x = float(value)
        except OverflowError:  # an int beyond any float (10**400)
            raise ParameterError(name, f"must be finite, got an integer of "
                                       f"{len(str(abs(value)))} digits") from None
        if not math.isfinite(x):
            raise ParameterError(name, f"must be finite, got {plain(x)}")
        if not test(np.asarray(x)):
            raise ParameterError(name, f"{what}, got {plain(x)}")
        return x
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):  # (a ragged nesting included)
        raise ParameterError(name, f"must be a number, got {plain(value)}") from None
    scalar = arr.ndim == 0 and not isinstance(value, np.ndarray)
    bad = ~np.isfinite(arr)
    if bad.any():
        raise ParameterError(name, f"must be finite, got {plain(arr[bad].flat[0])}")
    ok = np.asarray(test(arr), dtype=bool)
    if not ok.all():
        raise ParameterError(name, f"{what}, got {plain(arr[~ok].flat[0])}")
    return float(arr) if scalar else arr


def check_number(name: str, value: Any, rule: Rule | None = None) -> float:
    """:func:`check` of one number: a model's field is a scalar, never an array (which
    :func:`check` passes through for batch inputs), a sequence, a string or a bool (``True``
    would be read as 1 and ``"5"`` as 5, silently).

    Parameters
    ----------
    name : str
        The field's name.
    value : float
        What the user gave.
    rule : (predicate, message), optional
        As for :func:`check`.

    Raises
    ------
    ParameterError
        Naming the field.
    """
    if type(value) is float or type(value) is int:  # the common case
        return check(name, value, rule)
    if isinstance(value, bool | np.bool_ | str | bytes):
        raise ParameterError(name, f"must be a number, got {value!r}")
    shape = np.shape(value) if isinstance(value, np.ndarray) or hasattr(value, "shape") \
        else None
    if shape not in (None, ()):
        raise ParameterError(name, f"must be one number, got an array of shape {shape}")
    if getattr(getattr(value, "dtype", None), "kind", "f") in "bUSO":  # (0-d bool or text)
        raise ParameterError(name, f"must be a number, got {value!r}")
    if isinstance(value, list | tuple | dict | set):
        raise ParameterError(name, f"must be one number, got a {type(value).__name__}")
    return float(check(name, value, rule))


def check_optional(name: str, value: float | None) -> float | None:
    """:func:`check_number` unless ``value`` is None (e.g. an unlimited force).

    Parameters
    ----------
    name : str
        The field's name.
    value : float or None
        What the user gave.
    """
    return None if value is None else check_number(name, value)


# (class, Protocol) pairs already checked, for the package's own frozen dataclasses only: a
# runtime-checkable Protocol's isinstance looks every member up on every call (24 us on
# Python 3.11; two per simulation, 5 % of a robust search's samples), and an instance of a
# frozen class of ours cannot differ from another in its members (a user's class can: a
# method set to None, an unset slot, a property that raises), so those are checked each time
_CLASS_MEETS_PROTOCOL: set[tuple[type, Any]] = set()


def _same_members_for_every_instance(cls: type) -> bool:
    params = getattr(cls, "__dataclass_params__", None)
    return cls.__module__.startswith("softlanding.") and bool(params and params.frozen)


def expect(name: str, value: Any, kind: Any, what: str | None = None) -> Any:
    """``value`` if it is an instance of ``kind``, else a :class:`ParameterError` naming
    ``name`` (the API's answer to a wrong type, instead of an AttributeError deep inside).

    Parameters
    ----------
    name : str
        The argument's name.
    value : Any
        What was passed.
    kind : type or tuple of types
        What is accepted (a ``runtime_checkable`` Protocol works too).
    what : str, optional
        How to name the accepted kinds in the message (default: their class names).
    """
    if (type(value), kind) in _CLASS_MEETS_PROTOCOL:
        return value
    if isinstance(value, kind):
        if getattr(kind, "_is_protocol", False) and _same_members_for_every_instance(type(value)):
            _CLASS_MEETS_PROTOCOL.add((type(value), kind))
        return value
    if what is None:
        kinds = kind if isinstance(kind, tuple) else (kind,)
        what = " or ".join(k.__name__ for k in kinds)
    raise ParameterError(name, f"must be a {what}, got {type(value).__name__} {value!r:.60}")


def check_count(name: str, value: Any, lower: int = 1, upper: int | None = None) -> int:
    """An integer size the user typed, within ``[lower, upper]``.

    Parameters
    ----------
    name : str
        The option's name.
    value : Any
        What the user gave (``2.5`` is refused, ``2.0`` accepted).
    lower, upper : int
        Inclusive bounds (``upper`` None: no bound).

    Raises
    ------
    ParameterError
        If it is not an integer (``2.5``), or out of range.
    """
    try:
        n = int(value)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(name, f"must be an integer, got {plain(value)}") from None
    if n != value:
        raise ParameterError(name, f"must be an integer, got {plain(value)}")
    if n < lower:
        raise ParameterError(name, f"must be >= {lower}, got {n}")
    if upper is not None and n > upper:
        raise ParameterError(name, f"must be <= {upper}, got {n}")
    return n
