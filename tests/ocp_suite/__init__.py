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
    "modal_double_integrator", "cannonball", "pendulum_swingup", "min_fuel_l1",
)
"""Modules of later problems (each defines ``PROBLEM``)."""


def _later() -> list[SuiteProblem]:
    out = []
    for name in MODULES:
        try:
            mod = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as err:  # a module still to come, not a broken one
            if err.name != f"{__name__}.{name}":
                raise
            continue
        out.append(mod.PROBLEM)
    return out


PROBLEMS: list[SuiteProblem] = [*FIRST, *_later()]

__all__ = ["MODULES", "PROBLEMS", "SuiteProblem"]
