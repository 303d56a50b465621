"""The landing OCP from a measured mid-landing state, on a ground whose stiffness factor and
drag number are parameters.

A controller that re-plans while the foot yields (:mod:`softlanding.control.mpc`) needs the
paper's landing problem started anywhere, for a ground it only estimates: here the start and
the ground law ``f = K d + c_d v_f^2`` are NLP parameters, so one problem (and one solved
structure of :func:`ocp.refine_structure`) serves every sample and every estimate. The
constraints, dynamics and objective are the landing's own
(:func:`softlanding.optimal.landing.landing_stance`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, ClassVar

import numpy as np

from ocp import OptimalControlProblem
from softlanding.model.dynamics import STATE_NAMES
from softlanding.model.ground import DragGround, Ground, LinearGround
from softlanding.model.robot import Robot
from softlanding.optimal.landing import landing_stance
from softlanding.optimal.limits import force_limit

STATE_PARAMETERS = ("r_m", "s", "u_max", "stiffness", "c_d", "x_b0", "v_b0", "x_f0", "v_f0")
"""The parameters of :func:`state_landing_problem`, in order."""


class ParametricGround:
    """``f = K d + c_d v_f^2`` with ``K`` and ``c_d`` symbols (a ground for the OCP only).

    Parameters
    ----------
    stiffness, c_d : casadi.SX
        The parameters.
    """

    name: ClassVar[str] = "parametric"

    def __init__(self, stiffness: Any, c_d: Any) -> None:
        self.stiffness, self.c_d = stiffness, c_d

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``K d + c_d v_f^2``.

        Parameters
        ----------
        depth, v_f : expression
            Foot depth and velocity.
        """
        return self.stiffness * depth + self.c_d * v_f ** 2

    def added_mass(self, depth: Any) -> Any:
        """No grains move with the foot.

        Parameters
        ----------
        depth : expression
            Unused.
        """
        return 0.0


@lru_cache(maxsize=1)
def state_landing_problem() -> OptimalControlProblem:
    """The landing OCP started at the parameters ``x_b0, v_b0, x_f0, v_f0`` (a yielding foot:
    ``v_f0 <= 0``, the crater's bottom at the foot) on the ground ``K d + c_d v_f^2``."""
    p = OptimalControlProblem("landing_from_state")
    for n in STATE_NAMES:
        p.state(n)
    r_m, s, u_max, k, c_d, *x0 = (p.parameter(n) for n in STATE_PARAMETERS)
    landing_stance(p, r_m, s, u_max, ParametricGround(k, c_d))
    for i, n in enumerate(STATE_NAMES):
        p.initial_constraint(p.x[i] - x0[i], 0.0, name=f"{n}(0) measured")
    return p


def ground_numbers(ground: Ground) -> tuple[float, float]:
    """``(K, c_d)`` of a linear or drag ground (what :func:`state_landing_problem` takes).

    Parameters
    ----------
    ground : LinearGround or DragGround
        The ground.

    Raises
    ------
    TypeError
        Another ground model (its law is not ``K d + c_d v^2``).
    """
    if isinstance(ground, LinearGround):
        return ground.stiffness, 0.0
    if isinstance(ground, DragGround):
        return ground.stiffness, ground.c_d
    raise TypeError(f"the state-started landing takes a linear or drag ground, not "
                    f"{ground.name}")


def state_parameters(robot: Robot, ground: Ground, x: np.ndarray) -> dict[str, float]:
    """The values of :data:`STATE_PARAMETERS` for a robot, a (model) ground and a state.

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit).
    ground : LinearGround or DragGround
        The ground the plan assumes.
    x : array of 4
        The measured state.
    """
    k, c_d = ground_numbers(ground)
    return dict(zip(STATE_PARAMETERS, (robot.r_m, robot.s, force_limit(robot), k, c_d,
                                       *map(float, x)), strict=True))


__all__ = ["STATE_PARAMETERS", "ParametricGround", "ground_numbers", "state_landing_problem",
           "state_parameters"]
