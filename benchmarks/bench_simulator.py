"""Exact simulator: current kernel against the frozen first kernel, and against scipy solve_ivp.

Run:  python -m benchmarks.bench_simulator [--cases 200] [--repeats 5] [--grid-repeats 2]
                                           [--skip-grid] [--skip-ivp]

Every timing is measured in this run, interleaved: the current kernel
(``softlanding.simulation.kernel``) and the frozen first kernel (``benchmarks/_kernel_v0.py``,
the kernel before the split, plugged into the same ``simulate`` wrappers) run
block by block in alternating order, several repeats; medians are reported in
CPU time (``time.process_time``: all threads of this process) and in wall time.
The machine's load average is printed before and after, since the cores are
shared.

Prints:
* per ``simulate()`` call and per landing of ``simulate_batch`` on a random
  sample (k_p, k_d in [0, 1], v0 in [-10, 0]); the ratio old / new;
* scipy ``solve_ivp`` (LSODA, rtol 1e-10, atol 1e-12, events; the same mode logic,
  tests/ivp_reference.py) on the same sample: time, ratio, largest depth difference;
* the paper's grid, k_p and k_d in [0, 1] step 0.01 times v0 in {0, -0.5, ..., -10}:
  214,221 landings; wall and CPU time of both kernels, the ratio, how many landings
  differ between them (by output column) and the statuses; then the grid alone in a
  fresh process (``_grid_rss_child.py``): its time and peak RSS.
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

HERE = Path(__file__).resolve().parent
from softlanding import Impact, Impedance, Robot, simulate, simulate_batch  # noqa: E402
from softlanding.model.controllers import impedance_gains  # noqa: E402
from softlanding.simulation import kernel as K  # noqa: E402
from tests.oracles import kernel_v0 as K0  # noqa: E402
from tests.oracles.ivp_reference import landing_depth_ivp  # noqa: E402

S = sys.modules["softlanding.simulation.simulator"]



class _FirstKernelPadded:
    """The frozen first kernel with its outputs padded to the current layout.

    The first kernel predates the columns ``O_DLIM`` and ``O_FOOT_REST``; the simulator reads
    every column, so the missing ones are filled here (NaN, 0) rather than the library making
    room for an old layout. The padding copies one row per landing: negligible next to a
    landing, and it counts against the first kernel.
    """

    N_OUT, O_DLIM, O_FOOT_REST = K.N_OUT, K.O_DLIM, K.O_FOOT_REST

    def __getattr__(self, name):
        return getattr(K0, name)

    @staticmethod
    def _pad(out):
        full = np.zeros(out.shape[:-1] + (K.N_OUT,))
        full[..., :K0.N_OUT] = out
        full[..., K.O_DLIM] = np.nan
        return full

    def run_landing(self, *args):
        out, segments = K0.run_landing(*args)
        return self._pad(out), segments

    def run_batch(self, *args):
        *head, out = args
        first = np.zeros((out.shape[0], K0.N_OUT))
        K0.run_batch(*head, first)
        out[:] = self._pad(first)


KERNELS = {"old": _FirstKernelPadded(), "new": K}
COMMON_FIELDS = [f for f in S.BATCH_FIELDS if f not in ("depth_limit", "foot_rest")]
"""Columns both kernels have (the first one predates the depth limit and foot-rest flag)."""


def _load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def interleaved(blocks: dict, repeats: int) -> dict:
    """Run each callable once per repeat, alternating the order; median (cpu, wall)."""
    res = {k: ([], []) for k in blocks}
    names = list(blocks)
    for r in range(repeats):
        for k in names if r % 2 == 0 else names[::-1]:
            c, w = time.process_time(), time.perf_counter()
            blocks[k]()
            res[k][0].append(time.process_time() - c)
            res[k][1].append(time.perf_counter() - w)
    return {k: (float(np.median(c)), float(np.median(w))) for k, (c, w) in res.items()}


def with_kernel(name, fn):
    """``fn`` run with ``softlanding.simulation.simulator`` wired to kernel ``name``."""
    def run():
        S.K = KERNELS[name]
        try:
            return fn()
        finally:
            S.K = K
    return run


def report(label, t, n, unit="us"):
    scale = 1e6 if unit == "us" else 1.0
    for k in ("old", "new"):
        c, w = t[k]
        print(f"  {label} {k}: cpu {c / n * scale:9.2f} {unit}, wall {w / n * scale:9.2f} {unit}")
    print(f"  {label} ratio old/new: cpu {t['old'][0] / t['new'][0]:.2f}x, "
          f"wall {t['old'][1] / t['new'][1]:.2f}x")


def sample_section(a, kp, kd, v0):
    robot = Robot(r_m=5, s=20)
    params = [Impact(v) for v in v0]
    pols = [Impedance(p, d) for p, d in zip(kp, kd, strict=True)]

    def calls():
        return [simulate(robot, p, q, energy=False) for p, q in zip(params, pols, strict=True)]

    t = interleaved({k: with_kernel(k, calls) for k in KERNELS}, a.repeats)
    print(f"simulate() per call ({a.cases} landings per block, {a.repeats} blocks each):")
    report("simulate()", t, a.cases)
    mats = S.mode_matrices(5.0)
    Kf = [np.tile(impedance_gains(p, d, 10.0), (3, 1)) for p, d in zip(kp, kd, strict=True)]
    x0 = [np.array([10.0, v, 0.0, v]) for v in v0]
    e = np.zeros(0)

    def kern(mod):
        def run():
            for i in range(a.cases):
                mod.run_landing(mats, Kf[i], math.inf, e, e, x0[i], 20.0, 1e4, 500, False)
        return run

    t = interleaved({"old": kern(K0), "new": kern(K)}, a.repeats)  # the raw kernels
    print("kernel run_landing() per call (the kernel's part of simulate()):")
    report("run_landing()", t, a.cases)
    reps = 20

    def batch():
        for _ in range(reps):
            simulate_batch(Robot(5, 20), v0, kp, kd)

    t = interleaved({k: with_kernel(k, batch) for k in KERNELS}, a.repeats)
    print(f"simulate_batch() per landing ({os.cpu_count()} cores):")
    report("batch", t, reps * a.cases)
    return calls()


def ivp_section(a, kp, kd, v0, ours):
    ref, t_ref, skipped = [], 0.0, 0
    for p, d, v, r in zip(kp, kd, v0, ours, strict=True):
        if not r.rest_proven:
            skipped += 1
            ref.append(None)
            continue
        t = time.process_time()
        ref.append(landing_depth_ivp(v, p, d))
        t_ref += time.process_time() - t
    n_cmp = a.cases - skipped
    diffs = [abs(r.depth - q["depth"]) for r, q in zip(ours, ref, strict=True) if q is not None]
    agree = sum(r.steps == q["steps"] for r, q in zip(ours, ref, strict=True) if q is not None)
    print(f"scipy solve_ivp (LSODA): cpu {t_ref / max(n_cmp, 1) * 1e6:10.1f} us per landing on "
          f"{n_cmp} landings (rest not proven by the toolkit: {skipped}); largest depth "
          f"difference {max(diffs):.2e}; intrusion steps agree in {agree}/{n_cmp}")


def grid_section(a):
    g = np.round(np.linspace(0, 1, 101), 12)
    v = np.round(np.linspace(-10, 0, 21), 12)
    KP, KD, V = np.meshgrid(g, g, v, indexing="ij")
    outs = {}

    def run(name):
        def go():
            outs[name] = simulate_batch(Robot(5, 20), V, KP, KD, progress=False)
        return with_kernel(name, go)

    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t = interleaved({k: run(k) for k in KERNELS}, a.grid_repeats)
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"paper grid: {KP.size:,} landings ({os.cpu_count()} cores, {a.grid_repeats} runs "
          f"of each kernel, alternating):")
    report("grid", t, 1, unit="s")
    print(f"  peak RSS of this process {rss1:.0f} MiB (before the grids {rss0:.0f} MiB)")
    old, new = outs["old"], outs["new"]
    for name in COMMON_FIELDS:
        x, y = np.asarray(old.data[name], float), np.asarray(new.data[name], float)
        nd = int((~((x == y) | (np.isnan(x) & np.isnan(y)))).sum())
        if nd:
            print(f"  column {name}: {nd} landings differ between the kernels")
    proven = old.status == 0
    eq = _rows_equal(old, new)
    eq_but_status = _rows_equal(old, new, skip=("status",))
    print(f"  rest proven by the old kernel: {int(proven.sum())}; of these identical in every "
          f"column: {int(eq[proven].sum())}, identical apart from the status: "
          f"{int(eq_but_status[proven].sum())}")
    for code in np.unique(new.status):
        print(f"  new status {int(code)} ({K.STATUS_NAMES[int(code)]}): "
              f"{int((new.status == code).sum())}")
    hops = new.status == K.HOPS_TO_LIMIT
    if hops.any():  # their limit against the closed form of the energy balance (r_m = 5)
        m_b, m_f = 5 / 6, 1 / 6
        closed = 1 + np.sqrt(1 + V[hops] ** 2 - m_f * (2 * m_b + m_f) / KP[hops])
        was = old.depth[hops]
        print(f"  undamped hops stopped at their limit: {int(hops.sum())}; largest difference "
              f"from the closed form 1 + sqrt(1 + v0^2 - m_f (2 m_b + m_f) / k_p): "
              f"{np.max(np.abs(new.depth[hops] - closed)):.1e}; the old kernel's depth at "
              f"its segment limit was short of it by {np.min(closed - was):.1e} to "
              f"{np.max(closed - was):.1e}")
    with np.errstate(invalid="ignore"):
        deepest = np.nanmax(np.where(new.feasible, new.depth, math.nan))
    print(f"  feasible: {new.feasible.mean():.1%}; deepest feasible landing: {deepest:.4f}")


def _rows_equal(b0, b1, skip=()):
    ok = None
    for name in COMMON_FIELDS:
        if name in skip:
            continue
        x, y = np.asarray(b0.data[name], float), np.asarray(b1.data[name], float)
        eq = (x == y) | (np.isnan(x) & np.isnan(y))
        ok = eq if ok is None else ok & eq
    return ok


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--grid-repeats", type=int, default=2)
    ap.add_argument("--skip-grid", action="store_true")
    ap.add_argument("--skip-ivp", action="store_true")
    a = ap.parse_args()

    rng = np.random.default_rng(a.seed)
    kp = rng.uniform(0, 1, a.cases)
    kd = rng.uniform(0, 1, a.cases)
    v0 = rng.uniform(-10, 0, a.cases)
    for name in KERNELS:  # warm-up (JIT load) outside the timings
        with_kernel(name, lambda: (simulate(Robot(5, 20), Impact(-1), Impedance(0.2, 0.2)),
                                   simulate_batch(Robot(5, 20), [-1.0], [0.2], [0.2])))()
    print(f"before: {_load()}; {os.cpu_count()} cores")
    ours = sample_section(a, kp, kd, v0)
    if not a.skip_ivp:
        ivp_section(a, kp, kd, v0, ours)
    if not a.skip_grid:
        grid_section(a)
        import subprocess

        print(subprocess.run([sys.executable, str(HERE / "_grid_rss_child.py")],
                             capture_output=True, text=True, check=True).stdout.rstrip())
    print(f"after: {_load()}")


if __name__ == "__main__":
    main()
