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
# 6 nodes: the bound of x is crossed between the nodes, and both solves say so (the check is
# tested in test_between_points.py; here the two solves' equality is)
@pytest.mark.filterwarnings("ignore::ocp.definition.errors.PathViolationWarning")
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


def _tiny_solver():
    import casadi as ca

    x = ca.SX.sym("x")
    return ca.nlpsol("tiny", "ipopt", {"x": x, "f": (x - 1) ** 2},
                     {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}})


def test_a_damaged_cached_library_is_compiled_again_before_it_is_loaded(cache):
    """Issue 47, defect 1: a truncated cached library killed every later run with a bus
    error, an emptied one gave a CasADi traceback. Its size and hash are recorded beside it
    and checked before loading; a library that does not match (or has no record) is
    compiled again."""
    import casadi as ca

    if not codegen.has_compiler():
        pytest.skip("no C compiler on this machine")
    solver = _tiny_solver()
    lib = codegen.compiled_library(solver)
    good = lib.read_bytes()
    assert codegen.intact(lib)
    for damage in (good[: len(good) // 2], b"", good[:-1] + bytes([good[-1] ^ 1])):
        lib.write_bytes(damage)
        assert not codegen.intact(lib)
        assert codegen.compiled_library(solver) == lib
        assert codegen.intact(lib) and lib.stat().st_size == len(good)
    codegen.record_path(lib).unlink()  # a library without its record (an older cache)
    assert codegen.compiled_library(solver) == lib and codegen.intact(lib)
    loaded = ca.nlpsol("tiny", "ipopt", str(lib), {"print_time": False,
                                                  "ipopt": {"print_level": 0, "sb": "yes"}})
    assert float(loaded(x0=5.0)["x"]) == pytest.approx(1.0, abs=1e-8)
    assert sorted(p.name for p in cache.iterdir()) == sorted([lib.name, lib.stem + ".json"])


def test_an_unusable_cache_folder_or_compiler_is_one_clear_error(tmp_path, monkeypatch):
    """Issue 47, defect 8: $OCP_CODEGEN_DIR naming a file or a path through a file, and
    CC='"', raised FileExistsError, NotADirectoryError or a bare ValueError."""
    a_file = tmp_path / "a-file"
    a_file.write_text("not a folder")
    solver = _tiny_solver()
    for bad in (a_file, a_file / "below"):
        monkeypatch.setenv("OCP_CODEGEN_DIR", str(bad))
        with pytest.raises(ProblemDefinitionError, match="OCP_CODEGEN_DIR .* cannot hold"):
            codegen.compiled_library(solver)
    monkeypatch.setenv("OCP_CODEGEN_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", '"')
    with pytest.raises(ProblemDefinitionError, match=r"\$CC=.* is not a command"):
        codegen.compiled_library(solver)
    assert a_file.read_text() == "not a folder" and not (tmp_path / "cache").exists()
