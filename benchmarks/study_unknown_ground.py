"""The unknown-ground study (issue 25): every controller on every true ground, against the
clairvoyant optimum; MPC step times in the paper's units and on the paper's rig.

Run:  python -m benchmarks.study_unknown_ground [--quick] [--period P] [--json FILE]
      python -m benchmarks.study_unknown_ground --controllers [--quick] [--noise S]
      [--delay N] [--cases all|bang-bang|creep] [--json FILE] [--realtime]

``--controllers`` runs the controller study of issue 33 instead: per case the clairvoyant
optimum and the compiled bang-bang controller with exact measurements and with noisy,
delayed ones (margins 0 and 2 standard deviations); its step times (wall and CPU: median,
99th percentile, maximum over every step of every landing) against the rig's period, the
samples it did not cover (fallbacks to the re-planning MPC), and the goals: depth within
1 % of the clairvoyant one and every limit held where the clairvoyant optimum is bang-bang,
every limit held and within 3 % with the noise and the delay.

Prints one row per case (true ground K, c_d and v0): depth / clairvoyant depth for the
nominal open-loop plan, the robust open-loop schedule and the two-stage tree (planned for all
the grounds at once), the impedance tuned for the paper's ground and the MPC with estimation
(``!`` marks a controller that broke a limit or whose rest is not proven), and the MPC's step
times; then per v0 the worst depth over the grounds of each, and the goals checked. Timings
are wall time of each sample's estimate and re-plan (``time.perf_counter``), on whatever else
the machine runs.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from benchmarks.realtime import RealtimeUnavailable, enter_realtime, rest
from softlanding.errors import ParameterError
from softlanding.model.terrain import paper_rig_units
from softlanding.studies.unknown_ground import (
    REALISTIC_DELAY,
    REALISTIC_NOISE,
    STUDY_DRAG,
    STUDY_STIFFNESS,
    STUDY_V0,
    controller_study,
    study_summary,
    unknown_ground_study,
)
from softlanding.util.files import atomic, output_path


def _write_rows(path: Path, rows: list, force: bool) -> None:
    """The rows as JSON, atomically (a temporary file beside ``path``, renamed into place:
    never a partial file, nothing left by a failure; a file that appeared at ``path``
    meanwhile is refused unless ``force``)."""
    with atomic(path, force=force) as tmp, open(tmp, "w") as f:
        json.dump(rows, f, default=float)


def _cell(c: dict) -> str:
    return f"{c['ratio']:8.4f}{' ' if c['feasible'] else '!'}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="v0 in {-3, -10}, K in {0.5, 2}, "
                                                         "c_d in {0, 1}")
    ap.add_argument("--period", type=float, default=0.01)
    ap.add_argument("--json", help="write every row to this new file (checked before the "
                                   "study; written whole or not at all)")
    ap.add_argument("--force", action="store_true", help="replace an existing --json file")
    ap.add_argument("--controllers", action="store_true",
                    help="the controller study (bang-bang, exact and noisy) instead")
    ap.add_argument("--noise", type=float, default=REALISTIC_NOISE)
    ap.add_argument("--delay", type=int, default=REALISTIC_DELAY)
    ap.add_argument("--estimator", choices=("measured", "filtered"), default="filtered",
                    help="--controllers: the noisy landings' ground estimator (filtered, the "
                         "default: the force as applied and the foot's state filtered; "
                         "measured: as measured)")
    ap.add_argument("--margins", default="0,2",
                    help="--controllers: the noisy landings' margins, comma-separated")
    ap.add_argument("--cases", choices=("all", "bang-bang", "creep"), default="all",
                    help="--controllers: only the cases whose clairvoyant optimum is "
                         "bang-bang, or only the creeps (default: all)")
    ap.add_argument("--realtime", action="store_true",
                    help="--controllers: run as a robot's control loop (SCHED_FIFO on one "
                         "CPU, memory locked: benchmarks.realtime; needs root or "
                         "CAP_SYS_NICE)")
    a = ap.parse_args()
    if a.json:
        try:  # before hours of work: an existing file, a missing folder
            a.json = output_path(a.json, "json", force=a.force)
        except ParameterError as err:
            ap.error(str(err))
    grid = ((-3.0, -10.0), (0.5, 2.0), (0.0, 1.0)) if a.quick else (STUDY_V0, STUDY_STIFFNESS,
                                                                    STUDY_DRAG)
    if a.controllers:
        if a.realtime:
            try:
                print(enter_realtime())
            except RealtimeUnavailable as err:
                ap.error(f"--realtime: {err}")
        controllers(grid, a)
        return
    if a.realtime:
        ap.error("--realtime applies to --controllers only")
    if a.cases != "all":
        ap.error("--cases applies to --controllers only")
    t0 = time.perf_counter()
    rows = unknown_ground_study(*grid, period=a.period)
    tau = paper_rig_units().time
    print(f"sample period {a.period:g} (= {1e3 * a.period * tau:.3g} ms on the paper's rig); "
          f"{len(rows)} cases in {time.perf_counter() - t0:.0f} s")
    print(f"{'v0':>6} {'K':>5} {'c_d':>4} {'clairvoyant':>12} {'open-loop':>10} "
          f"{'robust':>10} {'tree':>10} {'imp. nom':>10} {'imp. worst':>10} {'MPC':>10} "
          f"{'median ms':>10} "
          f"{'p99 ms':>8}  re-plans")
    for r in rows:
        g = r["ground"]
        print(f"{r['v0']:>6.1f} {g.get('stiffness', 1.0):>5.2f} {g.get('c_d', 0.0):>4.1f} "
              f"{r['clairvoyant_depth']:>11.5f}{' ' if r['clairvoyant_verified'] else '?'} "
              f"{_cell(r['open_loop'])} {_cell(r['robust'])} {_cell(r['tree'])} "
              f"{_cell(r['impedance_nominal'])} {_cell(r['impedance_worst'])} {_cell(r['mpc'])} "
              f"{r['mpc']['step_time_median_ms']:>10.3f} {r['mpc']['step_time_p99_ms']:>8.2f}"
              f"  {r['mpc']['replans']}")
    s = study_summary(rows)
    keys = ("clairvoyant", "open_loop", "robust", "tree", "impedance_nominal",
            "impedance_worst", "mpc")
    print(f"\nworst depth over the grounds ('!': a limit broken on one of them)\n{'v0':>6} "
          + " ".join(f"{k:>18}" for k in keys))
    for v, w in s["worst_case"].items():
        print(f"{v:>6} " + " ".join(
            f"{w[k]:>17.5f}{' ' if w.get(k + '_feasible', True) else '!'}" for k in keys))
    print("\n" + json.dumps({k: v for k, v in s.items() if k != "worst_case"}, indent=1))
    print(f"goals (limits held, then worst depth): robust <= nominal at every v0: "
          f"{all(w['robust_le_nominal'] for w in s['worst_case'].values())}; tree <= robust: "
          f"{all(w['tree_le_robust'] for w in s['worst_case'].values())}")
    print(f"step time over all {s['steps']} steps: median {s['step_time_median_ms']:.3g} ms, "
          f"99th percentile {s['step_time_p99_ms']:.3g} ms wall; CPU median "
          f"{s['step_cpu_median_ms']:.3g} ms, 99th percentile {s['step_cpu_p99_ms']:.3g} ms "
          f"(goals 1 and 5 ms), against a "
          f"sample period of {1e3 * a.period * tau:.3g} ms on the paper's rig")
    if a.json:
        _write_rows(a.json, rows, a.force)


def _c(r: dict) -> str:
    return f"{r['ratio']:8.5f}{' ' if r['feasible'] else '!'}"


def _compiled(rows: list[dict], key: str) -> dict:
    """Step times of the compiled controller's own samples (its fallbacks to the
    re-planning MPC left out) in every landing ``key``, its deferred samples and the most
    integrator steps of one sample."""
    import numpy as np

    w = np.concatenate([r[key]["compiled_times_ms"] for r in rows] + [np.zeros(0)])
    c = np.concatenate([r[key]["compiled_cpu_ms"] for r in rows] + [np.zeros(0)])
    return {"compiled_steps": int(w.size),
            "compiled_wall_median_ms": float(np.median(w)) if w.size else None,
            "compiled_wall_p99_ms": float(np.percentile(w, 99)) if w.size else None,
            "compiled_wall_max_ms": float(w.max()) if w.size else None,
            "compiled_cpu_median_ms": float(np.median(c)) if c.size else None,
            "compiled_cpu_p99_ms": float(np.percentile(c, 99)) if c.size else None,
            "compiled_cpu_max_ms": float(c.max()) if c.size else None,
            **_loop(rows, key),
            "deferred": sum(r[key]["deferred"] for r in rows),
            "step_work_max": max((r[key]["step_work_max"] or 0 for r in rows), default=0)}


def _loop(rows: list[dict], key: str) -> dict:
    """Step times of the same compiled samples replayed as a control loop (one per period
    of the rig, nothing else between them; ``softlanding.control.loop_replay``)."""
    import numpy as np

    w = np.concatenate([r[key]["loop_times_ms"] for r in rows] + [np.zeros(0)])
    c = np.concatenate([r[key]["loop_cpu_ms"] for r in rows] + [np.zeros(0)])
    out: dict = {"loop_steps": int(w.size)}
    for name, v in (("wall", w), ("cpu", c)):
        for stat, f in (("median", np.median), ("p99", lambda a: np.percentile(a, 99)),
                        ("max", np.max)):
            out[f"loop_{name}_{stat}_ms"] = float(f(v)) if v.size else None
    return out


def controllers(grid: tuple, a: argparse.Namespace) -> None:
    """The controller study (``--controllers``)."""
    import numpy as np

    t0 = time.perf_counter()
    only = {"all": None, "bang-bang": True, "creep": False}[a.cases]
    margins = tuple(float(m) for m in a.margins.split(","))
    rows = controller_study(*grid, period=a.period, noise=a.noise, delay=a.delay,
                            bang_bang=only, estimator=a.estimator, margins=margins,
                            before_landing=rest if a.realtime else None)
    rig = 1e3 * a.period * paper_rig_units().time
    keys = [k for k in rows[0] if k == "exact" or k.startswith("noisy")]
    print(f"sample period {a.period:g} (= {rig:.3g} ms on the paper's rig); noise "
          f"{a.noise:g}, delay {a.delay}, estimator {a.estimator}; {len(rows)} cases in "
          f"{time.perf_counter() - t0:.0f} s")
    print(f"{'v0':>6} {'K':>5} {'c_d':>4} {'clairvoyant':>12} "
          + " ".join(f"{k:>10}" for k in keys) + "  max step ms (wall, CPU)  uncovered")
    for r in rows:
        g, e = r["ground"], r["exact"]
        print(f"{r['v0']:>6.1f} {g.get('stiffness', 1.0):>5.2f} {g.get('c_d', 0.0):>4.1f} "
              f"{r['clairvoyant_depth']:>11.5f}{' ' if r['clairvoyant_bang_bang'] else '~'} "
              + " ".join(_c(r[k]) for k in keys)
              + f"  {e['step_time_max_ms']:.4f}, {e['step_cpu_max_ms']:.4f}"
              + f"  {' '.join(str(r[k]['uncovered']) for k in keys)}")
    print("('~': the clairvoyant optimum is not bang-bang (a creep); '!': a limit broken or "
          "rest not proven)")
    bang = [r for r in rows if r["clairvoyant_bang_bang"]]
    out: dict = {"cases": len(rows), "bang_bang_cases": len(bang)}
    for k in keys:
        wall = np.concatenate([r[k]["step_times_ms"] for r in rows])
        cpu = np.concatenate([r[k]["step_cpu_ms"] for r in rows])
        covered = [r for r in rows if r[k]["uncovered"] == 0]
        cw = np.concatenate([r[k]["step_times_ms"] for r in covered] + [np.zeros(0)])
        out[k] = {
            "feasible": sum(r[k]["feasible"] for r in rows),
            "feasible_bang_bang": sum(r[k]["feasible"] for r in bang),
            "stroke_held": sum(r[k]["stroke_held"] for r in rows),
            "max_ratio_bang_bang": max((r[k]["ratio"] for r in bang), default=None),
            "within_1_percent_bang_bang": sum(r[k]["ratio"] <= 1.01 for r in bang),
            "within_3_percent": sum(r[k]["ratio"] <= 1.03 for r in rows),
            "max_ratio": max(r[k]["ratio"] for r in rows),
            "cases_with_uncovered_samples": len(rows) - len(covered),
            "steps": int(wall.size),
            "wall_median_ms": float(np.median(wall)),
            "wall_p99_ms": float(np.percentile(wall, 99)), "wall_max_ms": float(wall.max()),
            "cpu_median_ms": float(np.median(cpu)),
            "cpu_p99_ms": float(np.percentile(cpu, 99)), "cpu_max_ms": float(cpu.max()),
            "covered_wall_max_ms": float(cw.max()) if cw.size else None,
            **_compiled(rows, k),
            "prepare_s_max": max(r[k]["prepare_time_s"] for r in rows)}
    print(json.dumps(out, indent=1))
    e = out["exact"]
    print(f"goals (exact sensing): within 1 % on every bang-bang case: "
          f"{e['within_1_percent_bang_bang'] == len(bang)}; limits held there: "
          f"{e['feasible_bang_bang'] == len(bang)}; max step <= {rig:.3g} ms wall on covered "
          f"landings: {e['covered_wall_max_ms'] is not None and e['covered_wall_max_ms'] <= rig}"
          f" ({e['covered_wall_max_ms']}); median <= 0.02 ms: {e['wall_median_ms'] <= 0.02}")
    for k in keys:
        n = out[k]
        print(f"compiled controller's own samples ({k}): CPU median / p99 / max "
              f"{n['compiled_cpu_median_ms']:.4f} / {n['compiled_cpu_p99_ms']:.4f} / "
              f"{n['compiled_cpu_max_ms']:.4f} ms, wall max {n['compiled_wall_max_ms']:.4f} "
              f"ms; max CPU <= {rig:.3g} ms: {n['compiled_cpu_max_ms'] <= rig}; deferred "
              f"{n['deferred']}, most integrator steps of a sample {n['step_work_max']}")
        if n["loop_steps"]:
            print(f"  its {n['loop_steps']} compiled calls (an uncovered sample's included) "
                  f"as a control loop (replayed one per period, identical to the bit): wall "
                  f"median / p99 / max "
                  f"{n['loop_wall_median_ms']:.4f} / {n['loop_wall_p99_ms']:.4f} / "
                  f"{n['loop_wall_max_ms']:.4f} ms, CPU {n['loop_cpu_median_ms']:.4f} / "
                  f"{n['loop_cpu_p99_ms']:.4f} / {n['loop_cpu_max_ms']:.4f} ms; median <= "
                  f"0.02 ms: {n['loop_cpu_median_ms'] <= 0.02}; max <= {rig:.3g} ms: "
                  f"{n['loop_wall_max_ms'] <= rig}")
    for k in keys[1:]:
        n = out[k]
        print(f"goals ({k}): every limit held in all {len(rows)} cases: "
              f"{n['feasible'] == len(rows)} ({n['feasible']}); within 3 %: "
              f"{n['within_3_percent'] == len(rows)} ({n['within_3_percent']})")
    if a.json:
        _write_rows(a.json, rows, a.force)


if __name__ == "__main__":
    main()
