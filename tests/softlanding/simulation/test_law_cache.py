"""The compiled ground-law cache: bounded (least recently used evicted), shown and cleared by
``softlanding cache``; without a C compiler a law runs in Python with the same numbers."""

import ctypes
import json
import os

import pytest

import softlanding.simulation.groundcode as groundcode
from softlanding.model import Impedance
from softlanding.model.ground import DragGround
from softlanding.model.robot import PAPER_ROBOT
from softlanding.simulation.simulator import simulate


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SOFTLANDING_CACHE", str(tmp_path))
    return groundcode.law_cache_dir()


def _fake_laws(folder, n, size=1000):
    paths = []
    for i in range(n):
        p = folder / f"law_{i:020d}.so"
        p.write_bytes(b"x" * size)
        os.utime(p, (1e9 + i, 1e9 + i))  # law 0 the least recently used
        paths.append(p)
    return paths


def test_the_cache_keeps_its_bounds_evicting_the_least_recently_used(cache, monkeypatch):
    monkeypatch.setattr(groundcode, "LAW_CACHE_MAX_FILES", 4)
    laws = _fake_laws(cache, 6)
    os.utime(laws[0])  # used just now: kept
    assert groundcode.prune_law_cache(keep=laws[5]) == 2
    assert sorted(p.name for p in cache.iterdir()) == sorted(
        p.name for p in (laws[0], laws[3], laws[4], laws[5]))
    monkeypatch.setattr(groundcode, "LAW_CACHE_MAX_BYTES", 2500)  # now size binds: 2 laws
    assert groundcode.prune_law_cache(keep=laws[5]) == 2
    assert sorted(p.name for p in cache.iterdir()) == sorted([laws[0].name, laws[5].name])


def test_cache_command_shows_and_clears(cache, cli):
    _fake_laws(cache, 3, size=2**19)
    code, out, _ = cli("cache")
    assert code == 0 and f"{cache}" in out and "3 (at most 256)" in out and "1.50 MiB" in out
    code, out, _ = cli("cache", "--clear", "--json")
    d = json.loads(out)
    assert code == 0 and (d["removed"], d["laws"], d["bytes"]) == (3, 0, 0)
    assert list(cache.iterdir()) == []


def test_without_a_c_compiler_a_law_runs_in_python_with_the_same_numbers(cache, monkeypatch,
                                                                         capsys):
    ground = DragGround(0.41, 1.7)
    compiled, p_compiled = groundcode.compile_law(ground)
    monkeypatch.setenv("CC", str(cache / "no-such-cc"))
    python, p_python = groundcode.compile_law(DragGround(0.41, 1.7000000000000002))
    assert not isinstance(python, ctypes.CDLL) and "runs in Python" in capsys.readouterr().err
    law = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double,
                           ctypes.POINTER(ctypes.c_double))
    for d, v in ((0.0, -1.0), (0.3, -2.5), (2.0, -0.1)):
        a, b = (ctypes.c_double * 5)(), (ctypes.c_double * 5)()
        law(p_compiled)(d, v, a), law(p_python)(d, v, b)
        assert list(a) == pytest.approx(list(b), rel=1e-12, abs=1e-14)
    # the kernel takes the Python law: the same landing (a ground not compiled in this run)
    on_python = simulate(PAPER_ROBOT, -3, Impedance(0.2, 0.2), DragGround(0.41, 1.71))
    monkeypatch.delenv("CC")
    compiled_run = simulate(PAPER_ROBOT, -3, Impedance(0.2, 0.2),
                            DragGround(0.41, 1.7100000000000002))
    assert on_python.status == "rest proven"
    assert on_python.depth == pytest.approx(compiled_run.depth, rel=1e-12)
