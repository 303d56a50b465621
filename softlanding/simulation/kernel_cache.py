"""numba's on-disk cache of the kernel: dropped when any kernel source changed; whether it holds
the landing loop, and running the kernel as Python when it does not.

numba invalidates a cached function when its own file changes, not when a function it
inlines from another file does (``forceinline`` across ``linalg``, ``events``, ``landing``,
...): after an upgrade that edits one kernel module, the others would load machine code
compiled from the old source, a silent wrong number. So the kernel's sources are hashed
together, the hash is stamped beside the cache, and the cache is dropped when they differ
(the next landing recompiles, about 10 s). This module is plain Python and outside the
kernel's package: it runs before any compiled module is loaded.

A process that runs a few landings and ends (``softlanding demo``: about a hundred) spends
more CPU compiling the kernel on an empty cache (about 20 s) than running it as Python (about
3 s): :func:`interpret_unless_cached` decides before the kernel is imported. The kernel's
functions are plain Python (numba's ``DISABLE_JIT``); the demo's results are identical to the
last bit (``tests/softlanding/simulation/test_kernel_cache.py``).
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

STAMP = "kernel-sources.sha256"
"""The stamp's file name in the cache folder."""
KERNEL = Path(__file__).parent / "kernel"
"""The kernel's package folder."""
LOOP_INDEX = "landing.simulate_one-*.nbi"
"""numba's index file of the landing loop (every landing's entry point)."""


def sources_digest(folder: Path, *more: Path) -> str:
    """The SHA-256 of the folders' ``*.py`` files (names and contents, in name order).

    Parameters
    ----------
    folder, *more : Path
        The package folders whose sources the compiled code is made of.
    """
    h = hashlib.sha256()
    for d in (folder, *more):
        for f in sorted(d.glob("*.py")):
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def drop_stale_cache(folder: Path = KERNEL, inlined: tuple[Path, ...] = ()) -> bool:
    """Remove the folder's numba cache files if its sources (or the ones it inlines) changed
    since they were stamped; whether anything was dropped.

    Only numba's default cache location (``__pycache__`` beside the sources) is handled;
    with ``NUMBA_CACHE_DIR`` set, that folder is the user's to manage. A read-only install
    is left as it is (numba then does not cache there either).

    Parameters
    ----------
    folder : Path
        The package folder of the compiled functions (default: the kernel's).
    inlined : tuple of Path
        Other folders whose compiled functions it inlines (``softlanding.control`` inlines
        the kernel's and the model's).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    cache = folder / "__pycache__"
    stamp = cache / STAMP
    digest = sources_digest(folder, *inlined)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:  # no stamp yet: a fresh install, or caches from before the stamp
        pass
    dropped = False
    try:
        for f in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
            f.unlink(missing_ok=True)
            dropped = True
        cache.mkdir(exist_ok=True)
        tmp = cache / f"{STAMP}.{os.getpid()}.tmp"
        tmp.write_text(digest)
        os.replace(tmp, stamp)  # atomic: a concurrent reader sees the old or the new stamp
    except OSError:
        pass
    return dropped


def loop_cached(folder: Path = KERNEL) -> bool:
    """Whether numba's cache holds the landing loop compiled from the present sources.

    In numba's default location (``__pycache__`` beside the sources) the stamp must match the
    sources; under ``NUMBA_CACHE_DIR`` (the user's to manage) an index file is enough. An
    index compiled for another machine or signature reads as cached: the landing then
    compiles, slower but the same numbers. A read-only install (numba then caches in the
    user's folder) always reads as not cached: a demo there runs as Python (about 5 s).

    Parameters
    ----------
    folder : Path
        The kernel's package folder.
    """
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        return next(Path(user).rglob(LOOP_INDEX), None) is not None
    cache = folder / "__pycache__"
    try:
        fresh = (cache / STAMP).read_text() == sources_digest(folder)
    except OSError:
        return False
    return fresh and next(cache.glob(LOOP_INDEX), None) is not None


def interpret_unless_cached() -> bool:
    """Run the kernel as Python in this process unless its landing loop is cached; whether it
    will.

    For a process that runs a few landings and ends: it must be called before the kernel is
    imported (once imported, the kernel stays as it is and this returns False), and it turns
    numba's compilation off for every function decorated after it in the process.
    """
    if "softlanding.simulation.kernel" in sys.modules or loop_cached():
        return False
    from numba import config

    config.DISABLE_JIT = True  # type: ignore[attr-defined]
    return True


__all__ = ["KERNEL", "LOOP_INDEX", "STAMP", "drop_stale_cache", "interpret_unless_cached",
           "loop_cached", "sources_digest"]
