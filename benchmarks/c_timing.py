"""What the exported C's step-time benchmarks share (``bench_export_step``,
``bench_export_filter``): the C clocks around a timed call, the contenders' names, and the
statistics printed."""

from __future__ import annotations

import numpy as np

CLOCKS_C = """
#define _POSIX_C_SOURCE 199309L
#include <string.h>
#include <time.h>
#include "softlanding_controller.h"

static double now_ns(clockid_t c)
{
    struct timespec t;
    clock_gettime(c, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

void sl_timer_overhead(double *ns)
{
    double c0 = now_ns(CLOCK_PROCESS_CPUTIME_ID), w0 = now_ns(CLOCK_MONOTONIC);
    double w1 = now_ns(CLOCK_MONOTONIC), c1 = now_ns(CLOCK_PROCESS_CPUTIME_ID);
    ns[0] = w1 - w0;
    ns[1] = c1 - c0;
}
"""
"""The C clocks (``now_ns``: monotonic wall and process CPU, nanoseconds) and
``sl_timer_overhead`` (two readings of each, back to back: the clocks' own cost), before a
benchmark's timed functions."""

CONTENDERS = ("numba", "C from Python", "C in C")
"""The contenders: the numba function called from Python, the C through ctypes, the C timed
inside C."""


def stats(v: np.ndarray) -> list[float]:
    """Median, 99th percentile and maximum of ``v``.

    Parameters
    ----------
    v : ndarray
        Times.
    """
    return [float(np.median(v)), float(np.percentile(v, 99)), float(v.max())]
