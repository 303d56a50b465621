"""What the exported C's step-time benchmarks share (``bench_export_step``,
``bench_export_filter``, ``bench_export_filtered``): the C clocks around a timed call, the
controller compiled with a benchmark's timed functions, the contenders' names, and the
statistics printed."""

from __future__ import annotations

import ctypes
import tempfile
from pathlib import Path

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

int sl_timed_step(double *P, double *M, const double *x, double a_f, double u, double h,
                  int estimate, double *ns)
{
    /* the CPU clock (a system call) outside the wall clock's window (vDSO, cheap) */
    double c0 = now_ns(CLOCK_PROCESS_CPUTIME_ID), w0 = now_ns(CLOCK_MONOTONIC);
    int st = sl_control_step(P, M, x, a_f, u, h, estimate);
    double w1 = now_ns(CLOCK_MONOTONIC), c1 = now_ns(CLOCK_PROCESS_CPUTIME_ID);
    ns[0] = w1 - w0;
    ns[1] = c1 - c0;
    return st;
}
"""
"""The C clocks (``now_ns``: monotonic wall and process CPU, nanoseconds),
``sl_timer_overhead`` (two readings of each, back to back: the clocks' own cost) and
``sl_timed_step`` (the plain ``sl_control_step`` timed), before a benchmark's own timed
functions."""

CONTENDERS = ("numba", "C from Python", "C in C")
"""The contenders: the numba function called from Python, the C through ctypes, the C timed
inside C."""


def timed_library(timer_c: str, noise_std: float | None = None) -> ctypes.CDLL:
    """The paper's robot's exported controller (for ``K = 1``, ``c_d = 0``; with the foot
    filter for ``noise_std``) and a benchmark's timed functions ``timer_c``, compiled into
    one shared library (exits with a message when there is no C compiler).

    Parameters
    ----------
    timer_c : str
        C source of the timed functions (:data:`CLOCKS_C` first).
    noise_std : float, optional
        The sensors' noise the exported filter is for (None: no filter).
    """
    from softlanding.control import bangbang as bb
    from softlanding.control.export_c.binding import compile_shared, find_compiler
    from softlanding.control.export_c.writer import controller_sources, write_controller
    from softlanding.model.robot import PAPER_ROBOT

    if find_compiler() is None:
        raise SystemExit("no C compiler (cc, gcc or $CC): nothing to measure")
    r = PAPER_ROBOT
    numbers = bb.robot_numbers(r.r_m, r.s, r.u_max, 1.0, 0.0)
    with tempfile.TemporaryDirectory() as tmp:  # (a loaded library outlives its file)
        folder = Path(tmp)
        write_controller(folder, controller_sources(numbers, "the paper's robot")
                         if noise_std is None else
                         controller_sources(numbers, "the paper's robot", noise_std))
        (folder / "timer.c").write_text(timer_c)
        return ctypes.CDLL(str(compile_shared(folder, folder / "lib.so",
                                              (str(folder / "timer.c"),))))


def stats(v: np.ndarray) -> list[float]:
    """Median, 99th percentile and maximum of ``v``.

    Parameters
    ----------
    v : ndarray
        Times.
    """
    return [float(np.median(v)), float(np.percentile(v, 99)), float(v.max())]
