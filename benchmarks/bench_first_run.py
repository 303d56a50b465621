"""A new user's first ``softlanding demo``: compile on an empty numba cache, then cached.

Run:  python -m benchmarks.bench_first_run [--baseline REV | --baseline-tree DIR | --no-baseline]
      [--repeats 3] [--cold-only]

Each run is a fresh process of ``softlanding demo --out FILE.png`` timed from outside
(``resource.getrusage`` of the child: user + system CPU, and wall time). A cold run gets an
empty ``NUMBA_CACHE_DIR`` and an empty ``XDG_CACHE_HOME`` (the compiled ground laws) of its
own, as a fresh install has; a cached run reuses the caches of a cold run after a landing
script (untimed, :data:`WARM`) has compiled the demo's landings, as any earlier command does
(a cold demo runs the simulator as Python since issue 47 and leaves the cache empty). With
``--baseline REV`` the revision ``REV`` is checked out into a temporary git worktree (with
``--baseline-tree DIR``, a source tree already there, e.g. ``git archive main | tar -x -C
DIR``) and the two trees alternate run by run (the other one first every second repeat), so
a drift of the shared machine's load falls on both; the medians' ratio now / baseline is
printed. The tables printed by both must agree. The default baseline is 4695ed7, the tree
issue 47 measured (22.4-24.7 s CPU cold; goal <= 15 s); ``--cold-only`` skips the cached
runs.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = "4695ed7"
"""The tree issue 47 measured the first demo on."""


def run_demo(tree: Path, cache: Path, out: Path) -> tuple[float, float, str, str]:
    """CPU and wall seconds, stdout and stderr of one ``softlanding demo`` with ``tree`` first
    on the path, numba's cache in ``cache / "numba"`` and the user cache in ``cache``."""
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=str(cache / "numba"),
               XDG_CACHE_HOME=str(cache))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "softlanding", "demo", "--out", str(out),
                        "--force"], env=env, cwd=tree, capture_output=True, text=True,
                       check=True)
    wall = time.perf_counter() - wall
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, p.stdout, p.stderr


WARM = ("from softlanding.report.demo import demo_table, stepped_intrusions\n"
        "demo_table(); [r.trajectory() for r in stepped_intrusions()]")
"""The demo's landings, compiled: what an earlier command leaves in the cache."""


def warm_up(tree: Path, cache: Path) -> None:
    """Compile the demo's landings into ``cache`` (a separate, untimed process)."""
    env = dict(os.environ, PYTHONPATH=str(tree), NUMBA_CACHE_DIR=str(cache / "numba"),
               XDG_CACHE_HOME=str(cache))
    subprocess.run([sys.executable, "-c", WARM], env=env, cwd=tree, capture_output=True,
                   check=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    base = ap.add_mutually_exclusive_group()
    base.add_argument("--baseline", default=BASELINE,
                      help=f"git revision to compare against (default: {BASELINE})")
    base.add_argument("--baseline-tree", type=Path,
                      help="source tree to compare against (instead of a revision)")
    base.add_argument("--no-baseline", action="store_true", help="this tree alone")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cold-only", action="store_true", help="no cached runs")
    args = ap.parse_args()
    if args.no_baseline or args.baseline_tree:
        args.baseline = None
    with tempfile.TemporaryDirectory(prefix="bench-first-run-") as tmp:
        trees = {"now": ROOT}
        if args.baseline_tree:
            trees = {"base": args.baseline_tree.resolve(), "now": ROOT}
        elif args.baseline:
            trees = {"base": Path(tmp) / "baseline", "now": ROOT}
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q",
                            str(trees["base"]), args.baseline], check=True)
        try:
            kinds = ("cold",) if args.cold_only else ("cold", "cached")
            rows: dict[str, dict[str, list]] = {k: {kind: [] for kind in kinds} for k in trees}
            tables: dict[str, set[str]] = {k: set() for k in trees}
            for r in range(args.repeats):
                order = list(trees) if r % 2 == 0 else list(trees)[::-1]
                for key in order:
                    cache = Path(tmp) / f"cache-{key}-{r}"
                    cache.mkdir()
                    png = Path(tmp) / f"demo-{key}.png"
                    cpu, wall, out, err = run_demo(trees[key], cache, png)
                    rows[key]["cold"].append((cpu, wall))
                    tables[key].add("\n".join(line for line in out.splitlines()
                                              if not line.startswith("figure written")))
                    print(f"{key:5s} cold   cpu {cpu:6.2f} s  wall {wall:6.2f} s  "
                          f"stderr {err.strip()!r}", flush=True)
                    if args.cold_only:
                        continue
                    warm_up(trees[key], cache)
                    cpu, wall, out, err = run_demo(trees[key], cache, png)
                    rows[key]["cached"].append((cpu, wall))
                    print(f"{key:5s} cached cpu {cpu:6.2f} s  wall {wall:6.2f} s  "
                          f"stderr {err.strip()!r}", flush=True)
            print(f"medians of {args.repeats} ({os.cpu_count()} cores, load average "
                  f"{os.getloadavg()[0]:.1f})")
            med = {(key, kind, i): statistics.median(x[i] for x in xs)
                   for key, kinds in rows.items() for kind, xs in kinds.items() for i in (0, 1)}
            for key, kinds in rows.items():
                for kind, xs in kinds.items():
                    print(f"  {key:5s} {kind:6s} cpu {med[key, kind, 0]:6.2f} s"
                          f"  wall {med[key, kind, 1]:6.2f} s  (least cpu "
                          f"{min(x[0] for x in xs):6.2f} s)")
            if "base" in trees:
                named = args.baseline or str(trees["base"])
                print(f"  base = {named}, now = this tree ({ROOT})")
                for kind in kinds:
                    print(f"  ratio now/base {kind:6s} cpu "
                          f"{med['now', kind, 0] / med['base', kind, 0]:.2f}  wall "
                          f"{med['now', kind, 1] / med['base', kind, 1]:.2f}")
            same = len(set().union(*tables.values())) == 1
            print(f"demo tables of all runs: {'identical' if same else 'DIFFERENT'}")
        finally:
            if args.baseline:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                                str(trees["base"])], check=False)


if __name__ == "__main__":
    main()
