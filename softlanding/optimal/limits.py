"""What a landing problem's inputs must satisfy, checked before any solver loads.

Kept apart from the solvers (no CasADi, no numba) so that the command line can refuse
bad input in a fraction of a second.
"""

from __future__ import annotations

from typing import Any

from softlanding.errors import InfeasibleLandingError, ParameterError, expect
from softlanding.model.ground import Ground
from softlanding.model.robot import Impact, Robot

#: The slowest touchdown of a hop: its apex ``v0^2/2`` must stay far above rounding (at
#: ``|v0| < 1e-154`` it underflows to zero and every energy ratio divides by it).
MIN_HOP_SPEED = 1e-3


def force_limit(robot: Robot) -> float:
    """The force limit of a landing problem (raises when none can work).

    Parameters
    ----------
    robot : Robot
        The robot.

    Raises
    ------
    ParameterError
        The robot has no force limit (the OCP needs one).
    InfeasibleLandingError
        The limit does not exceed the body's weight: the body can never be arrested.
    """
    expect("robot", robot, Robot)
    if robot.u_max is None:
        raise ParameterError("u_max", "the optimal control problem needs a force limit")
    if robot.u_max <= robot.body_mass:
        raise InfeasibleLandingError(
            f"u_max = {robot.u_max:g} does not exceed the body weight r_m/(1+r_m) = "
            f"{robot.body_mass:.4g}: the arrest force u_b <= u_max can never hold")
    return robot.u_max



def landing_input(robot: Robot, ground: Any) -> float:
    """The force limit of a landing on ``ground``, both checked (see :func:`force_limit`).

    Parameters
    ----------
    robot : Robot
        The robot.
    ground : Ground
        The ground model.

    Raises
    ------
    ParameterError
        ``ground`` is not a ground model, or the robot has no force limit.
    """
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    return force_limit(robot)


def hop_input(robot: Robot, impact: Impact | float, eta: float) -> tuple[Robot, Impact]:
    """The checked inputs of a hop cycle.

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit; its leg at the apex is ``s/2``).
    impact : Impact or float
        Touchdown velocity, at most ``-MIN_HOP_SPEED``.
    eta : float
        Regenerative efficiency in ``[0, 1)``.

    Raises
    ------
    ParameterError
        A value out of its range.
    InfeasibleLandingError
        The force limit cannot arrest the body.
    """
    force_limit(robot)
    impact = Impact.of(impact)
    if not impact.v0 <= -MIN_HOP_SPEED:
        raise ParameterError("v0", f"a hop needs a flight: v0 <= -{MIN_HOP_SPEED:g} (apex "
                                   f"v0^2/2 resolvable in double precision), got "
                                   f"{impact.v0:g}")
    if isinstance(eta, bool) or not isinstance(eta, (int, float)):
        raise ParameterError("eta", f"must be a number, got {eta!r}")
    if not 0.0 <= eta < 1.0:
        raise ParameterError("eta", f"the regenerative efficiency must lie in [0, 1), got "
                                    f"{eta!r}")
    if robot.l0 is not None and robot.l0 != robot.s / 2:
        raise ParameterError("l0", "the hop's apex posture is the paper's leg length s/2")
    return robot, impact


__all__ = ["MIN_HOP_SPEED", "force_limit", "hop_input", "landing_input"]
