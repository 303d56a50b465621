"""softlanding: optimal control of a two-mass legged robot landing on yielding terrain.

Implements and extends Lynch, Lynch & Umbanhowar, "The Soft Landing Problem:
Minimizing Energy Loss by a Legged Robot Impacting Yielding Terrain".

The value objects (:class:`Robot`, :class:`Impact`, the controllers
:class:`Rigid`, :class:`Impedance`, :class:`ForceSchedule`, and the ground
models) are validated once and passed to every study::

    from softlanding import PAPER_ROBOT, Impact, Impedance, simulate
    res = simulate(PAPER_ROBOT.without_force_limit(), Impact(-1), Impedance(0.2, 0.18))

The names below are imported on first use, so a light command (``softlanding
--help``, a scale conversion) does not load CasADi or compile anything.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from softlanding._version import __version__ as __version__

_WHERE = {
    "Controller": "model.controllers", "FeedbackSchedule": "model.controllers",
    "ForceSchedule": "model.controllers", "Impedance": "model.controllers",
    "Rigid": "model.controllers",
    "InfeasibleLandingError": "errors", "ParameterError": "errors",
    "SoftlandingError": "errors",
    "LINEAR_GROUND": "model.ground", "Ground": "model.ground", "LinearGround": "model.ground",
    "AddedMassGround": "model.ground", "CustomGround": "model.ground", "DragGround": "model.ground",
    "PAPER_IMPEDANCE_ROBOT": "model.robot", "PAPER_ROBOT": "model.robot", "Impact": "model.robot",
    "Robot": "model.robot", "Units": "model.robot",
    "PhysicalParams": "model.scaling", "Scenario": "model.scaling", "paper_rig": "model.scaling",
    "BatchResult": "simulation.simulator", "EnergyLedger": "simulation.simulator",
    "LandingResult": "simulation.simulator",
    "simulate": "simulation.simulator", "simulate_batch": "simulation.simulator",
}

__all__ = [
    "AddedMassGround",
    "BatchResult",
    "Controller",
    "CustomGround",
    "DragGround",
    "EnergyLedger",
    "FeedbackSchedule",
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


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'softlanding' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{where}", __name__), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, eagerly
    from softlanding.errors import InfeasibleLandingError, ParameterError, SoftlandingError
    from softlanding.model.controllers import (
        Controller,
        FeedbackSchedule,
        ForceSchedule,
        Impedance,
        Rigid,
    )
    from softlanding.model.ground import (
        LINEAR_GROUND,
        AddedMassGround,
        CustomGround,
        DragGround,
        Ground,
        LinearGround,
    )
    from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Impact, Robot, Units
    from softlanding.model.scaling import PhysicalParams, Scenario, paper_rig
    from softlanding.simulation.simulator import (
        BatchResult,
        EnergyLedger,
        LandingResult,
        simulate,
        simulate_batch,
    )
