"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .hopping import HopCycle as HopCycle, ThrustImpedance as ThrustImpedance, best_impedance_hop as best_impedance_hop, impedance_hop as impedance_hop, rigid_hop as rigid_hop, solve_hop as solve_hop, sweep_hops as sweep_hops
from .hopping_problem import build_hop_problem as build_hop_problem, hop_transcription as hop_transcription
from .landing import BangBangLanding as BangBangLanding, build_landing_problem as build_landing_problem, landing_transcription as landing_transcription, solve_landing as solve_landing, sweep_landing as sweep_landing
from .leg_extension import LegExtension as LegExtension, LegExtensionLanding as LegExtensionLanding, solve_leg_extension as solve_leg_extension, sweep_leg_extension as sweep_leg_extension
from .leg_extension_problem import build_leg_extension_problem as build_leg_extension_problem, leg_extension_transcription as leg_extension_transcription
from .limits import MIN_HOP_SPEED as MIN_HOP_SPEED, force_limit as force_limit, hop_input as hop_input
from .min_peak_force import MinPeakForceLanding as MinPeakForceLanding, solve_min_peak_force as solve_min_peak_force
from .phase_solve import phase_guess as phase_guess
from .pipeline import PhasedVariant as PhasedVariant, continuation as continuation, landing_parameters as landing_parameters, solve_phased as solve_phased
from .result import PhasedLanding as PhasedLanding
from .two_phase import TwoPhase as TwoPhase, TwoPhaseLanding as TwoPhaseLanding, TwoStepCheck as TwoStepCheck, solve_two_phase as solve_two_phase, sweep_two_phase as sweep_two_phase, two_step_check as two_step_check
from .two_phase_problem import build_two_phase_problem as build_two_phase_problem, two_phase_transcription as two_phase_transcription
from .variants import Option as Option, Variant as Variant, VariantError as VariantError, VariantResult as VariantResult, all_variants as all_variants, find_variant as find_variant, survey_variants as survey_variants, sweep_variant as sweep_variant
