"""The hybrid modules' public callables have numpydoc docstrings matching their signatures
(the check of tests/test_docstrings.py, applied to the modules of the hybrid studies)."""

import pytest
from test_docstrings import _public, test_public_callable_has_numpydoc_matching_its_signature

MODULES = [
    "softlanding.stance_phases", "softlanding.hybrid_problem", "softlanding.hybrid",
    "softlanding.leg_extension_problem", "softlanding.leg_extension",
    "softlanding.hopping_problem", "softlanding.hopping", "softlanding.actuator_work",
    "softlanding.phase_schedule", "softlanding.phase_solve", "softlanding.figures_hybrid",
    "softlanding.cli_hybrid", "softlanding.reproduce_hybrid", "softlanding.summary_hybrid",
    "ocp.phase_refinement", "ocp.phase_pmp",
]
CASES = sorted({qual: obj for m in MODULES for qual, obj in _public(m)}.items())


@pytest.mark.parametrize("qual,obj", CASES, ids=[q for q, _ in CASES])
def test_documented(qual, obj):
    test_public_callable_has_numpydoc_matching_its_signature(qual, obj)


def test_the_check_finds_them():
    assert len(CASES) > 40
