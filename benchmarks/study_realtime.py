"""The compiled controller at every sensing level (issue 46, item 4): every sample within the
rig's period, every limit held, the depth against the clairvoyant optimum.

Run:  python -m benchmarks.study_realtime [--quick] [--settings 1e-3:1,1e-2:2]
      [--margins 0,2] [--random 20] [--json FILE]

Cases: the unknown-ground study's 60 (the paper's robot; v0 in {-1, -3, -6, -10}, K in
{0.5, 0.75, 1, 1.5, 2}, c_d in {0, 0.2, 1}) and ``--random`` random robots on random grounds
(seeded: r_m in [2, 10], s in [8, 40], u_max in [2, 12] times the body's weight, K in
[0.5, 2], c_d 0 or in [0, 1], v0 in [-10, -1]). Each case lands under
``mpc_landing(..., controller="bangbang")`` (the default) for every sensing setting
``noise:delay`` and margin (seed 0), and against the clairvoyant optimum
(:func:`softlanding.solve_landing` on the true ground).

Per setting: the compiled samples' CPU time in the landing (``step_cpu_ms``: median, 99th
percentile, maximum over every sample of every landing) and replayed as a control loop
(:func:`softlanding.control.loop_replay.replay`, checked identical to the bit), against the
rig's 0.26 ms period; the samples the fallback met; the landings that held every limit
(stroke, force, rest proven); the depth / clairvoyant (largest, and how many within 3 %).
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from softlanding.control import mpc_landing
from softlanding.control.loop_replay import replay
from softlanding.model.robot import PAPER_ROBOT, Robot
from softlanding.model.terrain import paper_rig_units
from softlanding.optimal.landing import solve_landing
from softlanding.studies.unknown_ground import (
    STUDY_DRAG,
    STUDY_STIFFNESS,
    STUDY_V0,
    true_ground,
)
from softlanding.util.files import atomic, output_path


def random_cases(n: int, seed: int = 46) -> tuple[list[tuple[Robot, float, float, float]], int]:
    """``n`` random robots and grounds ``(robot, v0, K, c_d)`` on which a landing exists (the
    clairvoyant optimum solves), and how many were drawn without one (skipped).

    Parameters
    ----------
    n : int
        How many.
    seed : int
        Of :func:`numpy.random.default_rng`.
    """
    from softlanding.errors import InfeasibleLandingError

    rng = np.random.default_rng(seed)
    out: list[tuple[Robot, float, float, float]] = []
    skipped = 0
    while len(out) < n:
        r_m = float(np.exp(rng.uniform(np.log(2.0), np.log(10.0))))
        weight = r_m / (1 + r_m)
        robot = Robot(r_m=r_m, s=float(rng.uniform(8.0, 40.0)),
                      u_max=float(weight * rng.uniform(2.0, 12.0)))
        c_d = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.0, 1.0))
        case = (robot, float(rng.uniform(-10.0, -1.0)), float(rng.uniform(0.5, 2.0)), c_d)
        try:
            solve_landing(case[1], robot, true_ground(case[2], c_d))
        except InfeasibleLandingError:
            skipped += 1
            continue
        out.append(case)
    return out, skipped


def study_cases(quick: bool) -> list[tuple[Robot, float, float, float]]:
    """The unknown-ground study's cases (``quick``: v0 in {-1, -10}, K in {0.5, 2}, c_d in
    {0, 1})."""
    grid = ((-1.0, -10.0), (0.5, 2.0), (0.0, 1.0)) if quick else (STUDY_V0, STUDY_STIFFNESS,
                                                                  STUDY_DRAG)
    return [(PAPER_ROBOT, v, k, c) for v, k, c in itertools.product(*grid)]


def land(case: tuple[Robot, float, float, float], clair: float, noise: float, delay: int,
         margin: float) -> dict[str, Any]:
    """One landing's row."""
    robot, v0, k, c_d = case
    m = mpc_landing(v0, robot, true_ground(k, c_d), noise=noise, delay=delay, margin=margin)
    loop = replay(m.compiled) if m.compiled is not None and m.compiled.samples else ([], [])
    return {"robot": robot.to_dict(), "v0": v0, "K": k, "c_d": c_d, "noise": noise,
            "delay": delay, "margin": margin, "ratio": m.depth / clair,
            "feasible": m.feasible, "stroke_held": m.stroke_held, "force_held": m.force_held,
            "u_peak": m.u_peak, "uncovered": m.uncovered,
            "paths": sorted(set(m.step_paths)), "cpu_ms": list(m.step_cpu_ms),
            "loop_cpu_ms": list(loop[1]), "step_work_max": max(m.step_work, default=0)}


def summary(rows: list[dict[str, Any]], period_ms: float) -> dict[str, Any]:
    """One setting's numbers."""
    cpu = np.concatenate([np.asarray(r["cpu_ms"], float) for r in rows] + [np.zeros(0)])
    loop = np.concatenate([np.asarray(r["loop_cpu_ms"], float) for r in rows] + [np.zeros(0)])
    ratios = np.array([r["ratio"] for r in rows])
    worst = max(rows, key=lambda r: r["ratio"])
    return {"landings": len(rows), "samples": int(cpu.size),
            "cpu_median_ms": float(np.median(cpu)), "cpu_p99_ms": float(np.percentile(cpu, 99)),
            "cpu_max_ms": float(cpu.max()), "over_period": int((cpu > period_ms).sum()),
            "loop_cpu_p99_ms": float(np.percentile(loop, 99)) if loop.size else None,
            "loop_cpu_max_ms": float(loop.max()) if loop.size else None,
            "fallback_samples": sum(r["uncovered"] for r in rows),
            "landings_with_fallback": sum(r["uncovered"] > 0 for r in rows),
            "limits_held": sum(r["feasible"] for r in rows),
            "force_held": sum(r["force_held"] for r in rows),
            "max_ratio": float(ratios.max()), "within_3_percent": int((ratios <= 1.03).sum()),
            "worst": {k: worst[k] for k in ("v0", "K", "c_d", "ratio", "robot")}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="8 study cases, 4 random ones")
    ap.add_argument("--settings", default="1e-3:1,1e-3:2,1e-2:1,1e-2:2",
                    help="noise:delay pairs, comma-separated")
    ap.add_argument("--margins", default="0,2")
    ap.add_argument("--random", type=int, default=20, help="random robots and grounds")
    ap.add_argument("--json", help="write every row to this new file")
    a = ap.parse_args()
    path = output_path(a.json, "json", force=False) if a.json else None
    random, skipped = random_cases(4 if a.quick else a.random)
    cases = study_cases(a.quick) + random
    settings = [(float(n), int(d)) for n, d in (s.split(":") for s in a.settings.split(","))]
    margins = [float(m) for m in a.margins.split(",")]
    period_ms = 1e3 * 0.01 * paper_rig_units().time
    t0 = time.process_time()
    clair = [solve_landing(v, r, true_ground(k, c)).depth for r, v, k, c in cases]
    rows: list[dict[str, Any]] = []
    print(f"{len(cases)} cases ({len(cases) - len(random)} of the study, {len(random)} random "
          f"robots and grounds; {skipped} drawn without a landing skipped), period "
          f"{period_ms:.3g} ms on the rig")
    print(f"{'noise':>6} {'delay':>5} {'margin':>6} {'landings':>8} {'CPU median/p99/max ms':>24}"
          f" {'over':>4} {'loop p99/max ms':>16} {'fallback':>8} {'limits held':>11} "
          f"{'max ratio':>9} {'within 3%':>9}")
    for (noise, delay), margin in itertools.product(settings, margins):
        mine = [land(c, d, noise, delay, margin) for c, d in zip(cases, clair, strict=True)]
        rows += mine
        s = summary(mine, period_ms)
        print(f"{noise:>6g} {delay:>5} {margin:>6g} {s['landings']:>8} "
              f"{s['cpu_median_ms']:.4f}/{s['cpu_p99_ms']:.4f}/{s['cpu_max_ms']:.4f}".rjust(24)
              + f" {s['over_period']:>4} {s['loop_cpu_p99_ms']:.4f}/{s['loop_cpu_max_ms']:.4f}"
              f" {s['fallback_samples']:>8} {s['limits_held']:>5} of {s['landings']:<3} "
              f"{s['max_ratio']:>9.4f} {s['within_3_percent']:>9}", flush=True)
        print(f"       worst: {json.dumps(s['worst'])}", flush=True)
    print(f"{len(rows)} landings in {time.process_time() - t0:.0f} s CPU")
    if path is not None:
        with atomic(Path(path)) as tmp, open(tmp, "w") as f:
            json.dump(rows, f)


if __name__ == "__main__":
    main()
