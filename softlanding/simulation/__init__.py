"""Exact event-driven simulation of a landing: :func:`simulate` and :func:`simulate_batch`
(:mod:`.simulator`), the ground laws compiled for the kernel (:mod:`.groundcode`), the
actuator's work (:mod:`.actuator_work`) and the compiled kernel
(:mod:`softlanding.simulation.kernel`).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
