"""The value objects of a landing: units, the robot, the impact, and the paper's robot.

These are the only things the studies pass around: each validates its numbers
once, at construction (raising :class:`~softlanding.errors.ParameterError`
naming the field), and is frozen. The controllers live in
:mod:`softlanding.model.controllers`, the ground models in :mod:`softlanding.model.ground`.

All numbers are in the paper's dimensionless units: length
``x_s = m_t g / k_g``, time ``tau_s = sqrt(m_t / k_g)``, force ``m_t g``, with
``m_t`` the total mass and ``k_g`` the ground stiffness; :class:`Units` holds
the scales of one physical robot, and each object converts itself with
``to_si(units)`` / ``from_si(..., units)``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from softlanding.errors import ParameterError, check, check_number, check_optional

G_EARTH = 9.81
"""Gravity used by the paper, m/s^2."""

STATE_NAMES: tuple[str, ...] = ("x_b", "v_b", "x_f", "v_f")
"""The state ``[x_b, v_b, x_f, v_f]``: body height and velocity, foot height and velocity,
measured up from the undisturbed ground surface."""

XB, VB, XF, VF = range(4)


@dataclass(frozen=True)
class Units:
    """The paper's scales for a robot of total mass ``m_t`` on ground of stiffness ``k_g``.

    Parameters
    ----------
    m_t : float
        Total mass ``m_b + m_f`` [kg].
    k_g : float
        Ground stiffness [N/m] (the one-way plastic spring's).
    g : float
        Gravity [m/s^2].
    """

    m_t: float
    k_g: float
    g: float = G_EARTH

    def __post_init__(self) -> None:
        for name in ("m_t", "k_g", "g"):
            object.__setattr__(self, name, check_number(name, getattr(self, name)))

    @property
    def length(self) -> float:
        """``x_s = m_t g / k_g`` [m]: the depth at which the ground carries the weight."""
        return self.m_t * self.g / self.k_g

    @property
    def time(self) -> float:
        """``tau_s = sqrt(m_t / k_g)`` [s]."""
        return math.sqrt(self.m_t / self.k_g)

    @property
    def force(self) -> float:
        """``m_t g`` [N]."""
        return self.m_t * self.g

    @property
    def velocity(self) -> float:
        """``x_s / tau_s`` [m/s]."""
        return self.length / self.time

    @property
    def energy(self) -> float:
        """``m_t g x_s`` [J]: the unit of the dimensionless energies."""
        return self.force * self.length

    @property
    def stiffness(self) -> float:
        """``k_g`` [N/m]: the unit of a leg stiffness ``k_p``."""
        return self.k_g

    @property
    def damping(self) -> float:
        """``sqrt(m_t k_g)`` [N s/m]: the unit of a leg damping ``k_d``."""
        return math.sqrt(self.m_t * self.k_g)

    def to_dict(self) -> dict[str, float]:
        """The three defining numbers and the derived scales."""
        return {"m_t": self.m_t, "k_g": self.k_g, "g": self.g, "x_s_m": self.length,
                "tau_s_s": self.time, "u_s_N": self.force, "v_s_m_per_s": self.velocity,
                "E_s_J": self.energy}


@dataclass(frozen=True)
class Robot:
    """A two-mass leg: mass ratio, stroke, force limit and rest length (dimensionless).

    Parameters
    ----------
    r_m : float
        Mass ratio body/foot ``m_b / m_f`` (> 0).
    s : float
        Actuator stroke ``S / x_s`` (> 0): the leg length obeys ``0 <= x_b - x_f <= s``.
    u_max : float or None
        Actuator force limit ``U_max / (m_t g)`` (> 0), applied to every controller;
        None for an unlimited actuator.
    l0 : float or None
        Leg length at impact, and the default rest length of an impedance;
        None means the paper's ``s / 2``. Must lie within the stroke.

    Raises
    ------
    ParameterError
        Naming the field.
    """

    r_m: float
    s: float
    u_max: float | None = None
    l0: float | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "r_m", check_number("r_m", self.r_m))
        set_(self, "s", check_number("s", self.s))
        set_(self, "u_max", check_optional("u_max", self.u_max))
        set_(self, "l0", check_optional("l0", self.l0))
        if self.l0 is not None and self.l0 > self.s:
            raise ParameterError("l0", f"the leg length at impact must lie within the stroke "
                                       f"[0, s = {self.s:g}], got {self.l0:g}")

    @property
    def rest_length(self) -> float:
        """Leg length at impact (``s / 2`` unless given)."""
        return 0.5 * self.s if self.l0 is None else self.l0

    @property
    def body_mass(self) -> float:
        """``m_b / m_t = r_m / (1 + r_m)``: also the body's weight in units of ``m_t g``."""
        return self.r_m / (1.0 + self.r_m)

    @property
    def foot_mass(self) -> float:
        """``m_f / m_t = 1 / (1 + r_m)``."""
        return 1.0 / (1.0 + self.r_m)

    def replace(self, **changes: Any) -> Robot:
        """A copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Fields to change (``r_m``, ``s``, ``u_max``, ``l0``), validated again.
        """
        return dataclasses.replace(self, **changes)

    def without_force_limit(self) -> Robot:
        """The same robot with an unlimited actuator."""
        return self.replace(u_max=None)

    def to_si(self, units: Units) -> dict[str, float | None]:
        """``m_b, m_f`` [kg], ``stroke``, ``rest_length`` [m], ``U_max`` [N] (None: unlimited).

        Parameters
        ----------
        units : Units
            The scale (``m_t``, ``k_g``, ``g``) to convert with.
        """
        return {"m_b": units.m_t * self.body_mass, "m_f": units.m_t * self.foot_mass,
                "stroke": self.s * units.length, "rest_length": self.rest_length * units.length,
                "U_max": None if self.u_max is None else self.u_max * units.force}

    @classmethod
    def from_si(cls, m_b: float, m_f: float, stroke: float, k_g: float, *,
                U_max: float | None = None, rest_length: float | None = None,
                g: float = G_EARTH) -> tuple[Robot, Units]:
        """The dimensionless robot of a physical one, and its units.

        Parameters
        ----------
        m_b, m_f : float
            Body and foot masses [kg].
        stroke : float
            Actuator stroke [m].
        k_g : float
            Ground stiffness [N/m].
        U_max : float, optional
            Actuator force limit [N].
        rest_length : float, optional
            Leg length at impact [m] (default: half the stroke).
        g : float
            Gravity [m/s^2].
        """
        m_b, m_f = check("m_b", m_b), check("m_f", m_f)
        units = Units(m_b + m_f, k_g, g)
        robot = cls(r_m=m_b / m_f, s=check("stroke", stroke) / units.length,
                    u_max=None if U_max is None else check("U_max", U_max) / units.force,
                    l0=None if rest_length is None
                    else check("rest_length", rest_length) / units.length)
        return robot, units

    def to_dict(self) -> dict[str, float | None]:
        """Fields, with the rest length resolved."""
        return {"r_m": self.r_m, "s": self.s, "u_max": self.u_max, "l0": self.rest_length}


@dataclass(frozen=True)
class Impact:
    """The state at touchdown: both masses moving at ``v0`` (the paper's initial condition).

    Parameters
    ----------
    v0 : float
        Impact velocity ``V0 tau_s / x_s`` (<= 0: negative is downward).
    """

    v0: float

    def __post_init__(self) -> None:
        if np.ndim(self.v0) != 0:
            raise ParameterError("v0", f"must be one number, got an array of shape "
                                       f"{np.shape(self.v0)} (many impacts: simulate_batch)")
        object.__setattr__(self, "v0", check_number("v0", self.v0))

    @classmethod
    def of(cls, value: Impact | float) -> Impact:
        """An :class:`Impact`, or one made from a bare velocity."""
        return value if isinstance(value, Impact) else cls(value)

    def initial_state(self, robot: Robot) -> np.ndarray:
        """``[l0, v0, 0, v0]``: the foot at the surface, the leg at its rest length.

        Parameters
        ----------
        robot : Robot
            The robot (its leg length at impact).
        """
        return np.array([robot.rest_length, self.v0, 0.0, self.v0])

    @property
    def energy(self) -> float:
        """Impact kinetic energy ``v0^2 / 2`` (units of ``m_t g x_s``)."""
        return 0.5 * self.v0 * self.v0

    def to_si(self, units: Units) -> dict[str, float]:
        """``V0`` [m/s].

        Parameters
        ----------
        units : Units
            The scale (``m_t``, ``k_g``, ``g``) to convert with.
        """
        return {"V0": self.v0 * units.velocity}

    @classmethod
    def from_si(cls, V0: float, units: Units) -> Impact:
        """From an impact velocity ``V0`` [m/s] (<= 0)."""
        return cls(check("V0", V0) / units.velocity)

    def to_dict(self) -> dict[str, float]:
        """``{"v0": v0}``."""
        return {"v0": self.v0}


PAPER_ROBOT = Robot(r_m=5.0, s=20.0, u_max=8.2)
"""The paper's robot (Section II-C): ``r_m = 5``, ``s = 20``, ``u_max = 8.2``.

The paper takes ``u_max = 8.2`` from the peak force of its optimal impedance
at ``v0 = -10`` and uses it as the bound of the bang-bang problem; its
impedance study itself renders the impedance without a force limit, which is
:data:`PAPER_IMPEDANCE_ROBOT`.
"""

PAPER_IMPEDANCE_ROBOT = PAPER_ROBOT.without_force_limit()
"""The paper's robot as its impedance study treats it: no force limit."""

__all__ = ["G_EARTH", "Impact", "PAPER_IMPEDANCE_ROBOT", "PAPER_ROBOT", "Robot", "Units"]
