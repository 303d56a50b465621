"""Step time of the exported C filtered step (``sl_filtered_weight`` and
``sl_filtered_step`` of ``softlanding export-controller``: the per-sample weight, the
weighted step and the bounded full solve as recovery) against the plain C step
(``sl_control_step``) on the same inputs, interleaved call by call.

Run:  python -m benchmarks.bench_export_filtered [--steps 600] [--repeats 5]

The calls are the filtered controller's samples of the noisy landings of
``softlanding.control.export_c.filter_check`` (the paper's robot: random grounds, impact
velocities, periods, sensor noise and margins, and first its probes: the fast draggy
landings whose push needs the bounded full solve), recorded once; each is then run from the
same inputs by every contender, the first alternating call by call. Timed:

- C plain (the baseline): ``sl_control_step``, timed inside C (``clock_gettime``,
  monotonic and process CPU clocks; their own cost, printed, included);
- C filtered: ``sl_filtered_weight`` then ``sl_filtered_step``, as the README's filtered
  sample calls them, timed the same way;
- Python filtered: ``control.recovery.sample_weight`` then ``filtered_step`` (numba's step)
  called from Python, as ``mpc_landing`` runs a filtered sample (``perf_counter_ns``,
  ``process_time_ns``).

The C is compiled with the README's flags (``-std=c99 -O2 -ffp-contract=off``). Printed:
median, 99th percentile and maximum (microseconds) over all samples, the weighted ones
and those whose push needed the bounded full solve; the ratios to the plain step; whether
the C and Python filtered steps gave the same outputs.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import time

import numpy as np

from benchmarks.c_timing import CLOCKS_C, stats, timed_library

TIMER_C = CLOCKS_C + """
int sl_timed_filtered(double *P, double *M, const double *F, const double *x, double a_f,
                      double u, double h, int estimate, int *recovering, double *ns)
{
    double c0 = now_ns(CLOCK_PROCESS_CPUTIME_ID), w0 = now_ns(CLOCK_MONOTONIC);
    double w = estimate ? sl_filtered_weight(P, M, F, x, a_f, u) : 1.0;
    int st = sl_filtered_step(P, M, x, a_f, u, h, estimate, w, recovering);
    double w1 = now_ns(CLOCK_MONOTONIC), c1 = now_ns(CLOCK_PROCESS_CPUTIME_ID);
    ns[0] = w1 - w0;
    ns[1] = c1 - c0;
    return st;
}
"""

CONTENDERS = ("C plain", "C filtered", "Python filtered")
"""The contenders (the first the baseline)."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=600, help="samples (default 600)")
    ap.add_argument("--repeats", type=int, default=5, help="passes over them (default 5)")
    a = ap.parse_args()
    from softlanding.control import bangbang as bb
    from softlanding.control.export_c.filter_check import filtered_calls
    from softlanding.control.export_c.step_check import recovery_outcome
    from softlanding.control.recovery import filtered_step, sample_weight
    from softlanding.model.robot import PAPER_ROBOT

    lib = timed_library(TIMER_C, 1e-3)
    r = PAPER_ROBOT
    recorded = filtered_calls(r, a.steps)
    calls = recorded.steps
    vp, d, i = ctypes.c_void_p, ctypes.c_double, ctypes.c_int
    lib.sl_timed_step.argtypes = [vp, vp, vp, d, d, d, i, vp]
    lib.sl_timed_step.restype = i
    lib.sl_timed_filtered.argtypes = [vp, vp, vp, vp, d, d, d, i, ctypes.POINTER(i), vp]
    lib.sl_timed_filtered.restype = i
    lib.sl_timer_overhead.argtypes = [vp]
    ws = bb.workspace()
    ns = np.zeros(2)
    wall: dict[str, list[float]] = {c: [] for c in CONTENDERS}
    cpu: dict[str, list[float]] = {c: [] for c in CONTENDERS}
    differ = 0

    def plain(k):
        P, M = k.P.copy(), k.M.copy()
        lib.sl_timed_step(P.ctypes.data, M.ctypes.data, k.x.ctypes.data, k.a_f, k.u, k.h,
                           int(k.estimate), ns.ctypes.data)
        wall["C plain"].append(ns[0])
        cpu["C plain"].append(ns[1])

    def c_filtered(k):
        P, M = k.P.copy(), k.M.copy()
        n = i(k.recovering)
        st = lib.sl_timed_filtered(P.ctypes.data, M.ctypes.data, k.F.ctypes.data,
                                   k.x.ctypes.data, k.a_f, k.u, k.h, int(k.estimate),
                                   ctypes.byref(n), ns.ctypes.data)
        wall["C filtered"].append(ns[0])
        cpu["C filtered"].append(ns[1])
        return int(st), int(n.value), M

    def python(k):
        P, M = k.P.copy(), k.M.copy()
        c0, w0 = time.process_time_ns(), time.perf_counter_ns()
        w = sample_weight(P, M, k.F, k.x, k.a_f, k.u) if k.estimate else 1.0
        st, n = filtered_step(P, M, k.x, k.a_f, k.u, k.h, k.estimate, w, k.recovering, *ws)
        w1, c1 = time.perf_counter_ns(), time.process_time_ns()
        wall["Python filtered"].append(w1 - w0)
        cpu["Python filtered"].append(c1 - c0)
        return st, n, M, w

    kinds = []
    for k in calls:  # what each sample is (and the first calls, untimed)
        st, n, M, w = python(k)
        kinds.append("recovery" if recovery_outcome(st, M, k.recovering, n) is not None
                     else "weighted" if w < 1.0 else "weight 1")
        plain(k)
        c_filtered(k)
    for c in CONTENDERS:
        wall[c].clear()
        cpu[c].clear()
    t0 = time.perf_counter()
    for rep in range(a.repeats):
        for j, k in enumerate(calls):
            order = (0, 1, 2) if (j + rep) % 2 == 0 else (2, 1, 0)
            out = {}
            for o in order:
                if o == 0:
                    plain(k)
                elif o == 1:
                    out["c"] = c_filtered(k)
                else:
                    out["p"] = python(k)[:3]
            (sc, nc, mc), (sp, n_p, mp) = out["c"], out["p"]
            differ += sc != sp or nc != n_p or not np.array_equal(mc, mp)
    over = np.array([(lib.sl_timer_overhead(ns.ctypes.data), *ns)[1:] for _ in range(2000)])
    sel = np.array(kinds * a.repeats)
    print(f"{len(calls)} filtered samples of {recorded.landings} noisy landings (paper's "
          f"robot): {kinds.count('weighted')} weighted, {kinds.count('recovery')} with the "
          f"bounded full solve, {kinds.count('weight 1')} of weight 1; {a.repeats} passes, "
          f"interleaved call by call; {time.perf_counter() - t0:.1f} s; load average "
          f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; C and Python filtered "
          f"outputs differing: {differ}")
    print(f"C compiled with -std=c99 -O2 -ffp-contract=off; the C clocks' own cost, "
          f"included: median wall {np.median(over[:, 0]) / 1e3:.3f} us, CPU "
          f"{np.median(over[:, 1]) / 1e3:.3f} us")
    print(f"{'us per step':26} {'med wall':>9} {'p99 wall':>9} {'max wall':>9} "
          f"{'med CPU':>9} {'p99 CPU':>9} {'max CPU':>9}")
    rows = {}
    for c in CONTENDERS:
        w, p = np.array(wall[c]) / 1e3, np.array(cpu[c]) / 1e3
        rows[c] = stats(w) + stats(p)
        print(f"{c:26} " + " ".join(f"{v:9.3f}" for v in rows[c]))
        for kind in ("weighted", "recovery", "weight 1"):
            s = sel == kind
            if s.any():
                print(f"  {kind + f' ({s.sum() // a.repeats})':24} "
                      + " ".join(f"{v:9.3f}" for v in stats(w[s]) + stats(p[s])))
    for c in CONTENDERS[1:]:
        print(f"{'ratio ' + c + '/C plain':26} " + " ".join(
            f"{x / y:9.3f}" for x, y in zip(rows[c], rows["C plain"], strict=True)))


if __name__ == "__main__":
    main()
