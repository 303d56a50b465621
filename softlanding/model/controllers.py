"""Leg controllers: a rigid lock, an impedance (spring-damper), an open-loop force schedule.

Each is a frozen value object validated at construction. The robot's force
limit (:attr:`softlanding.model.robot.Robot.u_max`) saturates whatever force a
controller asks for; the simulator reads each controller's law as an affine
functional of the augmented state ``z = [x_b, v_b, x_f, v_f, 1]`` per ground
mode (:meth:`kernel_arrays`), so every law stays exact.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from softlanding.errors import FINITE, ParameterError, check, check_number, check_optional
from softlanding.model.robot import VB, VF, Robot, Units

EMPTY = np.zeros(0)


def impedance_gains(k_p: Any, k_d: Any, l0: Any) -> np.ndarray:
    """``K`` with ``u = K . [x_b, v_b, x_f, v_f, 1] = -k_p (x_b - x_f - l0) - k_d (v_b - v_f)``.

    Parameters
    ----------
    k_p, k_d : float or array
        Stiffness and damping (arrays give one gain vector per column).
    l0 : float or array
        Rest length.
    """
    return np.array([-k_p, -k_d, k_p, k_d, k_p * l0])


def rigid_lock_gains(mats: dict[str, Any]) -> np.ndarray:
    """Per-mode feedback ``u = Kf[mode] . z`` keeping ``v_b' = v_f'``, read off the mode matrices.

    Parameters
    ----------
    mats : dict
        :func:`softlanding.model.dynamics.mode_matrices` of the robot and ground.
    """
    R = np.zeros(5)
    R[VB], R[VF] = 1.0, -1.0
    Kf = np.empty((3, 5))
    for m in range(3):
        Kf[m] = -(R @ mats["A"][m]) / (R @ mats["B"][m])
    return Kf


@dataclass(frozen=True)
class Rigid:
    """Body and foot locked together: the actuator supplies whatever force keeps the
    leg length constant (derived per ground mode from the dynamics), up to the
    robot's force limit (beyond it the lock slips)."""

    def describe(self) -> str:
        """One line for tables and titles."""
        return "rigid leg"

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-mode feedback keeping ``v_b' = v_f'``, read off the mode matrices.

        Parameters
        ----------
        mats : dict
            :func:`softlanding.model.dynamics.mode_matrices` of the robot and ground.
        robot : Robot
            Unused (the lock has no parameter).

        Returns
        -------
        Kf : (3, 5) array
            ``u = Kf[mode] . z``.
        sched_t, sched_u : empty arrays
            (no open-loop schedule)
        """
        return rigid_lock_gains(mats), EMPTY, EMPTY

    def to_si(self, units: Units) -> dict[str, Any]:
        """No parameter to convert.

        Parameters
        ----------
        units : Units
            The scale (nothing to convert).
        """
        return {}

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "rigid"}``."""
        return {"kind": "rigid"}


@dataclass(frozen=True)
class Impedance:
    """Rendered spring-damper ``u = -k_p (x_b - x_f - l0) - k_d (v_b - v_f)``.

    Parameters
    ----------
    k_p : float
        Dimensionless stiffness ``K_p / k_g`` (>= 0).
    k_d : float
        Dimensionless damping ``K_d / sqrt(m_t k_g)`` (>= 0).
    l0 : float or None
        Rest length of the rendered spring; None means the robot's rest length
        (its leg length at impact, ``s / 2`` in the paper).
    """

    k_p: float
    k_d: float
    l0: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_p", check_number("k_p", self.k_p))
        object.__setattr__(self, "k_d", check_number("k_d", self.k_d))
        object.__setattr__(self, "l0", check_optional("l0", self.l0))

    def rest_length(self, robot: Robot) -> float:
        """The spring's rest length on this robot (within its stroke).

        Parameters
        ----------
        robot : Robot
            The robot (its stroke bounds ``l0``).

        Raises
        ------
        ParameterError
            If an explicit rest length lies outside the robot's stroke.
        """
        if self.l0 is None:
            return robot.rest_length
        if self.l0 > robot.s:
            raise ParameterError("l0", f"the impedance rest length must lie within the stroke "
                                       f"[0, s = {robot.s:g}], got {self.l0:g}")
        return self.l0

    def gain_vector(self, robot: Robot) -> np.ndarray:
        """``u = K . [x_b, v_b, x_f, v_f, 1]``.

        Parameters
        ----------
        robot : Robot
            The robot (its rest length when ``l0`` is None).
        """
        return impedance_gains(self.k_p, self.k_d, self.rest_length(robot))

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The same feedback in every ground mode (see :meth:`Rigid.kernel_arrays`).

        Parameters
        ----------
        mats : dict
            The mode data of :func:`~softlanding.model.dynamics.mode_matrices`.
        robot : Robot
            The robot.
        """
        Kf = np.empty((3, 5))
        Kf[:] = self.gain_vector(robot)
        return Kf, EMPTY, EMPTY

    def describe(self) -> str:
        """One line for tables and titles."""
        return f"impedance k_p={self.k_p:g}, k_d={self.k_d:g}"

    def to_si(self, units: Units) -> dict[str, Any]:
        """``K_p`` [N/m], ``K_d`` [N s/m], ``rest_length`` [m] (None: the robot's).

        Parameters
        ----------
        units : Units
            The scale of the gains (stiffness and damping units).
        """
        return {"K_p": self.k_p * units.stiffness, "K_d": self.k_d * units.damping,
                "rest_length": None if self.l0 is None else self.l0 * units.length}

    @classmethod
    def from_si(cls, K_p: float, K_d: float, units: Units,
                rest_length: float | None = None) -> Impedance:
        """From a leg stiffness [N/m], damping [N s/m] and rest length [m] (or None)."""
        return cls(check("K_p", K_p) / units.stiffness, check("K_d", K_d) / units.damping,
                   None if rest_length is None
                   else check("rest_length", rest_length) / units.length)

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "impedance", "k_p", "k_d", "l0"}``."""
        return {"kind": "impedance", "k_p": self.k_p, "k_d": self.k_d, "l0": self.l0}


@dataclass(frozen=True)
class ForceSchedule:
    """Open-loop piecewise-constant force: ``u = values[i]`` on ``[times[i-1], times[i])``.

    Parameters
    ----------
    times : sequence of float
        Switching instants, strictly increasing and > 0.
    values : sequence of float
        One more entry than ``times``; the last value is held forever.
    """

    times: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        t = tuple(float(v) for v in np.ravel(check("times", self.times)))
        u = tuple(float(v) for v in np.ravel(check("values", self.values)))
        if len(u) != len(t) + 1:
            raise ParameterError("values", f"needs exactly one more entry than times "
                                           f"({len(t)} times, {len(u)} values)")
        if any(b <= a for a, b in zip((0.0,) + t, t, strict=False)):
            raise ParameterError("times", "must be strictly increasing and > 0")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", u)

    @classmethod
    def from_arcs(cls, durations, values) -> ForceSchedule:
        """Schedule from arc durations (> 0) and the force on each arc (and after).

        Parameters
        ----------
        durations : sequence of float
            Length of each arc but the last (held forever).
        values : sequence of float
            Force on each arc; one more than ``durations``.
        """
        d = np.ravel(check("durations", durations))
        return cls(tuple(np.cumsum(d)), tuple(values))

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No feedback; the schedule's times and values.

        Parameters
        ----------
        mats, robot
            The mode data (unused) and the robot, whose force limit bounds the values.

        Raises
        ------
        ParameterError
            If a value exceeds the robot's force limit.
        """
        v = np.asarray(self.values, float)
        if robot.u_max is not None and np.abs(v).max() > robot.u_max * (1 + 1e-6):
            raise ParameterError("values", f"a scheduled force ({np.abs(v).max():g}) exceeds "
                                           f"the robot's force limit u_max = {robot.u_max:g}")
        return np.zeros((3, 5)), np.asarray(self.times, float), v

    def describe(self) -> str:
        """One line for tables and titles (how many switches)."""
        return f"open-loop schedule with {len(self.times)} switches"

    def to_si(self, units: Units) -> dict[str, Any]:
        """``times_s`` [s] and ``forces_N`` [N].

        Parameters
        ----------
        units : Units
            The scale of the times [s] and of the forces [N].
        """
        return {"times_s": [t * units.time for t in self.times],
                "forces_N": [u * units.force for u in self.values]}

    @classmethod
    def from_si(cls, times_s, forces_N, units: Units) -> ForceSchedule:
        """From switching instants [s] and forces [N]."""
        return cls(tuple(np.asarray(times_s, float) / units.time),
                   tuple(np.asarray(forces_N, float) / units.force))

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "schedule", "times", "values"}``."""
        return {"kind": "schedule", "times": list(self.times), "values": list(self.values)}


@dataclass(frozen=True)
class FeedbackSchedule:
    """Open-loop schedule of affine laws: ``u = gains[i] . [x_b, v_b, x_f, v_f, 1]`` on
    ``[times[i-1], times[i])``, the last held forever.

    A constant force ``u`` is the row ``[0, 0, 0, 0, u]`` (:class:`ForceSchedule` is the
    all-constant case); a state-feedback row replays an optimal control's boundary arc
    (e.g. the force that holds the leg at a stroke limit). Exact in the simulator (every
    piece is affine). The laws are not saturated: they are what the optimiser found within
    its bounds.

    Parameters
    ----------
    times : sequence of float
        Switching instants, strictly increasing and > 0.
    gains : sequence of sequence of float
        One row of 5 per piece (one more row than ``times``).
    """

    times: tuple[float, ...]
    gains: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        t = tuple(float(v) for v in np.ravel(check("times", self.times)))
        g = check("gains", self.gains, FINITE)  # (ragged rows: "must be a number")
        if np.ndim(g) != 2 or g.shape != (len(t) + 1, 5):
            raise ParameterError("gains", f"needs {len(t) + 1} rows of 5 (one more than "
                                          f"times), got shape {np.shape(g)}")
        if any(b <= a for a, b in zip((0.0,) + t, t, strict=False)):
            raise ParameterError("times", "must be strictly increasing and > 0")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "gains", tuple(tuple(float(x) for x in row) for row in g))

    @classmethod
    def from_arcs(cls, durations, gains) -> FeedbackSchedule:
        """Schedule from arc durations (> 0, as for :meth:`ForceSchedule.from_arcs`) and
        the law on each arc and after (``gains``: rows of 5, one more than ``durations``)."""
        d = np.ravel(check("durations", durations))
        return cls(tuple(np.cumsum(d)), tuple(tuple(r) for r in gains))

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """No feedback gains of the impedance kind; the schedule's times and rows.

        Parameters
        ----------
        mats : dict
            Unused.
        robot : Robot
            Unused (the laws are not saturated).
        """
        return np.zeros((3, 5)), np.asarray(self.times, float), np.asarray(self.gains, float)

    def describe(self) -> str:
        """One line for tables and titles."""
        n = sum(any(row[:4]) for row in self.gains)
        return f"open-loop schedule with {len(self.times)} switches ({n} feedback pieces)"

    def to_si(self, units: Units) -> dict[str, Any]:
        """``times_s`` [s] and ``gains_SI`` (rows in N/m, N s/m, N/m, N s/m, N).

        Parameters
        ----------
        units : Units
            The scale of the times and of the gains' rows.
        """
        scale = np.array([units.force / units.length, units.force / units.velocity,
                          units.force / units.length, units.force / units.velocity,
                          units.force])
        return {"times_s": [t * units.time for t in self.times],
                "gains_SI": (np.asarray(self.gains) * scale).tolist()}

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "feedback schedule", "times", "gains"}``."""
        return {"kind": "feedback schedule", "times": list(self.times),
                "gains": [list(r) for r in self.gains]}


Controller = Rigid | Impedance | ForceSchedule | FeedbackSchedule
"""Any of the controllers."""

__all__ = ["Controller", "FeedbackSchedule", "ForceSchedule", "Impedance", "Rigid",
           "impedance_gains", "rigid_lock_gains"]
