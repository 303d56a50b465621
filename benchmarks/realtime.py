"""Run a benchmark as a robot runs its controller: a real-time scheduling class, one CPU,
memory locked (issue 33: every sample within the rig's period, worst case, in wall time).

On a shared machine the largest wall time of a sample is the scheduler's, not the code's:
a sample that takes 0.1 ms of CPU can be preempted for milliseconds by any other process.
A robot's control loop runs under ``SCHED_FIFO`` (no time slicing against ordinary
processes), pinned to a core, with its memory locked (no page fault mid-sample); this does
the same for a benchmark's process, so that its wall-time maximum measures the controller.
It needs the privilege to do so (root, or ``CAP_SYS_NICE`` and ``CAP_IPC_LOCK``); without
it :func:`enter_realtime` refuses (:class:`RealtimeUnavailable`, one line) rather than
measuring something else.
The kernel's real-time throttling (``/proc/sys/kernel/sched_rt_runtime_us``, by default
0.95 s of every 1 s period) leaves the other processes some time on that core: a benchmark
that computes without pause (unlike a control loop, idle between samples) is stopped for
50 ms once a second, wherever it is -- measured once inside a 0.17 ms CPU sample (51 ms
wall). :func:`rest` before each landing sleeps longer than that, so a period that holds a
rest never reaches the limit and the samples of the landing's first 0.9 s are never
throttled (its compiled samples come first; a fallback's re-plans after them).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import os
import time

#: ``SCHED_FIFO`` priority (1-99): above ordinary processes, below the kernel's own threads.
PRIORITY = 50
_MCL_CURRENT, _MCL_FUTURE = 1, 2


#: Seconds :func:`rest` sleeps: more than the 0.05 s per period the throttling keeps back.
REST_S = 0.06


def rest() -> None:
    """Sleep :data:`REST_S` (call before each landing of a real-time benchmark)."""
    time.sleep(REST_S)


class RealtimeUnavailable(RuntimeError):
    """The platform or the privileges do not allow real-time scheduling."""


def enter_realtime(priority: int = PRIORITY, cpu: int | None = None) -> str:
    """Put this process under ``SCHED_FIFO``, on one CPU, with its memory locked.

    Garbage collection is also frozen (the objects alive now are never scanned again) so
    that a collection of the set-up's objects cannot fall into a sample.

    Parameters
    ----------
    priority : int
        ``SCHED_FIFO`` priority, 1 to 99.
    cpu : int, optional
        The CPU to run on (default: the last one the process may use).

    Returns
    -------
    str
        What was done, for the benchmark's header.

    Raises
    ------
    RealtimeUnavailable
        With a one-line message, if the platform or the privileges do not allow it.
    """
    if not hasattr(os, "sched_setscheduler"):
        raise RealtimeUnavailable("this platform has no SCHED_FIFO (Linux only)")
    allowed = sorted(os.sched_getaffinity(0))
    cpu = allowed[-1] if cpu is None else cpu
    if cpu not in allowed:
        raise RealtimeUnavailable(f"CPU {cpu} is not one this process may use ({allowed})")
    try:
        os.sched_setaffinity(0, {cpu})
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError:
        raise RealtimeUnavailable("real-time scheduling not permitted (needs root or "
                                  "CAP_SYS_NICE)") from None
    libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    locked = libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) == 0
    gc.collect()
    gc.freeze()
    runtime = _rt_runtime()
    return (f"real-time: SCHED_FIFO priority {priority} on CPU {cpu}, memory "
            f"{'locked' if locked else 'NOT locked (' + os.strerror(ctypes.get_errno()) + ')'}"
            f", garbage collection frozen{runtime}")


def _rt_runtime() -> str:
    try:
        with open("/proc/sys/kernel/sched_rt_runtime_us") as f:
            us = int(f.read())
    except (OSError, ValueError):
        return ""
    return f"; real-time throttling {us / 1e6:g} s per second" if us >= 0 else \
        "; no real-time throttling"


__all__ = ["PRIORITY", "REST_S", "RealtimeUnavailable", "enter_realtime", "rest"]
