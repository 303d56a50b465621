"""Optimal control problems from the literature with published optimal values.

Shared by ``tests/test_ocp_suite.py`` and ``benchmarks/ocp_suite.py``. Each
entry of :data:`PROBLEMS` builds the problem with the public ``ocp`` API and
says where the published value comes from, how it is reached (collocation
with mesh refinement, or multiple shooting) and to what tolerance it can be
compared (the published value's own digits and discretisation bound it).

``problems.py`` holds the first twelve; each later problem has a module of its
own (builder, independent reference, ``PROBLEM``), listed in :data:`MODULES`.
"""

import importlib

from .problems import PROBLEMS as FIRST
from .problems import SuiteProblem

MODULES = (
    "fuller", "rayleigh_min_time", "oscillator_min_time", "thrusters_2d",
    "modal_double_integrator", "cannonball", "pendulum_swingup", "min_fuel_double_integrator",
)
"""Modules of later problems (each defines ``PROBLEM``, or ``PROBLEMS_HERE`` for several)."""


def _later() -> list[SuiteProblem]:
    out = []
    for name in MODULES:
        mod = importlib.import_module(f".{name}", __name__)
        out += getattr(mod, "PROBLEMS_HERE", [mod.PROBLEM])
    return out


PROBLEMS: list[SuiteProblem] = [*FIRST, *_later()]

__all__ = ["MODULES", "PROBLEMS", "SuiteProblem"]
