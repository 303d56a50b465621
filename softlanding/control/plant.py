"""A stepping plant: the exact simulator advanced sample by sample from its own state.

A controller closed around the simulator needs it stopped at every sample and continued
under the next control. Each step is one exact simulation from the state the last one ended
in (matrix exponentials on affine grounds, the integrator's tolerance otherwise), so the
stepped run equals the uninterrupted one to rounding. The crater's memory is the foot's
depth while it digs: the plant refuses a state whose foot has risen above its crater's
bottom (a flight), which the landings it serves never reach.

The plant is the actuator too: the force it applies saturates at the robot's force limit,
whatever the command (:func:`~softlanding.control.commands.saturated`: a constant force
clipped; an affine law, which a schedule's rows may be, saturated exactly by the
simulator's saturation events where it would leave the limit, :class:`AffineLaw`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from softlanding.control.commands import saturated
from softlanding.errors import ParameterError, RestNotProvenError, check
from softlanding.model.controllers import Controller, FeedbackSchedule, ForceSchedule
from softlanding.model.dynamics import VF, robot_rhs
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import Impact, Robot
from softlanding.simulation.simulator import LandingResult, simulate

#: Exact points of each step on which its stroke range is taken.
STROKE_POINTS = 65

#: The relative excess over the force limit a simulation's peak force may show before the
#: plant applies the command saturated (the peak of an affine law is taken on the
#: simulation's nodes and events: rounding).
PEAK_TOL = 1e-9


@dataclass(frozen=True)
class AffineLaw:
    """A force affine in the state, ``u = row . [x_b, v_b, x_f, v_f, 1]``, saturated at the
    robot's force limit by the simulator (its feedback's saturation events), as an
    impedance is.

    Parameters
    ----------
    row : tuple of 5 floats
        The law.
    """

    row: tuple[float, ...]

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The law as the feedback of every ground mode, no schedule (the simulator's
        arrays; ``mats`` and ``robot`` unused: the simulator saturates at the robot's limit).

        Parameters
        ----------
        mats, robot
            The simulator's arguments.
        """
        Kf = np.empty((3, 5))
        Kf[:] = np.asarray(self.row, float)
        return Kf, np.zeros(0), np.zeros(0)

    def describe(self) -> str:
        """One line for tables and titles."""
        return "affine force law, saturated"

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": "affine law", "row"}``."""
        return {"kind": "affine law", "row": list(self.row)}


def pieces(control: Any, duration: float) -> list[tuple[Any, float]]:
    """A schedule's pieces over ``[0, duration)`` (the last one to ``duration``, which may be
    ``inf``), each a constant force or an :class:`AffineLaw`.

    Parameters
    ----------
    control : ForceSchedule or FeedbackSchedule
        The schedule.
    duration : float
        How long.
    """
    rows = [(0.0, 0.0, 0.0, 0.0, float(v)) for v in control.values] \
        if isinstance(control, ForceSchedule) else list(control.gains)
    out, t0 = [], 0.0
    for t1, row in zip((*control.times, np.inf), rows, strict=True):
        t1 = min(float(t1), duration)
        if t1 > t0:
            law = AffineLaw(tuple(row)) if any(row[:4]) else ForceSchedule((), (row[4],))
            out.append((law, t1 - t0))
            t0 = t1
        if t0 >= duration:
            break
    return out


def _stroke_range(t: np.ndarray, s: np.ndarray) -> tuple[float, float]:
    """``min, max`` of the stroke ``s`` sampled at ``t``, an interior extremum refined by the
    parabola through it and its neighbours (exact for a quadratic stroke)."""
    lo, hi = float(np.min(s)), float(np.max(s))
    for i in (int(np.argmin(s)), int(np.argmax(s))):
        if 0 < i < len(s) - 1:
            a, b, c = s[i - 1], s[i], s[i + 1]
            den = a - 2 * b + c
            if den != 0:
                v = b - (c - a) ** 2 / (8 * den)
                lo, hi = min(lo, v), max(hi, v)
    return lo, hi


class SteppingPlant:
    """The exact simulator of one landing, advanced by :meth:`step`.

    Parameters
    ----------
    robot : Robot
        The robot (its force limit saturates every control).
    impact : Impact or float
        The impact (the start of the landing).
    ground : Ground
        The true ground.

    Attributes
    ----------
    x : ndarray of 4
        The current state.
    t : float
        The time since impact.
    crater : float
        The crater's depth (the deepest the foot has been).
    history : list of (float, LandingResult)
        Every step's start time and simulation (whose stroke range covers the future under
        the step's control, beyond the step).
    stroke_ranges : list of (float, float)
        The stroke's range within each step (on :data:`STROKE_POINTS` exact points of the
        step, an interior extremum refined by the parabola through its neighbours).
    """

    def __init__(self, robot: Robot, impact: Impact | float,
                 ground: Ground = LINEAR_GROUND) -> None:
        self.robot, self.impact, self.ground = robot, Impact.of(impact), ground
        self.x = self.impact.initial_state(robot)
        self.t = 0.0
        self.crater = 0.0
        self.history: list[tuple[float, LandingResult]] = []
        self.stroke_ranges: list[tuple[float, float]] = []

    def step(self, control: Controller, duration: float) -> np.ndarray:
        """Apply ``control`` (its time from this step's start) for ``duration``, saturated at
        the force limit; the new state. A schedule whose affine row leaves the limit is
        applied piece by piece, each piece's law saturated by the simulator.

        Parameters
        ----------
        control : controller
            Any controller :func:`~softlanding.simulation.simulator.simulate` takes.
        duration : float
            The sample period (> 0).
        """
        h = check("duration", duration, (lambda v: v > 0, "must be > 0"))
        if self.x[2] > -self.crater + 1e-12 * max(1.0, self.crater) and self.crater > 0:
            raise ParameterError("x", "the foot has left its crater's bottom: the stepping "
                                      "plant holds the crater only while the foot digs")
        control = saturated(control, self.robot.u_max)
        res = simulate(self.robot, self.impact, control, self.ground, x0=self.x, t_max=h)
        if self._over(control, res):
            for law, dt in pieces(control, h):
                self._advance(law, dt, simulate(self.robot, self.impact, law, self.ground,
                                                x0=self.x, t_max=dt))
            return self.x
        return self._advance(control, h, res)

    def _over(self, control: Controller, res: LandingResult) -> bool:
        """A schedule's force left the limit in its simulation (an affine row's: constants
        are clipped)."""
        u_max = self.robot.u_max
        return u_max is not None and isinstance(control, FeedbackSchedule) and \
            res.u_peak > u_max * (1 + PEAK_TOL)

    def _advance(self, control: Controller, h: float, res: LandingResult) -> np.ndarray:
        """The step's simulation ``res`` of ``control`` over ``h`` taken: the state, the
        time, the crater, the stroke's range and the history."""
        try:
            tr = res.trajectory(t_end=h, n=STROKE_POINTS)
        except RestNotProvenError:
            # the simulation proved the step's outcome before its end (the foot at rest,
            # the body leaving without bound): the step ends where its samples do
            tr = res.trajectory(n=STROKE_POINTS)
            h = float(tr.t[-1])
        end = tr.x[-1]
        self.stroke_ranges.append(_stroke_range(tr.t, tr.x[:, 0] - tr.x[:, 2]))
        self.history.append((self.t, res))
        self.x, self.t = np.array(end, float), self.t + h
        self.crater = max(self.crater, -self.x[2])
        return self.x

    def finish(self, control: Controller) -> LandingResult:
        """Run ``control`` from the current state until the landing ends (rest proven).

        Parameters
        ----------
        control : controller
            The control from now on (its time from now), saturated at the force limit as
            :meth:`step` saturates it.
        """
        control = saturated(control, self.robot.u_max)
        res = simulate(self.robot, self.impact, control, self.ground, x0=self.x)
        if self._over(control, res):
            *head, (law, _) = pieces(control, np.inf)
            for piece, dt in head:
                self._advance(piece, dt, simulate(self.robot, self.impact, piece, self.ground,
                                                  x0=self.x, t_max=dt))
            res = simulate(self.robot, self.impact, law, self.ground, x0=self.x)
        self.history.append((self.t, res))
        return res

    def foot_acceleration(self, u: float) -> float:
        """What an accelerometer on the yielding foot reads under force ``u`` now.

        Parameters
        ----------
        u : float
            The actuator force.
        """
        f = self.ground.yield_force(-self.x[2], self.x[3]) if self.x[3] < 0 else 0.0
        return float(robot_rhs(self.x, u, f, self.robot.r_m)[VF])


__all__ = ["PEAK_TOL", "AffineLaw", "SteppingPlant", "pieces"]
