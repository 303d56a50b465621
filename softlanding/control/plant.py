"""A stepping plant: the exact simulator advanced sample by sample from its own state.

A controller closed around the simulator needs it stopped at every sample and continued
under the next control. Each step is one exact simulation from the state the last one ended
in (matrix exponentials on affine grounds, the integrator's tolerance otherwise), so the
stepped run equals the uninterrupted one to rounding. The crater's memory is the foot's
depth while it digs: the plant refuses a state whose foot has risen above its crater's
bottom (a flight), which the landings it serves never reach.
"""

from __future__ import annotations

import numpy as np

from softlanding.errors import ParameterError, RestNotProvenError, check
from softlanding.model.controllers import Controller
from softlanding.model.dynamics import VF, robot_rhs
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import Impact, Robot
from softlanding.simulation.simulator import LandingResult, simulate

#: Exact points of each step on which its stroke range is taken.
STROKE_POINTS = 65


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
        """Apply ``control`` (its time from this step's start) for ``duration``; the new state.

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
        res = simulate(self.robot, self.impact, control, self.ground, x0=self.x, t_max=h)
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
            The control from now on (its time from now).
        """
        res = simulate(self.robot, self.impact, control, self.ground, x0=self.x)
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


__all__ = ["SteppingPlant"]
