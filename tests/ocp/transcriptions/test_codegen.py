"""Compiled NLP functions (``codegen=True``): the same solution, a disk cache, refusals."""

from __future__ import annotations

import pytest

from ocp import Collocation, MultipleShooting, ProblemDefinitionError
from ocp.transcriptions import codegen
from tests.oracles.ocp_suite.problems import bryson_denham


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("OCP_CODEGEN_DIR", str(tmp_path))
    return tmp_path


@pytest.mark.slow
def test_compiled_nlp_solves_as_the_uncompiled_one_and_is_cached(cache):
    if not codegen.has_compiler():
        pytest.skip("no C compiler on this machine")
    plain = MultipleShooting(bryson_denham(), nodes=6, substeps=1, expand=True).solve()
    tr = MultipleShooting(bryson_denham(), nodes=6, substeps=1, codegen=True)
    sol = tr.solve()
    assert sol.success and sol.iterations == plain.iterations
    assert sol.objective == pytest.approx(plain.objective, rel=1e-12)
    assert abs(sol.w - plain.w).max() < 1e-10
    # a re-solve runs the same compiled functions: no expanded solver is built for it
    assert tr.solve().expanded is False and len(tr._solvers) == 1
    libs = sorted(cache.glob("nlp-*.so"))
    assert len(libs) == 1 and not list(cache.glob(".gen-*"))  # no temporary left
    stamp = libs[0].stat().st_mtime_ns
    again = MultipleShooting(bryson_denham(), nodes=6, substeps=1, codegen=True)
    assert again.solve().objective == pytest.approx(sol.objective, rel=1e-12)
    assert sorted(cache.glob("nlp-*.so")) == libs and libs[0].stat().st_mtime_ns == stamp


def test_codegen_refusals(cache, monkeypatch):
    with pytest.raises(ProblemDefinitionError, match="True or False"):
        MultipleShooting(bryson_denham(), nodes=4, codegen="yes")
    with pytest.raises(ProblemDefinitionError, match="rk4"):
        MultipleShooting(bryson_denham(), nodes=4, integrator="cvodes", codegen=True)
    with pytest.raises(ProblemDefinitionError, match="refine"):
        Collocation(bryson_denham(), intervals=4, codegen=True).refine()
    monkeypatch.setenv("CC", str(cache / "no-such-compiler"))
    with pytest.raises(ProblemDefinitionError, match="C compiler"):
        MultipleShooting(bryson_denham(), nodes=4, substeps=1, codegen=True).solve()
    assert not list(cache.iterdir())  # nothing left behind by the failure
