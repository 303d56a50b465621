"""Exact event-driven simulation of a landing: :func:`simulate` and :func:`simulate_batch`
(:mod:`.simulator`), the ground laws compiled for the kernel (:mod:`.groundcode`), the
actuator's work (:mod:`.actuator_work`) and the compiled kernel
(:mod:`softlanding.simulation.kernel`).

Every name below is importable from here (``from softlanding.simulation import ...``),
loaded on first use.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submod_attrs={
        "actuator_work": [
            "Work", "result_work", "segment_work", "state_at"
        ],
        "groundcode": [
            "compile_law", "hold_is_depth", "kernel_law", "law_expressions", "needs_integration"
        ],
        "simulator": [
            "BATCH_FIELDS", "BatchResult", "EnergyLedger", "LandingResult", "MODE_NAMES",
            "STATUS_NAMES", "simulate", "simulate_batch", "stroke"
        ],
    },
)
