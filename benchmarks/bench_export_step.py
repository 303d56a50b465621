"""Step time of the exported C controller (``softlanding export-controller``) against the
numba controller it was exported from (issue 33, item 6), interleaved call by call.

Run:  python -m benchmarks.bench_export_step [--samples 1000] [--repeats 5]

The calls are those of random landings (``softlanding.control.export_c.samples``: the
paper's robot on random grounds, a plant on a ground off the controller's prior, noisy
sensors, and landings whose samples go as planned), recorded once; each sample's control
step (estimate and plan update: ``control_step`` / ``sl_control_step``) is then run by
both contenders from the same inputs, alternating which goes first call by call. Timed:

- numba: ``bangbang.control_step`` called from Python, wall (``perf_counter_ns``) and CPU
  (``process_time_ns``) around the call, as ``mpc_landing`` times its steps;
- C from Python: ``sl_control_step`` through ctypes, timed the same way (the baseline's
  conditions: a call from Python);
- C in C: the same call timed inside C (``clock_gettime``, monotonic and process CPU
  clocks), what a robot's loop would see; the two clock readings' own cost is printed.

The C is compiled with the README's flags (``-std=c99 -O2 -ffp-contract=off``). Printed:
median, 99th percentile and maximum (wall and CPU, microseconds) of each, by path (plan
kept, re-solved), the ratios C / numba, the issue's goals (max step <= the rig's sample
period, 0.26 ms; median <= 20 us), and whether both gave the same outputs.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import time

import numpy as np

from benchmarks.c_timing import CLOCKS_C, CONTENDERS, stats, timed_library


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000, help="control steps (default 1000)")
    ap.add_argument("--repeats", type=int, default=5, help="passes over them (default 5)")
    a = ap.parse_args()
    from softlanding.control import bangbang as bb
    from softlanding.control.export_c.samples import recorded_calls
    from softlanding.control.mpc import DEFAULT_PERIOD
    from softlanding.model.robot import PAPER_ROBOT
    from softlanding.model.terrain import paper_rig_units

    lib = timed_library(CLOCKS_C)  # (its sl_timed_step)
    r = PAPER_ROBOT
    calls, landings = recorded_calls(r, a.samples)
    steps = [k for k in calls if not k.first]
    vp, d = ctypes.c_void_p, ctypes.c_double
    lib.sl_timed_step.argtypes = [vp, vp, vp, d, d, d, ctypes.c_int, vp]
    lib.sl_timed_step.restype = ctypes.c_int
    lib.sl_timer_overhead.argtypes = [vp]
    ws = bb.workspace()
    ns = np.zeros(2)
    wall = {c: [] for c in CONTENDERS}
    cpu = {c: [] for c in CONTENDERS}
    paths: list[str] = []
    differ = 0

    def numba(k):
        P, M = k.P.copy(), k.M.copy()
        c0, w0 = time.process_time_ns(), time.perf_counter_ns()
        st = bb.control_step(P, M, k.x, k.a_f, k.u, k.h, True, *ws)
        w1, c1 = time.perf_counter_ns(), time.process_time_ns()
        wall["numba"].append(w1 - w0)
        cpu["numba"].append(c1 - c0)
        return int(st), M

    def c_step(k):
        P, M = k.P.copy(), k.M.copy()
        pp, pm, px, pn = P.ctypes.data, M.ctypes.data, k.x.ctypes.data, ns.ctypes.data
        c0, w0 = time.process_time_ns(), time.perf_counter_ns()
        st = lib.sl_timed_step(pp, pm, px, k.a_f, k.u, k.h, 1, pn)
        w1, c1 = time.perf_counter_ns(), time.process_time_ns()
        wall["C from Python"].append(w1 - w0)
        cpu["C from Python"].append(c1 - c0)
        wall["C in C"].append(ns[0])
        cpu["C in C"].append(ns[1])
        return int(st), M

    for k in steps[:20]:  # first calls (numba's dispatch, the library's pages), untimed
        numba(k), c_step(k)
    for c in CONTENDERS:
        wall[c].clear()
        cpu[c].clear()
    t0 = time.perf_counter()
    for rep in range(a.repeats):
        for i, k in enumerate(steps):
            if (i + rep) % 2 == 0:
                (sn, mn), (sc, mc) = numba(k), c_step(k)
            else:
                (sc, mc), (sn, mn) = c_step(k), numba(k)
            differ += sn != sc or not np.array_equal(mn, mc)
            paths.append("plan kept" if sn == bb.HOLDS else "re-solved")
    over = np.array([(lib.sl_timer_overhead(ns.ctypes.data), *ns)[1:] for _ in range(2000)])
    rig_us = 1e6 * DEFAULT_PERIOD * paper_rig_units().time
    kinds = np.array(paths)
    print(f"{len(steps)} control steps of {landings} random landings (paper's robot), "
          f"{a.repeats} passes, interleaved call by call; {time.perf_counter() - t0:.1f} s; "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; outputs "
          f"differing (status or memory): {differ}")
    print(f"C compiled with -std=c99 -O2 -ffp-contract=off; the C clocks' own cost, "
          f"included in 'C in C': median wall {np.median(over[:, 0]) / 1e3:.3f} us, CPU "
          f"{np.median(over[:, 1]) / 1e3:.3f} us")
    print(f"{'us per step':24} {'med wall':>9} {'p99 wall':>9} {'max wall':>9} "
          f"{'med CPU':>9} {'p99 CPU':>9} {'max CPU':>9}")
    rows = {}
    for c in CONTENDERS:
        w, p = np.array(wall[c]) / 1e3, np.array(cpu[c]) / 1e3
        rows[c] = stats(w) + stats(p)
        print(f"{c:24} " + " ".join(f"{v:9.3f}" for v in rows[c]))
        for kind in ("plan kept", "re-solved"):
            sel = kinds == kind
            print(f"  {kind + f' ({sel.sum() // a.repeats})':22} "
                  + " ".join(f"{v:9.3f}" for v in stats(w[sel]) + stats(p[sel])))
    for c in CONTENDERS[1:]:
        print(f"{'ratio ' + c + '/numba':24} " + " ".join(
            f"{x / y:9.3f}" for x, y in zip(rows[c], rows["numba"], strict=True)))
    b = rows["C in C"]
    print(f"goals (C in C): max step <= {rig_us:.0f} us (the rig's period): wall "
          f"{'met' if b[2] <= rig_us else 'NOT met'} ({b[2]:.1f} us), CPU "
          f"{'met' if b[5] <= rig_us else 'NOT met'} ({b[5]:.1f} us); median <= 20 us: wall "
          f"{'met' if b[0] <= 20 else 'NOT met'} ({b[0]:.2f} us), CPU "
          f"{'met' if b[3] <= 20 else 'NOT met'} ({b[3]:.2f} us)")


if __name__ == "__main__":
    main()
