"""Optimal control problems from the literature with published optimal values.

Shared by ``tests/test_ocp_suite.py`` and ``benchmarks/ocp_suite.py``. Each
entry of :data:`PROBLEMS` builds the problem with the public ``ocp`` API and
says where the published value comes from, how it is reached (collocation
with mesh refinement, or multiple shooting) and to what tolerance it can be
compared (the published value's own digits and discretisation bound it).
"""

from .problems import PROBLEMS, SuiteProblem

__all__ = ["PROBLEMS", "SuiteProblem"]
