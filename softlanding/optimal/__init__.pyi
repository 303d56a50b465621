"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .hopping import (
    HopCycle, ThrustImpedance, best_impedance_hop, impedance_hop, rigid_hop, solve_hop, sweep_hops
)
from .hopping_problem import build_hop_problem, hop_transcription
from .landing import (
    BangBangLanding, build_landing_problem, landing_transcription, solve_landing, sweep_landing
)
from .leg_extension import (
    LegExtension, LegExtensionLanding, solve_leg_extension, sweep_leg_extension
)
from .leg_extension_problem import build_leg_extension_problem, leg_extension_transcription
from .pipeline import PhasedVariant, continuation, force_limit, landing_parameters, solve_phased
from .result import PhasedLanding
from .two_phase import (
    TwoPhase, TwoPhaseLanding, TwoStepCheck, solve_two_phase, sweep_two_phase, two_step_check
)
from .two_phase_problem import build_two_phase_problem, two_phase_transcription
