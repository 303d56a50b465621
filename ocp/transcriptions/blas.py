"""CasADi's bundled OpenBLAS, which MUMPS (Ipopt's linear solver) calls, on one thread.

Its worker threads wait for work by spinning: on a transcription's small banded KKT
systems they add CPU time and no speed. Measured (2 cores, CPU / wall): the alp rider's
refinement 5.26 / 4.27 s with OpenBLAS's default threads, 4.14 / 4.14 s on one; a
brachistochrone solve 0.093 / 0.058 s, on one 0.058 / 0.058 s.

The library is loaded on one thread (no worker thread starts) before :mod:`ocp` builds its
first Ipopt solver, unless ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` is set in the
environment: that choice is kept. :func:`set_blas_threads` changes the count at any time,
and a count set by it is kept too. The setting is process-wide (CasADi's solvers outside
:mod:`ocp` share the library); numpy's own BLAS is not touched.
"""

from __future__ import annotations

import ctypes
import os
import re
import threading
from functools import cache
from pathlib import Path

ENVIRONMENT = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
"""Variables that, when set, leave the thread count to OpenBLAS (and to the user)."""

_LOCK = threading.Lock()
_CHOSEN = threading.Event()  # set_blas_threads was called: the default no longer applies


def library_files() -> list[Path]:
    """CasADi's bundled OpenBLAS files (empty if this CasADi build has none)."""
    import casadi

    return sorted(Path(casadi.__file__).parent.glob("libcasadi-tp-openblas*"))


@cache
def casadi_openblas() -> ctypes.CDLL | None:
    """CasADi's bundled OpenBLAS (loaded if it was not), or None if this CasADi build has
    none (another platform's wheel, a build against the system's BLAS).

    The wheel holds copies of one library under several names (``.so``, ``.so.0``, ...):
    the one loaded already, else the one named as the solver plugins ask for it
    (``.so.<major>``), is taken -- setting another copy would change nothing. A first load
    with no count in the environment is made with ``OPENBLAS_NUM_THREADS=1`` set for its
    duration (then restored), so that OpenBLAS starts no worker thread: starting them
    costs about 0.1 s CPU of spinning on another core.
    """
    files = library_files()
    loaded = _mapped_files()
    files.sort(key=lambda f: (str(f.resolve()) not in loaded,
                              re.fullmatch(r".*\.so\.\d+", f.name) is None))
    with _LOCK:
        quiet = not any(os.environ.get(v) for v in ENVIRONMENT)
        before = os.environ.get("OPENBLAS_NUM_THREADS")  # None, or set but empty
        if quiet:
            os.environ["OPENBLAS_NUM_THREADS"] = "1"
        try:
            for lib in files:
                try:
                    blas = ctypes.CDLL(str(lib))
                    blas.openblas_set_num_threads, blas.openblas_get_num_threads  # noqa: B018
                except (OSError, AttributeError):
                    continue
                blas.openblas_get_num_threads.restype = ctypes.c_int
                return blas
            return None
        finally:
            if quiet and before is None:
                os.environ.pop("OPENBLAS_NUM_THREADS", None)
            elif quiet:
                os.environ["OPENBLAS_NUM_THREADS"] = before  # type: ignore[assignment]


def _mapped_files() -> set[str]:
    """Files mapped into this process (Linux; empty elsewhere)."""
    try:
        text = Path("/proc/self/maps").read_text()
    except OSError:
        return set()
    return {line.split(None, 5)[5] for line in text.splitlines() if line.count(" ") >= 5
            and "/" in line}


def _apply(n: int) -> bool:
    blas = casadi_openblas()
    if blas is None:
        return False
    blas.openblas_set_num_threads(ctypes.c_int(n))
    return True


def available_cpus() -> int:
    """The CPUs this process may use (its affinity mask where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def set_blas_threads(n: int) -> bool:
    """Let CasADi's OpenBLAS (under Ipopt's MUMPS) use ``n`` threads, from now on (later
    solves keep this count).

    A count above the CPUs this process may use (:func:`available_cpus`) is capped at that
    number, the rule OpenBLAS applies to ``OPENBLAS_NUM_THREADS`` (more threads than CPUs
    only spin); OpenBLAS may cap it further at the limit it was built with.
    :func:`blas_threads` reads the count set.

    Parameters
    ----------
    n : int
        Threads (>= 1).

    Returns
    -------
    bool
        False if this CasADi has no bundled OpenBLAS (nothing was changed).

    Raises
    ------
    ValueError
        ``n`` is not a positive integer.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"set_blas_threads: n must be a positive integer, got {n!r}")
    _CHOSEN.set()
    return _apply(min(n, available_cpus()))  # also keeps n within OpenBLAS's C int


def blas_threads() -> int | None:
    """The threads CasADi's OpenBLAS may use (None if this CasADi has none).

    Returns
    -------
    int or None
    """
    blas = casadi_openblas()
    return None if blas is None else int(blas.openblas_get_num_threads())


@cache
def default_blas_threads() -> None:
    """One thread for CasADi's OpenBLAS, once per process, unless the environment or
    :func:`set_blas_threads` chose a count. Called before an Ipopt solver is built."""
    if not _CHOSEN.is_set() and not any(os.environ.get(v) for v in ENVIRONMENT):
        _apply(1)


__all__ = ["ENVIRONMENT", "available_cpus", "blas_threads", "casadi_openblas",
           "default_blas_threads", "library_files", "set_blas_threads"]
