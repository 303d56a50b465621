"""The closed loop's options and their bounds: the controllers and estimators by name, the
sample period and the sensor's noise.

A light module (no numba, no CasADi): the command line checks its options here before it
imports the controllers, so that a bad option is refused in a fraction of a second.
"""

from __future__ import annotations

from typing import Any

from softlanding.errors import ParameterError, check

#: The default sample period, in the paper's time unit ``sqrt(m_t / k_g)`` (26 ms on the
#: paper's rig, so 0.26 ms: a 4 kHz controller): a tenth of the shortest bang arc of the
#: paper's landings.
DEFAULT_PERIOD = 0.01

#: The shortest sample period taken: 1e-4 (2.6 us on the paper's rig), about 10,000 samples
#: over the longest landing of the unknown-ground study (T < 1); a shorter one would run for
#: hours (1e-9: a million times more samples) and is refused at once.
MIN_PERIOD = 1e-4

#: The longest sample period taken: the landing problem's horizon bound
#: (:data:`softlanding.optimal.landing.T_MAX`, the same number: a test keeps them equal). A
#: period beyond the landing is one open-loop sample; far beyond it (1e300) the simulation's
#: times lose every digit of the landing's.
MAX_PERIOD = 30.0

#: The controllers :func:`~softlanding.control.mpc_landing` runs, by name: the compiled
#: real-time controller (the default) and the re-planning MPC.
CONTROLLERS = ("bangbang", "replan")

#: What the ground estimate regresses (:func:`~softlanding.control.mpc_landing`'s
#: ``estimator``).
ESTIMATORS = ("measured", "filtered")

#: The least sensor noise (standard deviation, paper units) taken, but 0 (exact): the
#: measured states are of order 1 to 10, so their own rounding is about 1e-15; the foot
#: filter weighs each innovation by the noise, which below the states' rounding means
#: nothing (1e-20 divided by zero in it). 1e-12 keeps a factor 100 over that; landings at
#: 1e-12 and 1e-14 end at the clairvoyant depth to 6e-13.
MIN_NOISE = 1e-12

#: The largest sensor noise taken (paper units: 0.67 mm of foot position on the paper's rig,
#: 26 mm/s of velocity, 0.1 g of acceleration, a tenth of the robot's weight in force). The
#: estimator then still finds the ground within a landing; far beyond (1, 10: a noise the
#: size of the depth) a landing's measurements carry no ground the model can mean, and the
#: landing was a force limit broken or a stroke left (issue 47).
MAX_NOISE = 0.1


def check_period(name: str, period: Any) -> float:
    """A sample period within [:data:`MIN_PERIOD`, :data:`MAX_PERIOD`].

    Parameters
    ----------
    name : str
        The argument's name in the message (``--period`` on the command line).
    period : float
        What the caller gave.

    Raises
    ------
    ParameterError
        Not finite, or out of the range.
    """
    return check(name, period, (lambda v: (v >= MIN_PERIOD) & (v <= MAX_PERIOD),
                                f"must be within [{MIN_PERIOD:g}, {MAX_PERIOD:g}] (the "
                                f"shortest bounds the samples per landing to about 1e4)"))


def check_noise(name: str, noise: Any) -> float:
    """A sensor noise: 0 (exact), or within [:data:`MIN_NOISE`, :data:`MAX_NOISE`].

    Parameters
    ----------
    name : str
        The argument's name in the message (``--noise-std`` on the command line).
    noise : float
        What the caller gave.

    Raises
    ------
    ParameterError
        Not finite, or out of the range.
    """
    return check(name, noise, (
        lambda v: (v == 0) | ((v >= MIN_NOISE) & (v <= MAX_NOISE)),
        f"must be 0 (exact measurements) or within [{MIN_NOISE:g}, {MAX_NOISE:g}] (below, "
        f"less than the measured states' own rounding; above, measurements too noisy for "
        f"the ground estimate within a landing)"))


def check_choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    """One of ``choices``.

    Parameters
    ----------
    name : str
        The argument's name in the message.
    value : str
        What the caller gave.
    choices : tuple of str
        The names taken.

    Raises
    ------
    ParameterError
        Another value.
    """
    if value not in choices:
        raise ParameterError(name, f"must be one of {', '.join(choices)}, got {value!r}")
    return value


__all__ = ["CONTROLLERS", "DEFAULT_PERIOD", "ESTIMATORS", "MAX_NOISE", "MAX_PERIOD",
           "MIN_NOISE", "MIN_PERIOD", "check_choice", "check_noise", "check_period"]
