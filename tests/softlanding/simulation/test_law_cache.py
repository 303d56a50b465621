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


def test_a_damaged_cached_law_is_compiled_again(cache):
    """Issue 47 (the review of defect 1's kind): a law library emptied or overwritten in the
    cache failed to load (a truncated one would kill the process); its size and hash are
    recorded beside it, checked before loading, and a bad one is compiled again."""
    import hashlib

    from ocp.transcriptions.codegen import intact

    ground = DragGround(0.37, 1.3)
    key = hashlib.sha256(groundcode.law_source(ground).encode()).hexdigest()[:20]
    so = cache / f"law_{key}.so"
    so.write_bytes(b"\x7fELF" + b"\0" * 60)  # a library cut short (and no record)
    lib, address = groundcode.compile_law(ground)
    assert intact(so) and so.stat().st_size > 1000
    law = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double,
                           ctypes.POINTER(ctypes.c_double))(address)
    out = (ctypes.c_double * 5)()
    law(0.5, -2.0, out)
    assert out[0] == pytest.approx(1.3 * 0.5 + 0.37 * 4.0, rel=1e-14)  # f = K d + c_d v^2


def test_a_cache_folder_that_cannot_be_made_is_one_line(tmp_path, monkeypatch, cli):
    (tmp_path / "a-file").write_text("")
    monkeypatch.setenv("SOFTLANDING_CACHE", str(tmp_path / "a-file"))
    code, out, err = cli("simulate", "--v0", "-3", "--rigid", "--ground", "drag", "--cd",
                         "0.1", "--stiffness", "2.5")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "$SOFTLANDING_CACHE" in err and "cannot hold the compiled ground laws" in err
