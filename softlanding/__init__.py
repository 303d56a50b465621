"""softlanding: optimal control of a two-mass legged robot landing on yielding terrain.

Implements and extends Lynch, Lynch & Umbanhowar, "The Soft Landing Problem:
Minimizing Energy Loss by a Legged Robot Impacting Yielding Terrain".
"""

from .errors import ParameterError
from .scaling import DimensionlessParams, PhysicalParams, paper_rig
from .simulate import (
    BatchResult,
    EnergyLedger,
    ForceSchedule,
    Impedance,
    LandingResult,
    Rigid,
    Trajectory,
    simulate,
    simulate_batch,
)

__version__ = "0.1.0"

__all__ = [
    "BatchResult",
    "DimensionlessParams",
    "EnergyLedger",
    "ForceSchedule",
    "Impedance",
    "LandingResult",
    "ParameterError",
    "PhysicalParams",
    "Rigid",
    "Trajectory",
    "paper_rig",
    "simulate",
    "simulate_batch",
]
