"""Step time of the exported C foot filter (``sl_filter_step`` of ``softlanding
export-controller``) against the numba filter it was exported from
(``softlanding.control.foot_filter.filter_step``), interleaved.

Run:  python -m benchmarks.bench_export_filter [--steps 600] [--repeats 5]

The calls are those of noisy landings of the filtered controller
(``softlanding.control.export_c.filter_check``: the paper's robot, random grounds, impact
velocities, periods and sensor noise 1e-4 to 1e-2, and the fast draggy impact of its
probes), recorded once; each is then run by every contender from the same inputs,
alternating which goes first call by call. Timed:

- numba: ``filter_step`` called from Python, wall (``perf_counter_ns``) and CPU
  (``process_time_ns``) around the call, as ``mpc_landing`` calls it;
- C from Python: ``sl_filter_step`` through ctypes, timed the same way;
- C in C, per call: the call timed inside C (``clock_gettime``, monotonic and process CPU
  clocks; the clocks' own cost, printed, included);
- C in C, batch: all the recorded calls run back to back inside C (each from a copy of its
  recorded memory and measurement, the copies included), 200 times, the total divided by
  the calls: the step's cost without the clocks'; and its baseline, numba in numba,
  batch: the same loop compiled by numba around ``filter_step``, timed from Python around
  it, the two batches alternating.

The C is compiled with the README's flags (``-std=c99 -O2 -ffp-contract=off``). Printed:
median, 99th percentile and maximum (microseconds), the ratios C / numba, and whether the
outputs are identical.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import time

import numpy as np

from benchmarks.c_timing import CLOCKS_C, CONTENDERS, stats, timed_library

TIMER_C = CLOCKS_C + """
int sl_timed_filter(double *F, double *x, double g, double U1, double U2, double h,
                    double beta, double noise, double *ns)
{
    double c0 = now_ns(CLOCK_PROCESS_CPUTIME_ID), w0 = now_ns(CLOCK_MONOTONIC);
    int w = sl_filter_step(F, x, g, U1, U2, h, beta, noise);
    double w1 = now_ns(CLOCK_MONOTONIC), c1 = now_ns(CLOCK_PROCESS_CPUTIME_ID);
    ns[0] = w1 - w0;
    ns[1] = c1 - c0;
    return w;
}

/* the n calls (inputs in rows) run reps times; the total wall and CPU ns; a checksum */
double sl_filter_batch(const double *F0, const double *x0, const double *in, int n, int reps,
                       double *ns)
{
    double F[SL_NF], x[4], sum = 0.0;
    double c0 = now_ns(CLOCK_PROCESS_CPUTIME_ID), w0 = now_ns(CLOCK_MONOTONIC);
    int r, i;
    for (r = 0; r < reps; r++) {
        for (i = 0; i < n; i++) {
            const double *a = in + 6 * i;
            memcpy(F, F0 + SL_NF * i, sizeof F);
            memcpy(x, x0 + 4 * i, sizeof x);
            sl_filter_step(F, x, a[0], a[1], a[2], a[3], a[4], a[5]);
            sum += x[3];
        }
    }
    ns[0] = now_ns(CLOCK_MONOTONIC) - w0;
    ns[1] = now_ns(CLOCK_PROCESS_CPUTIME_ID) - c0;
    return sum;
}
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=600, help="filter steps (default 600)")
    ap.add_argument("--repeats", type=int, default=5, help="passes over them (default 5)")
    a = ap.parse_args()
    from softlanding.control import foot_filter as ff
    from softlanding.control.export_c.filter_check import filtered_calls
    from softlanding.model.robot import PAPER_ROBOT

    lib = timed_library(TIMER_C, 1e-3)
    r = PAPER_ROBOT
    recorded = filtered_calls(r, a.steps)
    calls, landings = recorded.filter, recorded.landings
    vp, d = ctypes.c_void_p, ctypes.c_double
    lib.sl_timed_filter.argtypes = [vp, vp, d, d, d, d, d, d, vp]
    lib.sl_timed_filter.restype = ctypes.c_int
    lib.sl_timer_overhead.argtypes = [vp]
    lib.sl_filter_batch.argtypes = [vp, vp, vp, ctypes.c_int, ctypes.c_int, vp]
    lib.sl_filter_batch.restype = d
    ns = np.zeros(2)
    wall: dict[str, list[float]] = {c: [] for c in CONTENDERS}
    cpu: dict[str, list[float]] = {c: [] for c in CONTENDERS}
    differ = 0

    def numba(k):
        F, x = k.F.copy(), k.x.copy()
        c0, w0 = time.process_time_ns(), time.perf_counter_ns()
        ff.filter_step(F, x, k.g, k.U1, k.U2, k.h, k.beta, k.noise)
        w1, c1 = time.perf_counter_ns(), time.process_time_ns()
        wall["numba"].append(w1 - w0)
        cpu["numba"].append(c1 - c0)
        return F, x

    def c_step(k):
        F, x = k.F.copy(), k.x.copy()
        pf, px, pn = F.ctypes.data, x.ctypes.data, ns.ctypes.data
        c0, w0 = time.process_time_ns(), time.perf_counter_ns()
        lib.sl_timed_filter(pf, px, k.g, k.U1, k.U2, k.h, k.beta, k.noise, pn)
        w1, c1 = time.perf_counter_ns(), time.process_time_ns()
        wall["C from Python"].append(w1 - w0)
        cpu["C from Python"].append(c1 - c0)
        wall["C in C"].append(ns[0])
        cpu["C in C"].append(ns[1])
        return F, x

    for k in calls[:20]:  # first calls (numba's dispatch, the library's pages), untimed
        numba(k), c_step(k)
    for c in CONTENDERS:
        wall[c].clear()
        cpu[c].clear()
    t0 = time.perf_counter()
    for rep in range(a.repeats):
        for i, k in enumerate(calls):
            if (i + rep) % 2 == 0:
                (fn, xn), (fc, xc) = numba(k), c_step(k)
            else:
                (fc, xc), (fn, xn) = c_step(k), numba(k)
            differ += not (np.array_equal(fn, fc) and np.array_equal(xn, xc))
    over = np.array([(lib.sl_timer_overhead(ns.ctypes.data), *ns)[1:] for _ in range(2000)])
    F0 = np.ascontiguousarray([k.F for k in calls])
    x0 = np.ascontiguousarray([k.x for k in calls])
    inputs = np.ascontiguousarray([[k.g, k.U1, k.U2, k.h, k.beta, k.noise] for k in calls])
    reps = 200
    numba_batch = _numba_batch(ff.filter_step, ff.NF)
    numba_batch(F0, x0, inputs, 1)  # compiled, untimed
    batch, nbatch = [], []
    for i in range(10):
        for first in ((0, 1) if i % 2 == 0 else (1, 0)):
            if first == 0:
                lib.sl_filter_batch(F0.ctypes.data, x0.ctypes.data, inputs.ctypes.data,
                                    len(calls), reps, ns.ctypes.data)
                batch.append(ns / (reps * len(calls)))
            else:
                c0, w0 = time.process_time_ns(), time.perf_counter_ns()
                numba_batch(F0, x0, inputs, reps)
                w1, c1 = time.perf_counter_ns(), time.process_time_ns()
                nbatch.append(np.array([w1 - w0, c1 - c0]) / (reps * len(calls)))
    batch_ns, nbatch_ns = np.array(batch), np.array(nbatch)
    print(f"{len(calls)} filter steps of {landings} noisy landings (paper's robot), "
          f"{a.repeats} passes, interleaved call by call; {time.perf_counter() - t0:.1f} s; "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; outputs "
          f"differing: {differ}")
    print(f"C compiled with -std=c99 -O2 -ffp-contract=off; the C clocks' own cost, "
          f"included in 'C in C': median wall {np.median(over[:, 0]):.0f} ns, CPU "
          f"{np.median(over[:, 1]):.0f} ns")
    print(f"{'us per step':24} {'med wall':>9} {'p99 wall':>9} {'max wall':>9} "
          f"{'med CPU':>9} {'p99 CPU':>9} {'max CPU':>9}")
    rows = {}
    for c in CONTENDERS:
        w, p = np.array(wall[c]) / 1e3, np.array(cpu[c]) / 1e3
        rows[c] = stats(w) + stats(p)
        print(f"{c:24} " + " ".join(f"{v:9.3f}" for v in rows[c]))
    for c in CONTENDERS[1:]:
        print(f"{'ratio ' + c + '/numba':24} " + " ".join(
            f"{x / y:9.3f}" for x, y in zip(rows[c], rows["numba"], strict=True)))
    for name, b in (("C in C", batch_ns), ("numba in numba", nbatch_ns)):
        w, p = b[:, 0], b[:, 1]
        print(f"{name + ', batch':24} ({reps} x {len(calls)} calls, {len(b)} runs "
              f"alternating): wall median {np.median(w):.1f} ns per step ({w.min():.1f} "
              f"to {w.max():.1f}), CPU median {np.median(p):.1f} ns ({p.min():.1f} to "
              f"{p.max():.1f})")
    med, nmed = np.median(batch_ns, axis=0), np.median(nbatch_ns, axis=0)
    print(f"{'ratio C/numba, batch':24} wall {med[0] / nmed[0]:.3f}, CPU "
          f"{med[1] / nmed[1]:.3f} (medians)")


def _numba_batch(step, nf):
    """The C batch's loop compiled by numba around ``step``."""
    from numba import njit

    @njit(cache=False)
    def run(F0, x0, inputs, reps):
        F = np.empty(nf)
        x = np.empty(4)
        total = 0.0
        for _ in range(reps):
            for i in range(F0.shape[0]):
                F[:] = F0[i]
                x[:] = x0[i]
                a = inputs[i]
                step(F, x, a[0], a[1], a[2], a[3], a[4], a[5])
                total += x[3]
        return total

    return run


if __name__ == "__main__":
    main()
