"""Drop numba's on-disk cache of the kernel when any kernel source changed.

numba invalidates a cached function when its own file changes, not when a function it
inlines from another file does (``forceinline`` across ``linalg``, ``events``, ``landing``,
...): after an upgrade that edits one kernel module, the others would load machine code
compiled from the old source, a silent wrong number. So the kernel's sources are hashed
together, the hash is stamped beside the cache, and the cache is dropped when they differ
(the next landing recompiles, about 10 s). This module is plain Python: it runs before any
compiled module is loaded.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

STAMP = "kernel-sources.sha256"
"""The stamp's file name in the cache folder."""


def sources_digest(folder: Path) -> str:
    """The SHA-256 of the folder's ``*.py`` files (names and contents, in name order).

    Parameters
    ----------
    folder : Path
        The kernel's package folder.
    """
    h = hashlib.sha256()
    for f in sorted(folder.glob("*.py")):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def drop_stale_cache(folder: Path = Path(__file__).parent) -> bool:
    """Remove the folder's numba cache files if its sources changed since they were stamped;
    whether anything was dropped.

    Only numba's default cache location (``__pycache__`` beside the sources) is handled;
    with ``NUMBA_CACHE_DIR`` set, that folder is the user's to manage. A read-only install
    is left as it is (numba then does not cache there either).

    Parameters
    ----------
    folder : Path
        The kernel's package folder.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return False
    cache = folder / "__pycache__"
    stamp = cache / STAMP
    digest = sources_digest(folder)
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


__all__ = ["STAMP", "drop_stale_cache", "sources_digest"]
