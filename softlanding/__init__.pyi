"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .errors import InfeasibleLandingError, ParameterError, SoftlandingError
from .model import (
    AddedMassGround, Controller, CustomGround, DragGround, FeedbackSchedule, ForceSchedule, Ground,
    Impact, Impedance, LINEAR_GROUND, LinearGround, PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT,
    PhysicalParams, Rigid, Robot, Scenario, Units, paper_rig
)
from .optimal import (
    BangBangLanding, HopCycle, LegExtensionLanding, TwoPhaseLanding, solve_hop, solve_landing,
    solve_leg_extension, solve_two_phase, sweep_hops, sweep_landing, sweep_leg_extension,
    sweep_two_phase
)
from .report import reproduce
from .simulation import BatchResult, EnergyLedger, LandingResult, simulate, simulate_batch
from .studies import ImpedanceOptimum, optimize_impedance
