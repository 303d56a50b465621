"""Re-solves and mesh refinement (issue 31, items 2 and 3), against rockit and a baseline.

Run:  pip install -e ".[bench]" && python -m benchmarks.bench_resolve [--baseline fc46d09]
      [--repeats 30] [--alp]

1. **Moon lander re-solves** (the suite's ``moon_lander``: multiple shooting N = 20 with
   4 RK4 steps per interval; Radau collocation N = 10, degree 3), interleaved solve by
   solve in one process (CPU time, ``time.process_time``, medians):

   * this toolkit's ``solve(warm_start=sol)`` at its own solution (Ipopt: 1 iteration);
   * this toolkit's ``solve()`` from the default guess;
   * the same with ``expand=False`` (shooting; the default ``"auto"`` re-solves on the
     expanded graph) and with ``codegen=True`` (compiled NLP
     functions, cached on disk: the first run compiles);
   * rockit's re-solve of its built ``Ocp`` from the same guess (the same problem through
     ``benchmarks.ocp_suite``'s translation, same N, scheme and Ipopt options).

   Goals: warm re-solve <= 0.25x rockit's re-solve; re-solve from the guess <= rockit's.

2. **Small builds** (the baseline revision, ``--baseline``, loaded from git into a
   temporary directory and run in fresh processes, alternating with the current tree
   process by process): brachistochrone, Radau N = 5, build + solve, and
   ``refine(tol=1e-6)``; the moon lander, Radau N = 5, build + solve. Goal: no slower
   than the baseline (0.2.0: ``--baseline 95cc625``).

3. **The landing's 41-velocity warm sweep** (``--sweep``): ``sweep_landing`` over
   ``v0 = 0 ... -10`` (41 values, as ``softlanding solve-sweep --n 41``; each solve
   warm-starts the next), CPU of the first sweep in a fresh process (the NLP's build
   included) and of the same sweep repeated there; current and baseline in alternating
   fresh processes. Goal: at least 2x faster than the baseline (the tree the issue measured).

4. **Alp rider** (``--alp``; Betts 2010, pp. 163-165, J* = 2030.85609): Radau from
   N = 20 with ``refine(tol=1e-6)``, CPU per run, current and baseline alternating.
   Goal: <= 5 s CPU.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

SMALL = r"""
import json, sys, time, warnings
import numpy as np
from ocp import Collocation
try:
    from tests.oracles.ocp_suite.problems import brachistochrone, moon_lander
except ImportError:  # a revision before the oracles folder (0.2.0: tests/ocp_suite)
    from tests.ocp_suite.problems import brachistochrone, moon_lander
warnings.simplefilter("ignore")
repeats = int(sys.argv[1])
def one():
    return Collocation(brachistochrone(), intervals=5).solve()
def ref():
    return Collocation(brachistochrone(), intervals=5).refine(tol=1e-6)
def moon():
    return Collocation(moon_lander(), intervals=5).solve()
one(); ref(); moon()  # imports, CasADi's first calls
out = {}
for name, f in (("build_solve", one), ("refine", ref), ("moon_build_solve", moon)):
    ts = []
    for _ in range(repeats):
        c = time.process_time(); s = f(); ts.append(time.process_time() - c)
    out[name] = float(np.median(ts))
    out[name + "_J"] = s.objective
print(json.dumps(out))
"""

ALP = r"""
import json, time, warnings
from ocp import Collocation
from tests.oracles.ocp_suite.alp_rider import alp_rider
warnings.simplefilter("ignore")
c = time.process_time()
sol = Collocation(alp_rider(), intervals=20).refine(tol=1e-6, max_rounds=10)
print(json.dumps({"cpu": time.process_time() - c, "J": sol.objective,
                  "rounds": len(sol.mesh_history), "N": int(sol.N),
                  "iterations": [r.iterations for r in sol.mesh_history],
                  "converged": bool(sol.mesh_converged)}))
"""


SWEEP = r"""
import json, time, warnings
import numpy as np
warnings.simplefilter("ignore")
from softlanding.optimal.landing import sweep_landing
v = np.linspace(0.0, -10.0, 41)
out = {}
for key in ("first", "again", "transcribed"):
    c = time.process_time(); w = time.perf_counter()
    res = sweep_landing(v, refine=key != "transcribed")
    out[key], out[key + "_wall"] = time.process_time() - c, time.perf_counter() - w
    if key == "again":
        out["depth"] = [r.depth for r in res]
        out["paths"] = [getattr(r, "path", "") for r in res]
out["depth_transcribed"] = [r.depth for r in res]
print(json.dumps(out))
"""


def baseline_tree(rev: str) -> Path:
    """The baseline's ``ocp``, ``softlanding`` and ``tests`` in a temporary directory
    (``git archive``)."""
    tmp = Path(tempfile.mkdtemp(prefix="ocp_baseline_"))
    arch = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "ocp", "softlanding",
                           "tests"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=arch, check=True)
    alp = "tests/oracles/ocp_suite/alp_rider.py"  # the problem, if the baseline lacks it
    if (tmp / alp).parent.is_dir() and not (tmp / alp).exists():
        (tmp / alp).write_text((ROOT / alp).read_text())
    return tmp


def child(tree: Path, code: str, *args: str) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", code, *args], cwd=tree, env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def alternate(base: Path, code: str, runs: int, *args: str) -> tuple[list, list]:
    """Fresh processes, baseline and current alternating (the other first every second)."""
    old, new = [], []
    for k in range(runs):
        order = [(base, old), (ROOT, new)][:: 1 if k % 2 == 0 else -1]
        for tree, acc in order:
            acc.append(child(tree, code, *args))
    return old, new


# ------------------------------------------------------------------ moon lander
def rockit_moon(method: str) -> Any:
    from rockit import DirectCollocation, MultipleShooting

    from benchmarks.ocp_suite import rockit_problem
    from tests.oracles.ocp_suite.problems import moon_lander

    N = 20 if method == "ms" else 10
    ocp, _ = rockit_problem(moon_lander(), N, 3)
    ocp.method(MultipleShooting(N=N, M=4, intg="rk") if method == "ms"
               else DirectCollocation(N=N, degree=3, scheme="radau"))
    ocp.solve()  # build (transcription) and first solve
    return ocp


def moon(repeats: int) -> None:
    from ocp import Collocation, MultipleShooting
    from tests.oracles.ocp_suite.problems import moon_lander

    for method in ("ms", "radau"):
        tr = MultipleShooting(moon_lander(), nodes=20) if method == "ms" else \
            Collocation(moon_lander(), intervals=10)
        sol = tr.solve()
        ocp = rockit_moon(method)
        fns = {"warm": lambda tr=tr, sol=sol: tr.solve(warm_start=sol),
               "guess": tr.solve, "rockit": ocp.solve}
        if method == "ms":  # the default expand="auto" re-solves expanded; before: not
            trx = MultipleShooting(moon_lander(), nodes=20, expand=False)
            trx.solve()
            fns["unexpanded"] = trx.solve
        # compiled NLP functions (opt-in; the first solve compiles unless cached on disk)
        trc = MultipleShooting(moon_lander(), nodes=20, codegen=True) if method == "ms" else \
            Collocation(moon_lander(), intervals=10, codegen=True)
        c = time.perf_counter()
        trc.solve()
        first_codegen = time.perf_counter() - c
        fns["codegen"] = trc.solve
        runs: dict[str, list[float]] = {k: [] for k in fns}
        iters: dict[str, int] = {}
        for k in range(repeats):
            names = list(fns) if k % 2 == 0 else list(fns)[::-1]
            for name in names:
                c = time.process_time()
                out = fns[name]()
                runs[name].append(time.process_time() - c)
                iters[name] = (int(out.stats["iter_count"]) if name == "rockit"
                               else out.iterations)
        med = {k: statistics.median(v) * 1e3 for k, v in runs.items()}
        J = float(ocp._method.opti.debug.value(ocp._method.opti.f))
        label = "multiple shooting N = 20" if method == "ms" else "Radau N = 10, degree 3"
        print(f"moon lander, {label}: CPU ms per solve (median of {repeats}), iterations")
        for name, what in (("warm", "toolkit solve(warm_start=sol)"),
                           ("guess", "toolkit solve() from the guess"),
                           ("unexpanded", "the same, expand=False"),
                           ("codegen", "the same, codegen=True"),
                           ("rockit", "rockit re-solve from the guess")):
            if name in med:
                print(f"  {what:34s} {med[name]:7.3f} ms  {iters[name]:3d} it")
        extra = (f", unexpanded / rockit {med['unexpanded'] / med['rockit']:.2f}"
                 if "unexpanded" in med else "")
        extra += (f", codegen / rockit {med['codegen'] / med['rockit']:.2f} (its first solve "
                  f"{first_codegen:.1f} s wall, compile or cache load included)")
        print(f"  ratio warm / rockit {med['warm'] / med['rockit']:.2f} (goal <= 0.25); "
              f"guess / rockit {med['guess'] / med['rockit']:.2f} (goal <= 1){extra}; "
              f"objective {sol.objective:.10f}, rockit {J:.10f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", default="fc46d09")
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--processes", type=int, default=3, help="fresh processes per tree")
    ap.add_argument("--alp", action="store_true", help="also the alp rider (minutes)")
    ap.add_argument("--sweep", action="store_true",
                    help="also the landing's 41-velocity warm sweep")
    ap.add_argument("--skip-moon", action="store_true")
    ap.add_argument("--skip-small", action="store_true")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()}; {os.cpu_count()} cores")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if not args.skip_moon:
            moon(args.repeats)
    base = baseline_tree(args.baseline)
    try:
        baseline_runs(base, args)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    print(f"load average {os.getloadavg()}")


def baseline_runs(base: Path, args: Any) -> None:
    """The brachistochrone and alp rider runs against the baseline tree ``base``."""
    if not args.skip_small:
        small(base, args)
    if args.sweep:
        sweep(base, args)
    if args.alp:
        old, new = alternate(base, ALP, 1)
        for who, r in (("baseline", old[0]), ("now", new[0])):
            print(f"alp rider, refine(1e-6) from N = 20, {who}: {r['cpu']:.2f} s CPU, "
                  f"J = {r['J']:.8f} (published 2030.85609), {r['rounds']} rounds, final "
                  f"N = {r['N']}, iterations {r['iterations']}, converged {r['converged']}")


def sweep(base: Path, args: Any) -> None:
    """The landing's 41-velocity sweep, baseline and current in alternating processes."""
    old, new = alternate(base, SWEEP, args.processes)
    print(f"landing, sweep_landing over 41 v0 in [-10, 0] (CPU s per sweep, "
          f"{args.processes} fresh processes each, alternating): baseline {args.baseline} / now")
    for key, what in (("first", "first sweep (build included)"),
                      ("again", "the sweep repeated"),
                      ("transcribed", "transcribed (refine=False)")):
        a, b = [r[key] for r in old], [r[key] for r in new]
        print(f"  {what:30s} {' '.join(f'{x:6.3f}' for x in a)} / "
              f"{' '.join(f'{x:6.3f}' for x in b)}; ratio of medians "
              f"{statistics.median(b) / statistics.median(a):.2f} (goal <= 0.5)")
    da, db = np.array(old[0]["depth"]), np.array(new[0]["depth"])
    ta, tb = np.array(old[0]["depth_transcribed"]), np.array(new[0]["depth_transcribed"])
    print(f"  largest depth difference {np.max(np.abs(da - db)):.2e} (transcribed "
          f"{np.max(np.abs(ta - tb)):.2e}); paths now "
          f"{dict(zip(*np.unique(new[0]['paths'], return_counts=True), strict=True))}")


def small(base: Path, args: Any) -> None:
    """Brachistochrone builds, baseline and current in alternating fresh processes."""
    old, new = alternate(base, SMALL, args.processes, str(max(3, args.repeats // 4)))
    print(f"brachistochrone (build_solve, refine) and moon lander (moon_build_solve), Radau "
          f"N = 5 (median CPU per process, {args.processes} processes each, alternating): "
          f"baseline {args.baseline} / now")
    for key in ("build_solve", "refine", "moon_build_solve"):
        a = [r[key] * 1e3 for r in old]
        b = [r[key] * 1e3 for r in new]
        print(f"  {key:16s} {' '.join(f'{v:6.1f}' for v in a)} ms / "
              f"{' '.join(f'{v:6.1f}' for v in b)} ms; ratio of medians "
              f"{statistics.median(b) / statistics.median(a):.2f}; objectives "
              f"{old[0][key + '_J']:.12g} / {new[0][key + '_J']:.12g}")


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    main()
