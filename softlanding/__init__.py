"""softlanding: optimal control of a two-mass legged robot landing on yielding terrain.

Implements and extends Lynch, Lynch & Umbanhowar, "The Soft Landing Problem:
Minimizing Energy Loss by a Legged Robot Impacting Yielding Terrain".

The value objects (:class:`Robot`, :class:`Impact`, the controllers
:class:`Rigid`, :class:`Impedance`, :class:`ForceSchedule`, and the ground
models) are validated once and passed to every study::

    from softlanding import PAPER_ROBOT, Impact, Impedance, simulate
    res = simulate(PAPER_ROBOT.without_force_limit(), Impact(-1), Impedance(0.2, 0.18))
"""

from .controllers import Controller, ForceSchedule, Impedance, Rigid
from .errors import InfeasibleLandingError, ParameterError, SoftlandingError
from .ground import LINEAR_GROUND, Ground, LinearGround
from .model import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Impact, Robot, Units
from .scaling import PhysicalParams, Scenario, paper_rig
from .simulate import (
    BatchResult,
    EnergyLedger,
    LandingResult,
    simulate,
    simulate_batch,
)

__version__ = "0.2.0"

__all__ = [
    "BatchResult",
    "Controller",
    "EnergyLedger",
    "ForceSchedule",
    "Ground",
    "Impact",
    "Impedance",
    "InfeasibleLandingError",
    "LINEAR_GROUND",
    "LandingResult",
    "LinearGround",
    "PAPER_IMPEDANCE_ROBOT",
    "PAPER_ROBOT",
    "ParameterError",
    "PhysicalParams",
    "Rigid",
    "Robot",
    "Scenario",
    "SoftlandingError",
    "Units",
    "paper_rig",
    "simulate",
    "simulate_batch",
]
