"""numba does not notice an edit of a function inlined from another file: the kernel's cache is
dropped whenever any kernel source changes (softlanding.simulation.kernel.freshness)."""

from softlanding.simulation.kernel.freshness import STAMP, drop_stale_cache, sources_digest


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
