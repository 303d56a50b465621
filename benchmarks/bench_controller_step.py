"""Step time of the compiled bang-bang controller against the re-planning MPC (issue 33:
every step within the rig's 0.26 ms sample period, median <= 20 us), interleaved.

Run:  python -m benchmarks.bench_controller_step [--cases 12] [--repeats 2] [--noise S]
      [--delay N] [--margin M] [--realtime]

The contenders land the same cases (``bench_mpc_step.CASES``: every impact velocity on a
soft drag-free, a nominal dragging and a stiff draggy ground), alternating landing by landing
(the re-planning MPC first on even repeats, the bang-bang controller first on odd ones), so
that a drift of the shared machine's load falls on both. Each sample's estimate and control
update is timed in wall time (``time.perf_counter``) and CPU time (``time.process_time``),
as ``MPCLanding.step_times_ms`` / ``step_cpu_ms`` record it; the preparation before impact
(first plan, builds, compilation) is reported apart. One untimed landing per contender
first takes the process-wide compilations out of both. Printed: median, 99th percentile and
maximum step (wall and CPU) of each (and of the bang-bang controller's own samples, without
its fallbacks to the re-planning MPC: the goals'), their ratios, the goals, the bang-bang
controller's samples deferred by its bound on one sample's work (``bangbang.WORK``
integrator steps) and the most steps one sample took, and the relative depth difference
between the two per case (the same to 1e-8 where both are bang-bang). ``--realtime`` runs
the process as a robot runs its control loop (``benchmarks.realtime``: ``SCHED_FIFO``, one
CPU, memory locked), so that the wall-time maximum is the controller's, not the shared
machine's preemption.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from benchmarks.bench_mpc_step import CASES


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=len(CASES), help="the first N of the cases")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--noise", type=float, default=0.0, help="sensor noise std")
    ap.add_argument("--delay", type=int, default=0, help="samples of delay")
    ap.add_argument("--margin", type=float, default=0.0, help="bangbang's margin")
    ap.add_argument("--realtime", action="store_true",
                    help="run as a robot's control loop: SCHED_FIFO on one CPU, memory "
                         "locked (benchmarks.realtime; needs root or CAP_SYS_NICE)")
    a = ap.parse_args()
    if a.realtime:
        from benchmarks.realtime import RealtimeUnavailable, enter_realtime, rest

        try:
            print(enter_realtime())
        except RealtimeUnavailable as err:
            ap.error(f"--realtime: {err}")
    from softlanding.control.mpc import DEFAULT_PERIOD, mpc_landing
    from softlanding.model.robot import PAPER_ROBOT
    from softlanding.model.terrain import paper_rig_units
    from softlanding.studies.unknown_ground import true_ground

    names = ("replan", "bangbang")
    cases = CASES[:max(1, a.cases)]
    # (and the bang-bang controller's own samples: a sample it does not cover, and the rest
    # of that landing, are the re-planning MPC's, slow by design)
    stats = {n: {"wall": [], "cpu": [], "prep": [], "uncovered": 0, "deferred": 0, "work": 0}
             for n in (*names, "compiled")}
    depths: dict[str, dict[tuple, float]] = {n: {} for n in names}

    def land(name: str, case: tuple) -> object:
        if a.realtime:
            rest()
        return mpc_landing(case[0], PAPER_ROBOT, true_ground(case[1], case[2]),
                           controller=name, noise=a.noise, delay=a.delay, seed=1,
                           margin=a.margin if name == "bangbang" else 0.0)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for n in names:  # process-wide compilations, untimed
            land(n, cases[0])
        t0 = time.perf_counter()
        for rep in range(a.repeats):
            order = names if rep % 2 == 0 else names[::-1]
            for case in cases:
                for n in order:
                    m = land(n, case)
                    stats[n]["wall"] += m.step_times_ms
                    stats[n]["cpu"] += m.step_cpu_ms
                    stats[n]["prep"].append(m.prepare_time_s)
                    stats[n]["uncovered"] += m.uncovered
                    stats[n]["deferred"] += m.deferred
                    stats[n]["work"] = max([stats[n]["work"], *m.step_work])
                    depths[n][case] = m.depth
                    if n == "bangbang":
                        own = [k for k, p in enumerate(m.step_paths)
                               if p.startswith("bangbang")]
                        stats["compiled"]["wall"] += [m.step_times_ms[k] for k in own]
                        stats["compiled"]["cpu"] += [m.step_cpu_ms[k] for k in own]
                        stats["compiled"]["prep"].append(m.prepare_time_s)
                        stats["compiled"]["deferred"] += m.deferred
                        stats["compiled"]["work"] = stats["bangbang"]["work"]
    rig = 1e3 * DEFAULT_PERIOD * paper_rig_units().time
    print(f"{len(cases)} cases x {a.repeats} repeats, interleaved; noise {a.noise:g}, delay "
          f"{a.delay}, margin {a.margin:g}; {time.perf_counter() - t0:.0f} s; rig period "
          f"{rig:.3f} ms")
    print(f"{'':10} {'steps':>6} {'med wall':>9} {'p99 wall':>9} {'max wall':>9} "
          f"{'med CPU':>9} {'p99 CPU':>9} {'max CPU':>9} {'prep med s':>10} uncovered "
          f"deferred work  (ms; work: the most integrator steps of one sample)")
    rows = {}
    for n, s in stats.items():
        w, c = np.array(s["wall"]), np.array(s["cpu"])
        rows[n] = [np.median(w), np.percentile(w, 99), w.max(), np.median(c),
                   np.percentile(c, 99), c.max()]
        print(f"{n:10} {len(w):6d} " + " ".join(f"{v:9.4f}" for v in rows[n])
              + f" {np.median(s['prep']):10.2f} {s['uncovered']:9d} {s['deferred']:8d} "
              + (f"{s['work']:4d}" if n != "replan" else "   -"))
    ratio = [b / r for b, r in zip(rows["bangbang"], rows["replan"], strict=True)]
    print(f"{'ratio bb/rp':10} {'':6} " + " ".join(f"{v:9.2e}" for v in ratio))
    print("(compiled: the bang-bang controller's samples without the fallbacks to the "
          "re-planning MPC, the samples the goals are for)")
    b = rows["compiled"]
    from softlanding.control.bangbang import WORK

    print(f"bangbang's bound on one sample's work: {WORK} integrator steps")
    print(f"goals (bangbang): max step <= {rig:.3f} ms wall: "
          f"{'met' if b[2] <= rig else 'NOT met'} ({b[2]:.4f} ms; CPU {b[5]:.4f}); "
          f"median <= 0.020 ms wall: {'met' if b[0] <= 0.02 else 'NOT met'} ({b[0]:.4f} ms; "
          f"CPU {b[3]:.4f}); max CPU step <= {rig:.3f} ms: "
          f"{'met' if b[5] <= rig else 'NOT met'}")
    diffs = {c: depths["bangbang"][c] / depths["replan"][c] - 1 for c in cases}
    print("depths, bangbang / replan - 1 per case (v0, K, c_d): "
          + ", ".join(f"{c}: {d:.1e}" for c, d in diffs.items()))


if __name__ == "__main__":
    main()
