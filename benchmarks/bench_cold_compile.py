"""Where a cold numba cache's compile CPU goes: the kernels the fast tests compile, each
function's compile CPU, against a baseline tree.

Run:  python -m benchmarks.bench_cold_compile --baseline-tree DIR [--repeats 1] [--top 15]

Each run is a fresh process (this file's ``--child``) with an empty ``NUMBA_CACHE_DIR`` and
``XDG_CACHE_HOME`` of its own and the tree first on the path, which compiles what the fast
tests' first calls compile: the demo's table (the lite landing loop), one compiled-controller
landing with the filtered estimate (noise 1e-3, one sample of delay), one drag-ground landing
and its trajectory, an affine and a non-affine batch. It records numba's compile events: each
function's CPU exclusive of the functions compiled inside it, its signatures (two for one
function is a second compile of it) and the CPU of each stage. The trees alternate run by run
(``DIR``, e.g. ``git archive main | tar -x -C DIR``); the depths both print must agree.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def child() -> None:
    """The cold stages, in this process, with numba's compile events recorded; JSON on stdout."""
    from numba.core import event

    stack: list[list] = []
    rec: dict[str, dict] = {}

    class Listener(event.Listener):
        def on_start(self, e):
            stack.append([time.process_time(), 0.0])

        def on_end(self, e):
            t0, inner = stack.pop()
            dt = time.process_time() - t0
            if stack:
                stack[-1][1] += dt
            py = e.data["dispatcher"].py_func
            r = rec.setdefault(f"{py.__module__}.{py.__qualname__}", {"cpu": 0.0, "sigs": []})
            r["cpu"] += dt - inner
            if str(e.data["args"]) not in r["sigs"]:
                r["sigs"].append(str(e.data["args"]))

    event.register("numba:compile", Listener())
    stages, depths = {}, {}
    t = time.process_time()
    for name, run in _stages():
        depths[name] = run()
        stages[name], t = time.process_time() - t, time.process_time()
    print(json.dumps({"stages": stages, "depths": depths, "functions": rec}))


def _stages():
    import numpy as np

    from softlanding.control import mpc_landing
    from softlanding.model.controllers import Impedance
    from softlanding.model.ground import DragGround
    from softlanding.model.robot import PAPER_ROBOT, Impact
    from softlanding.report.demo import demo_table
    from softlanding.simulation.simulator import simulate, simulate_batch

    def drag():
        r = simulate(PAPER_ROBOT, Impact(-3.0), Impedance(0.5, 0.5), DragGround(0.4))
        return float(np.sum(r.trajectory(n=20).x)) + r.depth

    v = np.linspace(-5.0, -1.0, 64)
    return [("demo", lambda: demo_table()[-1]["impedance_depth"]),
            ("controller", lambda: mpc_landing(-3.0, noise=1e-3, delay=1).depth),
            ("drag ground", drag),
            ("batch", lambda: float(simulate_batch(PAPER_ROBOT, v, 0.5, 0.5,
                                                   progress=False).depth.sum())),
            ("drag batch", lambda: float(simulate_batch(PAPER_ROBOT, v, 0.5, 0.5,
                                                        DragGround(0.4),
                                                        progress=False).depth.sum()))]


def run(tree: Path, tmp: Path) -> tuple[float, dict]:
    """Process CPU (user + system, from outside) and the child's record of one cold run."""
    cache = Path(tempfile.mkdtemp(dir=tmp))
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=str(cache / "numba"),
               XDG_CACHE_HOME=str(cache))
    before = os.times()
    p = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child"], env=env,
                       cwd=tree, capture_output=True, text=True, check=True)
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system
                                                          - before.children_system)
    return cpu, json.loads(p.stdout.splitlines()[-1])


def report(rows: dict[str, list[tuple[float, dict]]], top: int) -> None:
    """Medians per tree and stage, the ratio, and the costliest functions of each tree."""
    med = {k: statistics.median(c for c, _ in v) for k, v in rows.items()}
    for key, runs in rows.items():
        comp = statistics.median(sum(f["cpu"] for f in r["functions"].values()) for _, r in runs)
        stages = {s: statistics.median(r["stages"][s] for _, r in runs) for s in
                  runs[0][1]["stages"]}
        print(f"{key}: process {med[key]:.1f} s CPU, compile {comp:.1f} s; stages "
              + ", ".join(f"{s} {c:.1f}" for s, c in stages.items()))
        funcs = runs[0][1]["functions"]
        print(f"  {len(funcs)} functions, {sum(len(f['sigs']) for f in funcs.values())} "
              "signatures; costliest (own compile CPU, signatures):")
        for name, f in sorted(funcs.items(), key=lambda kv: -kv[1]["cpu"])[:top]:
            print(f"    {f['cpu']:6.2f} s  {len(f['sigs'])}  {name}")
    if "base" in med:
        print(f"ratio now/base process CPU {med['now'] / med['base']:.2f}")
    depths = {json.dumps(r["depths"]) for v in rows.values() for _, r in v}
    print(f"depths of all runs: {'identical' if len(depths) == 1 else 'DIFFERENT'}")


def main() -> None:
    if "--child" in sys.argv:
        return child()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline-tree", type=Path, help="source tree to compare against")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--top", type=int, default=15)
    args = ap.parse_args()
    trees = {"now": ROOT}
    if args.baseline_tree:
        trees = {"base": args.baseline_tree.resolve(), "now": ROOT}
        print(f"base = {trees['base']}, now = this tree ({ROOT})")
    rows: dict[str, list] = {k: [] for k in trees}
    with tempfile.TemporaryDirectory(prefix="bench-cold-compile-") as tmp:
        for r in range(args.repeats):
            for key in (list(trees) if r % 2 == 0 else list(trees)[::-1]):
                rows[key].append(run(trees[key], Path(tmp)))
                print(f"{key:5s} cold cpu {rows[key][-1][0]:6.2f} s", flush=True)
    report(rows, args.top)


if __name__ == "__main__":
    main()
