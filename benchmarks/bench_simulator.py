"""Exact simulator against scipy solve_ivp, and the paper's full impedance grid.

Run:  python benchmarks/bench_simulator.py [--cases 200] [--skip-grid]

Prints, measured in this run on this machine:
* mean time per landing of the toolkit (one ``simulate`` call each, and
  per landing inside ``simulate_batch``) and of scipy ``solve_ivp`` (LSODA,
  rtol 1e-10, atol 1e-12, events; the same mode logic, tests/ivp_reference.py),
  their ratio, and the largest depth difference;
* wall time and peak resident memory of the paper's grid, k_p and k_d in
  [0, 1] step 0.01 times v0 in {0, -0.5, ..., -10}: 214,221 landings.
Goals (issue 2): ratio >= 1000x (floor 300x); depth difference <= 1e-7;
grid <= 20 s on 2 cores (floor 60 s); peak memory <= 2 GiB.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from ivp_reference import landing_depth_ivp  # noqa: E402

from softlanding import DimensionlessParams, Impedance, simulate, simulate_batch  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--skip-grid", action="store_true")
    a = ap.parse_args()

    rng = np.random.default_rng(a.seed)
    kp = rng.uniform(0, 1, a.cases)
    kd = rng.uniform(0, 1, a.cases)
    v0 = rng.uniform(-10, 0, a.cases)

    # warm-up (JIT load) outside the timings
    simulate(DimensionlessParams(v0=-1), Impedance(0.2, 0.2), energy=False)
    simulate_batch([0.2], [0.2], [-1.0])

    t = time.perf_counter()
    ours = [simulate(DimensionlessParams(r_m=5, s=20, v0=v), Impedance(p, d), energy=False)
            for p, d, v in zip(kp, kd, v0, strict=True)]
    t_ours = (time.perf_counter() - t) / a.cases

    reps = 20
    t = time.perf_counter()
    for _ in range(reps):
        b = simulate_batch(kp, kd, v0)
    t_batch = (time.perf_counter() - t) / (reps * a.cases)

    ref, t_ref, skipped = [], 0.0, 0
    for p, d, v, r in zip(kp, kd, v0, ours, strict=True):
        if not r.rest_proven:
            skipped += 1
            ref.append(None)
            continue
        t = time.perf_counter()
        ref.append(landing_depth_ivp(v, p, d))
        t_ref += time.perf_counter() - t
    n_cmp = a.cases - skipped
    t_ref /= max(n_cmp, 1)
    diffs = [abs(r.depth - q["depth"]) for r, q in zip(ours, ref, strict=True) if q is not None]
    steps_agree = sum(r.steps == q["steps"] for r, q in zip(ours, ref, strict=True)
                      if q is not None)
    assert np.array_equal(b.depth, np.array([r.depth for r in ours]))

    print(f"landings sampled: {a.cases} (k_p, k_d in [0,1], v0 in [-10,0], r_m=5, s=20); "
          f"compared: {n_cmp} (rest not proven by the toolkit: {skipped})")
    print(f"toolkit simulate()      : {t_ours * 1e6:10.1f} us per landing")
    print(f"toolkit simulate_batch(): {t_batch * 1e6:10.1f} us per landing "
          f"({os.cpu_count()} cores)")
    print(f"scipy solve_ivp (LSODA) : {t_ref * 1e6:10.1f} us per landing")
    print(f"speed ratio solve_ivp / simulate()       : {t_ref / t_ours:8.0f}x")
    print(f"speed ratio solve_ivp / batch per landing: {t_ref / t_batch:8.0f}x")
    print(f"largest depth difference: {max(diffs):.2e}; intrusion steps agree in "
          f"{steps_agree}/{n_cmp}")

    if a.skip_grid:
        return
    g = np.round(np.linspace(0, 1, 101), 12)
    v = np.round(np.linspace(-10, 0, 21), 12)
    KP, KD, V = np.meshgrid(g, g, v, indexing="ij")
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t = time.perf_counter()
    grid = simulate_batch(KP, KD, V, progress=False)
    t_grid = time.perf_counter() - t
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    unproven = int((grid.status != 0).sum())
    print(f"paper grid: {KP.size:,} landings in {t_grid:.1f} s "
          f"({t_grid / KP.size * 1e6:.0f} us each, {os.cpu_count()} cores); "
          f"peak RSS {rss1:.0f} MiB (before the grid {rss0:.0f} MiB)")
    print(f"  feasible: {grid.feasible.mean():.1%}; rest not proven: {unproven} "
          f"(k_p = 0 creeping, or k_d = 0 endless hopping), reported as such")
    with np.errstate(invalid="ignore"):
        depth_ratio = np.nanmax(np.where(grid.feasible, grid.depth, math.nan))
    print(f"  deepest feasible landing: {depth_ratio:.4f}")


if __name__ == "__main__":
    main()
