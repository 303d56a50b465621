"""Non-affine grounds: the integrated (DOP853) simulator against the exact path and solve_ivp.

Run:  python -m benchmarks.bench_terrain [--cases 100] [--repeats 3]

In one run, interleaved (contenders alternate block by block, several repeats; medians of
CPU time, ``time.process_time``, and wall time), on random landings (k_p, k_d in [0, 1],
v0 in [-10, 0], r_m = 5, s = 20):

* the exact path on the paper's spring (``simulate()``);
* the integrated path on the same spring (``method="integrate"``, c_d = 0): its depth
  against the exact one;
* the integrated path under drag (c_d = 0.2) and on the poppy-seed added-mass ground;
* scipy ``solve_ivp`` (DOP853, rtol = atol = 1e-12, events; tests/ivp_terrain.py, written
  from the equations) under drag on the same sample: time, depth difference;

then the ratios, and the paper's 101 x 101 (k_p, k_d) map at v0 = -4.8 under drag (2 cores).
The machine's load average is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from softlanding import PAPER_IMPEDANCE_ROBOT, Impact, Impedance, Robot, simulate, simulate_batch  # noqa: E402  # noqa: E402
from softlanding.model.ground import LINEAR_GROUND, DragGround  # noqa: E402
from softlanding.model.terrain import paper_rig_units, poppy_seed_added_mass  # noqa: E402
from tests.oracles.ivp_terrain import landing_ivp  # noqa: E402

ROBOT = Robot(5, 20)
DRAG = DragGround(0.2)


def _load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def _timed(fn, cases):
    c0, w0 = time.process_time(), time.perf_counter()
    out = [fn(*c) for c in cases]
    return (time.process_time() - c0) / len(cases), (time.perf_counter() - w0) / len(cases), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ivp-cases", type=int, default=20)
    a = ap.parse_args()
    rng = np.random.default_rng(7)
    cases = [(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(-10, 0)) for _ in range(a.cases)]
    poppy = poppy_seed_added_mass(paper_rig_units())
    blocks = {
        "exact (linear)": lambda kp, kd, v: simulate(ROBOT, Impact(v), Impedance(kp, kd)),
        "integrated, c_d = 0": lambda kp, kd, v: simulate(
            ROBOT, Impact(v), Impedance(kp, kd), LINEAR_GROUND, method="integrate"),
        "integrated, drag 0.2": lambda kp, kd, v: simulate(ROBOT, Impact(v), Impedance(kp, kd),
                                                           DRAG),
        "integrated, added mass": lambda kp, kd, v: simulate(ROBOT, Impact(v),
                                                             Impedance(kp, kd), poppy),
        "solve_ivp DOP853, drag 0.2": lambda kp, kd, v: landing_ivp(v, kp, kd, c_d=0.2),
    }
    for f in blocks.values():  # compile and load everything first
        f(*cases[0])
    print(_load())
    times: dict[str, tuple[list, list]] = {k: ([], []) for k in blocks}
    results: dict[str, list] = {}
    names = list(blocks)
    for r in range(a.repeats):
        for k in names if r % 2 == 0 else names[::-1]:
            sample = cases[:a.ivp_cases] if k.startswith("solve_ivp") else cases
            c, w, out = _timed(blocks[k], sample)
            times[k][0].append(c)
            times[k][1].append(w)
            results[k] = out
    med = {k: (statistics.median(v[0]), statistics.median(v[1])) for k, v in times.items()}
    for k, (c, w) in med.items():
        print(f"{k:<28}: {c * 1e6:10.1f} us CPU, {w * 1e6:10.1f} us wall per landing")
    ex, z0 = results["exact (linear)"], results["integrated, c_d = 0"]
    print(f"c_d = 0: largest depth difference integrated vs exact "
          f"{max(abs(x.depth - y.depth) for x, y in zip(ex, z0, strict=True)):.2e}; "
          f"steps agree in {sum(x.steps == y.steps for x, y in zip(ex, z0, strict=True))}"
          f"/{len(ex)}")
    dr, iv = results["integrated, drag 0.2"][:a.ivp_cases], results["solve_ivp DOP853, drag 0.2"]
    print(f"drag 0.2: largest depth difference vs solve_ivp "
          f"{max(abs(x.depth - y['depth']) for x, y in zip(dr, iv, strict=True)):.2e}")
    base = med["exact (linear)"][0]
    for k in ("integrated, c_d = 0", "integrated, drag 0.2", "integrated, added mass"):
        print(f"ratio {k} / exact path (CPU): {med[k][0] / base:6.2f}x")
    print(f"ratio solve_ivp / integrated, drag 0.2 (CPU): "
          f"{med['solve_ivp DOP853, drag 0.2'][0] / med['integrated, drag 0.2'][0]:8.0f}x")
    kp = np.linspace(0, 1, 101)[:, None]
    kd = np.linspace(0, 1, 101)[None, :]
    for g in (LINEAR_GROUND, DRAG, LINEAR_GROUND, DRAG):
        c0, w0 = time.process_time(), time.perf_counter()
        b = simulate_batch(PAPER_IMPEDANCE_ROBOT, -4.8, kp, kd, g)
        print(f"101 x 101 map at v0 = -4.8, {g.name:<6}: {time.perf_counter() - w0:6.2f} s wall, "
              f"{time.process_time() - c0:6.2f} s CPU (2-core machine); rest proven "
              f"{np.mean(b.status == 0):.1%}")
    print(_load())


if __name__ == "__main__":
    main()
