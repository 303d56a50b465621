"""Type stub of the front door: the names it loads on first use (lazy_loader reads it)."""

from .actuator_work import Work, result_work, segment_work, state_at
from .groundcode import compile_law, hold_is_depth, kernel_law, law_expressions, needs_integration
from .simulator import (
    BATCH_FIELDS, BatchResult, EnergyLedger, LandingResult, MODE_NAMES, STATUS_NAMES, simulate,
    simulate_batch, stroke
)
