"""numba does not notice an edit of a function inlined from another file: the kernel's cache is
dropped whenever any kernel source changes; a demo on a cache without the landing loop runs
the kernel as Python (softlanding.simulation.kernel_cache)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from softlanding.simulation.kernel_cache import (
    LOOP_INDEX,
    STAMP,
    drop_stale_cache,
    interpret_unless_cached,
    loop_cached,
    sources_digest,
)


def _cache(folder):
    c = folder / "__pycache__"
    c.mkdir(exist_ok=True)
    for name in ("landing.f-1.py311.nbi", "landing.f-1.py311.1.nbc"):
        (c / name).write_bytes(b"compiled")
    return c


def test_the_cache_is_dropped_when_a_source_changes_and_kept_otherwise(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    (tmp_path / "linalg.py").write_text("x = 1\n")
    (tmp_path / "landing.py").write_text("y = 2\n")
    cache = _cache(tmp_path)
    assert drop_stale_cache(tmp_path)  # no stamp yet: caches of unknown sources go
    assert sorted(p.name for p in cache.iterdir()) == [STAMP]
    assert (cache / STAMP).read_text() == sources_digest(tmp_path)
    _cache(tmp_path)
    assert not drop_stale_cache(tmp_path) and len(list(cache.iterdir())) == 3  # unchanged
    (tmp_path / "linalg.py").write_text("x = 3\n")  # an inlined helper edited
    assert drop_stale_cache(tmp_path)
    assert [p.name for p in cache.iterdir()] == [STAMP]


def test_a_user_cache_dir_is_left_alone(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    (tmp_path / "linalg.py").write_text("x = 1\n")
    cache = _cache(tmp_path)
    assert not drop_stale_cache(tmp_path) and len(list(cache.iterdir())) == 2


def test_the_loop_is_cached_only_with_its_index_and_fresh_sources(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    (tmp_path / "landing.py").write_text("y = 2\n")
    assert not loop_cached(tmp_path)  # nothing compiled
    _cache(tmp_path)
    drop_stale_cache(tmp_path)  # stamped, other functions only
    index = tmp_path / "__pycache__" / LOOP_INDEX.replace("*", "42.py311")
    index.write_bytes(b"index")
    assert loop_cached(tmp_path)
    (tmp_path / "landing.py").write_text("y = 3\n")  # edited: the cache will be dropped
    assert not loop_cached(tmp_path)


def test_a_user_cache_dir_holds_the_loop_anywhere_below_it(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "user"))
    assert not loop_cached(tmp_path)
    deep = tmp_path / "user" / "some" / "path"
    deep.mkdir(parents=True)
    (deep / LOOP_INDEX.replace("*", "7.py311")).write_bytes(b"index")
    assert loop_cached(tmp_path)


def test_the_kernel_already_imported_stays_compiled():
    import numba

    from softlanding.simulation import kernel  # noqa: F401  (imported, compiled)

    assert not interpret_unless_cached() and not numba.config.DISABLE_JIT


def test_an_empty_cache_runs_the_kernel_as_python(tmp_path):
    code = ("import numba\n"
            "from softlanding.simulation.kernel_cache import interpret_unless_cached\n"
            "print(interpret_unless_cached(), numba.config.DISABLE_JIT)\n"
            "from softlanding.simulation.kernel.landing import simulate_one\n"
            "print(type(simulate_one).__name__)")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                       env={"NUMBA_CACHE_DIR": str(tmp_path), "PATH": ""}, timeout=120)
    assert p.stdout.split() == ["True", "True", "function"], p.stderr


def test_an_edit_in_an_inlined_folder_drops_the_cache(tmp_path, monkeypatch):
    """softlanding.control's compiled functions inline the kernel's: its cache goes when a
    kernel source changes, though none of its own did."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    control, kernel = tmp_path / "control", tmp_path / "kernel"
    control.mkdir()
    kernel.mkdir()
    (control / "bangbang.py").write_text("x = 1\n")
    (kernel / "linalg.py").write_text("y = 1\n")
    cache = _cache(control)
    assert drop_stale_cache(control, (kernel,))
    _cache(control)
    assert not drop_stale_cache(control, (kernel,)) and len(list(cache.iterdir())) == 3
    (kernel / "linalg.py").write_text("y = 2\n")
    assert drop_stale_cache(control, (kernel,))
    assert [p.name for p in cache.iterdir()] == [STAMP]


def test_the_controller_package_is_stamped_with_the_kernel_and_the_model(monkeypatch):
    import softlanding.control as control
    from softlanding.simulation.kernel_cache import KERNEL

    folder = Path(control.__file__).parent
    stamp = folder / "__pycache__" / STAMP
    if os.environ.get("NUMBA_CACHE_DIR") or not stamp.exists():
        pytest.skip("a user's numba cache folder or a read-only install: nothing stamped")
    assert stamp.read_text() == sources_digest(folder, KERNEL, KERNEL.parents[1] / "model")
