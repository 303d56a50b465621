"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .errors import InfeasibleLandingError as InfeasibleLandingError, ParameterError as ParameterError, SoftlandingError as SoftlandingError
from .model import AddedMassGround as AddedMassGround, Controller as Controller, CustomGround as CustomGround, DragGround as DragGround, FeedbackSchedule as FeedbackSchedule, ForceSchedule as ForceSchedule, Ground as Ground, Impact as Impact, Impedance as Impedance, LINEAR_GROUND as LINEAR_GROUND, LinearGround as LinearGround, PAPER_IMPEDANCE_ROBOT as PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT as PAPER_ROBOT, PhysicalParams as PhysicalParams, Rigid as Rigid, Robot as Robot, Scenario as Scenario, Units as Units, paper_rig as paper_rig
from .optimal import BangBangLanding as BangBangLanding, HopCycle as HopCycle, LegExtensionLanding as LegExtensionLanding, TwoPhaseLanding as TwoPhaseLanding, solve_hop as solve_hop, solve_landing as solve_landing, solve_leg_extension as solve_leg_extension, solve_two_phase as solve_two_phase, sweep_hops as sweep_hops, sweep_landing as sweep_landing, sweep_leg_extension as sweep_leg_extension, sweep_two_phase as sweep_two_phase
from .report import reproduce as reproduce
from .simulation import BatchResult as BatchResult, EnergyLedger as EnergyLedger, LandingResult as LandingResult, simulate as simulate, simulate_batch as simulate_batch
from .studies import ImpedanceOptimum as ImpedanceOptimum, optimize_impedance as optimize_impedance
