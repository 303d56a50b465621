"""The worked example of a new variant (docs/examples/fastest_arrest.py): one module on the
shared pipeline, checked against independent computations."""

import importlib.util
import sys
from pathlib import Path

import pytest

from softlanding import PAPER_ROBOT, Impact, solve_two_phase

EXAMPLE = Path(__file__).resolve().parents[3] / "docs" / "examples" / "fastest_arrest.py"


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("fastest_arrest", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["fastest_arrest"] = mod  # dataclasses look their module up there
    spec.loader.exec_module(mod)
    yield mod
    del sys.modules["fastest_arrest"]


def test_the_variant_is_one_short_module():
    code = [ln for ln in EXAMPLE.read_text().splitlines() if ln.strip()]
    assert len(code) < 130


@pytest.mark.slow
def test_fastest_arrest_is_verified_and_agrees_with_a_finer_transcription(example):
    """The refined optimum is verified (exact replay), spends its whole depth budget, rests
    sooner than the minimum-depth landing and sooner with a larger budget; a transcription
    three times finer (another discretisation, no exact arcs) converges to its rest time."""
    from ocp import MultipleShooting

    best = solve_two_phase(-3.0)
    budgets = [best.depth + 0.1, best.depth + 0.5]
    results = [example.solve_fastest_arrest(-3.0, d) for d in budgets]
    for r, d in zip(results, budgets, strict=True):
        assert r.unverified_reasons() == []
        assert r.depth == pytest.approx(d, abs=1e-9)
        assert r.replay_difference < 1e-9
        assert r.T < best.T
    assert results[1].T < results[0].T
    coarse = example.fastest_arrest_transcription()
    fine = MultipleShooting(coarse.problem, nodes=[300, 120], integrator="rk4", substeps=4,
                            expand=True)
    params = {**example.FastestArrestVariant(PAPER_ROBOT, Impact(-3.0), budgets[0])
              .parameters()}
    sol = fine.solve(params, guess=results[0].transcribed)
    T_fine = float(sol.phases[-1].T)
    T_coarse = float(results[0].transcribed.phases[-1].T)
    assert abs(T_fine - results[0].T) < abs(T_coarse - results[0].T) + 1e-9
    assert abs(T_fine - results[0].T) < 1e-4
