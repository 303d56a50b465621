"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .actuator_work import Work as Work, result_work as result_work, segment_work as segment_work, state_at as state_at
from .groundcode import compile_law as compile_law, hold_stiffness as hold_stiffness, kernel_law as kernel_law, law_expressions as law_expressions, needs_integration as needs_integration
from .simulator import BATCH_FIELDS as BATCH_FIELDS, BatchResult as BatchResult, EnergyLedger as EnergyLedger, LandingResult as LandingResult, MODE_NAMES as MODE_NAMES, STATUS_NAMES as STATUS_NAMES, simulate as simulate, simulate_batch as simulate_batch, stroke as stroke
