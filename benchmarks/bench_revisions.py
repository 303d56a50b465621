"""Two revisions of this toolkit on the same workloads, interleaved.

Run:  python -m benchmarks.bench_revisions --baseline REV [--repeats 3] [names...]
      python -m benchmarks.bench_revisions --baseline REV --workload WORKLOAD
      (WORKLOAD: simulator, landing, stiffness, impedance, infeasible, work, startup, hop
      or unknown)

``--workload simulator`` times the exact simulator (bench_simulator's workloads: one batch
over a 150 x 150 gain grid on all cores, and 300 single landings with random gains and impact
velocities); ``--workload landing`` times the landing OCP end to end (bench_ocp's "toolkit
solve_landing (sweep)": a cold ``solve_landing`` at v0 = -3, then ``sweep_landing`` over 20
velocities in [-10, -0.5]). Both revisions must return the same numbers (a checksum of every
depth, printed); each child runs once untimed first (numba's cache, CasADi's code generation).
``--workload stiffness`` times the simulator on the ground ``LinearGround(2.0)``: a 101 x 101
gain map on all cores and 300 runs of one landing (integrated before the kernel took ``K``,
exact after: the checksums then agree to the integrator's tolerance, not bit for bit).
``--workload impedance`` times ``optimize_impedance`` at v0 = -3 on the paper's ground and at
-4.8 on ``DragGround(0.2)`` (the depths agree to about 1e-12 across a change of its search).
``--workload infeasible`` times the diagnosis of an infeasible request: ``solve_landing`` at
v0 = -10 with ``u_max = 2`` (the failed solve, then one relaxed solve per condition), first in
the process and again (the checksum is of the two messages' characters).
``--workload work`` times the actuator's positive and negative work along exact simulations
(:func:`softlanding.simulation.actuator_work.result_work`, the hop cycle's independent energy
check): 60 impedance landings with random gains, grounds and velocities plus 20 push/pull
schedules, then the replayed work of the hop at v0 = -2 (one start, one grid, the solve
itself untimed; the checksum is of every work). ``--workload startup`` times what a fresh
process pays before its first landing: importing the landing solve's modules, then that
import and ``solve_landing(-3)`` together (the checksum is the depth). ``--workload hop``
times ``best_impedance_hop(-3)`` and ``solve_hop(-2, doublings=1)``. ``--workload unknown``
times the unknown-ground study's 15 clairvoyant optima at v0 = -10 (one landing OCP per
ground, or per ground family) and the impedance tuned for the worst case over four of its
grounds at v0 = -3 (the checksum: the depths' sum and the worst case's value).

Answers "is anything slower than before?" for a change to ``ocp``: the baseline
revision ``REV`` (a commit, tag or branch) is checked out into a temporary git
worktree, and every problem of ``tests/ocp_suite`` that both revisions know is
solved by each revision in turn, in fresh processes, alternating baseline and
current run by run (and starting with the other one every second repeat), so that
a drift of the shared machine's load falls on both. Each run times, inside the
process after its imports, the whole collocation refinement (``Collocation.refine``
to the problem's tolerance) and one solve on the final mesh, in wall and CPU time
(``time.process_time``). The table gives medians and the ratio current / baseline
(below 1: faster now), and the objectives of both, which must agree.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time, warnings
try:
    from tests.oracles.ocp_suite import PROBLEMS
except ImportError:  # a revision before the tests were packages
    from ocp_suite import PROBLEMS
from ocp import Collocation
sp = {p.name: p for p in PROBLEMS}[sys.argv[1]]
extra = json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
guess = sp.guess() if sp.guess else None
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    w, c = time.perf_counter(), time.process_time()
    sol = Collocation(sp.build(), intervals=sp.intervals, degree=sp.degree).refine(
        tol=sp.tol, max_rounds=sp.max_rounds, guess=guess, **extra)
    rw, rc = time.perf_counter() - w, time.process_time() - c
    meshes = [ph.discretization.tau for ph in sol.phases]
    tr = Collocation(sp.build(), mesh=meshes, degree=sp.degree, verify="off")
    w, c = time.perf_counter(), time.process_time()
    one = tr.solve(guess=guess)
    sw, sc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"refine": rw, "refine_cpu": rc, "solve": sw, "solve_cpu": sc,
                  "value": sp.value(sol), "rounds": len(sol.mesh_history),
                  "ok": bool(sol.success and one.success)}))
"""

NAMES = r"""
import json
try:
    from tests.oracles.ocp_suite import PROBLEMS
except ImportError:
    from ocp_suite import PROBLEMS
print(json.dumps([p.name for p in PROBLEMS]))
"""


SIMULATOR = r"""
import json, time
import numpy as np
from softlanding import Impact, Impedance, Robot, simulate, simulate_batch
robot = Robot(5, 20)
kp, kd = np.linspace(0.05, 1.0, 150)[:, None], np.linspace(0.05, 1.0, 150)
simulate_batch(robot, -3.0, k_p=kp[:2], k_d=kd[:2])  # load the compiled kernel
simulate(robot, Impact(-1.0), Impedance(0.2, 0.18))
w, c = time.perf_counter(), time.process_time()
grid = simulate_batch(robot, -3.0, k_p=kp, k_d=kd)
bw, bc = time.perf_counter() - w, time.process_time() - c
rng = np.random.default_rng(1)
cases = [(-rng.uniform(0.5, 5.0), rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0))
         for _ in range(300)]
w, c = time.perf_counter(), time.process_time()
depths = [simulate(robot, Impact(v), Impedance(p, d)).depth for v, p, d in cases]
sw, sc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": bw, "batch_cpu": bc, "single": sw, "single_cpu": sc,
                  "check": float(np.nansum(grid.depth)) + float(np.nansum(depths))}))
"""

LANDING = r"""
import json, time
import numpy as np
try:
    from softlanding import PAPER_ROBOT, solve_landing, sweep_landing
except ImportError:  # before 0.3.0
    from softlanding import PAPER_ROBOT
    from softlanding.landing import solve_landing, sweep_landing
w, c = time.perf_counter(), time.process_time()
one = solve_landing(-3.0, PAPER_ROBOT)
ow, oc = time.perf_counter() - w, time.process_time() - c
w, c = time.perf_counter(), time.process_time()
sweep = sweep_landing(np.linspace(-0.5, -10.0, 20), PAPER_ROBOT)
sw, sc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": ow, "batch_cpu": oc, "single": sw, "single_cpu": sc,
                  "check": one.depth + sum(s.depth for s in sweep)}))
"""

STIFFNESS = r"""
import json, time
import numpy as np
from softlanding import Impact, Impedance, Robot, simulate, simulate_batch
from softlanding.model.ground import LinearGround
robot, ground = Robot(5, 20), LinearGround(2.0)
kp, kd = np.linspace(0.05, 1.0, 101)[:, None], np.linspace(0.05, 1.0, 101)
simulate_batch(robot, -3.0, k_p=kp[:2], k_d=kd[:2], ground=ground)  # load the compiled kernel
simulate(robot, Impact(-1.0), Impedance(0.2, 0.18), ground)
w, c = time.perf_counter(), time.process_time()
grid = simulate_batch(robot, -3.0, k_p=kp, k_d=kd, ground=ground)
bw, bc = time.perf_counter() - w, time.process_time() - c
w, c = time.perf_counter(), time.process_time()
depths = [simulate(robot, Impact(-3.0), Impedance(0.2, 0.18), ground).depth
          for _ in range(300)]
sw, sc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": bw, "batch_cpu": bc, "single": sw, "single_cpu": sc,
                  "check": float(np.nansum(grid.depth)) + float(np.nansum(depths))}))
"""

IMPEDANCE = r"""
import json, time
from softlanding import optimize_impedance, simulate_batch, PAPER_IMPEDANCE_ROBOT
from softlanding.model.ground import DragGround
simulate_batch(PAPER_IMPEDANCE_ROBOT, -3.0, k_p=[0.2], k_d=[0.2])  # load the compiled kernels
simulate_batch(PAPER_IMPEDANCE_ROBOT, -3.0, k_p=[0.2], k_d=[0.2], ground=DragGround(0.2))
w, c = time.perf_counter(), time.process_time()
one = optimize_impedance(-3.0)
ow, oc = time.perf_counter() - w, time.process_time() - c
w, c = time.perf_counter(), time.process_time()
drag = optimize_impedance(-4.8, ground=DragGround(0.2))
dw, dc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": ow, "batch_cpu": oc, "single": dw, "single_cpu": dc,
                  "check": one.depth + drag.depth}))
"""

INFEASIBLE = r"""
import json, time
from softlanding import PAPER_ROBOT, solve_landing
from softlanding.errors import InfeasibleLandingError


def diagnose():
    try:
        solve_landing(-10.0, PAPER_ROBOT.replace(u_max=2.0), replay=False)
    except InfeasibleLandingError as err:
        return str(err)
    raise SystemExit("the request was feasible")


w, c = time.perf_counter(), time.process_time()
first = diagnose()
fw, fc = time.perf_counter() - w, time.process_time() - c
w, c = time.perf_counter(), time.process_time()
again = diagnose()
aw, ac = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": fw, "batch_cpu": fc, "single": aw, "single_cpu": ac,
                  "check": float(sum(map(ord, first + again)))}))
"""

WORK = r"""
import json, time
import numpy as np
from softlanding import PAPER_ROBOT, simulate
from softlanding.model.controllers import ForceSchedule, Impedance
from softlanding.model.ground import LinearGround
from softlanding.simulation.actuator_work import result_work
import softlanding.optimal.hopping as hopping
rng = np.random.default_rng(1)
runs = []
for i in range(60):
    v0, kp, kd = -rng.uniform(0.5, 10), rng.uniform(0.01, 2), rng.uniform(0.01, 2)
    robot = PAPER_ROBOT.replace(u_max=None) if i % 2 else PAPER_ROBOT
    runs.append(simulate(robot, v0, Impedance(kp, kd), LinearGround(rng.uniform(0.3, 3)),
                         t_max=20))
for i in range(20):
    t1 = rng.uniform(0.05, 0.5)
    t2 = t1 + rng.uniform(0.05, 0.5)
    runs.append(simulate(PAPER_ROBOT, -3, ForceSchedule((t1, t2), (8.2, -8.2, 0.0)),
                         t_max=3))
w, c = time.perf_counter(), time.process_time()
works = [result_work(r, float(r.segments["t"][-1])) for r in runs]
lw, lc = time.perf_counter() - w, time.process_time() - c
replays = []  # the hop's replays, as its solve evaluates them (the solve untimed)
evaluate = hopping.evaluate_replay
hopping.evaluate_replay = lambda *a: replays.append((a[4], a[5])) or evaluate(*a)
hopping.HOP_STARTS = hopping.HOP_STARTS[:1]
hopping.solve_hop(-2.0, PAPER_ROBOT, eta=0.0, refine=False)
w, c = time.perf_counter(), time.process_time()
works += [result_work(res, t) for res, t in replays]
hw, hc = time.perf_counter() - w, time.process_time() - c
print(json.dumps({"batch": lw, "batch_cpu": lc, "single": hw, "single_cpu": hc,
                  "check": float(sum(x.positive + 2 * x.negative for x in works))}))
"""

STARTUP = r"""
import json, time
w, c = time.perf_counter(), time.process_time()
import softlanding.optimal.landing, softlanding.simulation.simulator  # noqa: E401
iw, ic = time.perf_counter() - w, time.process_time() - c
from softlanding import solve_landing
one = solve_landing(-3.0)
print(json.dumps({"batch": iw, "batch_cpu": ic, "single": time.perf_counter() - w,
                  "single_cpu": time.process_time() - c, "check": one.depth}))
"""

HOP = r"""
import json, time
from softlanding.optimal.hopping import best_impedance_hop, solve_hop
w, c = time.perf_counter(), time.process_time()
imp = best_impedance_hop(-3.0)
iw, ic = time.perf_counter() - w, time.process_time() - c
w, c = time.perf_counter(), time.process_time()
free = solve_hop(-2.0, doublings=1)
print(json.dumps({"batch": iw, "batch_cpu": ic, "single": time.perf_counter() - w,
                  "single_cpu": time.process_time() - c, "check": imp.energy + free.energy}))
"""

UNKNOWN = r"""
import itertools, json, time
from softlanding import PAPER_ROBOT, solve_landing
from softlanding.studies.impedance import optimize_impedance
from softlanding.studies.unknown_ground import STUDY_DRAG, STUDY_STIFFNESS, true_ground
solve_landing(-3.0)  # (the process's first landing: imports and the paper's NLP, untimed)
grounds = [true_ground(k, c) for k, c in itertools.product(STUDY_STIFFNESS, STUDY_DRAG)]
w, c = time.perf_counter(), time.process_time()
clair = [solve_landing(-10.0, PAPER_ROBOT, g) for g in grounds]
cw, cc = time.perf_counter() - w, time.process_time() - c
four = [true_ground(k, d) for k in (0.5, 2.0) for d in (0.0, 1.0)]
w, c = time.perf_counter(), time.process_time()
worst = optimize_impedance(-3.0, PAPER_ROBOT, four, grid=41)
print(json.dumps({"batch": cw, "batch_cpu": cc, "single": time.perf_counter() - w,
                  "single_cpu": time.process_time() - c,
                  "check": sum(r.depth for r in clair) + worst.value}))
"""

WORKLOADS = {"simulator": (SIMULATOR, "batch 150x150", "300 single"),
             "landing": (LANDING, "cold solve", "sweep of 20"),
             "stiffness": (STIFFNESS, "batch 101x101", "300 x one"),
             "impedance": (IMPEDANCE, "optimum -3", "drag 0.2 -4.8"),
             "infeasible": (INFEASIBLE, "first request", "again"),
             "work": (WORK, "80 landings", "hop replay"),
             "startup": (STARTUP, "imports", "first solve"),
             "hop": (HOP, "impedance -3", "free hop -2"),
             "unknown": (UNKNOWN, "15 grounds -10", "worst case -3")}


def compare_workload(base: Path, workload: str, repeats: int) -> None:
    """Time one workload on both trees, alternating, and print medians and ratios."""
    code, first, second = WORKLOADS[workload]
    for tree in (base, ROOT):  # untimed: compile and cache
        run_in(tree, code)
    rows: dict[str, list[dict]] = {"base": [], "now": []}
    for k in range(repeats):
        order = [("base", base), ("now", ROOT)]
        for key, tree in order if k % 2 == 0 else order[::-1]:
            rows[key].append(run_in(tree, code))  # type: ignore[arg-type]
    print(f"{workload}: medians of {repeats} interleaved runs in fresh processes; "
          f"ratio = current / baseline (below 1: faster now)")
    print(f"{'':10s} {'wall base':>10s} {'wall now':>9s} {'ratio':>6s} | {'cpu base':>9s} "
          f"{'cpu now':>8s} {'ratio':>6s}")
    for field, label in (("batch", first), ("single", second)):
        b = statistics.median(r[field] for r in rows["base"])
        n = statistics.median(r[field] for r in rows["now"])
        bc = statistics.median(r[field + "_cpu"] for r in rows["base"])
        nc = statistics.median(r[field + "_cpu"] for r in rows["now"])
        print(f"{label:14s} {b:6.3f} s {n:7.3f} s {n / b:6.2f} | {bc:7.3f} s {nc:6.3f} s "
              f"{nc / bc:6.2f}")
    checks = {key: {r["check"] for r in rs} for key, rs in rows.items()}
    same = checks["base"] == checks["now"] and len(checks["now"]) == 1
    print(f"checksum of every depth: baseline {sorted(checks['base'])}, now "
          f"{sorted(checks['now'])}: {'identical' if same else 'DIFFERENT'}")
    if not same:  # e.g. a workload moved from the integrated path to the exact one
        b, n = min(checks["base"]), min(checks["now"])
        print(f"relative difference of the checksums: {abs(n - b) / abs(b):.1e}")


def run_in(tree: Path, code: str, *args: str) -> dict | list:
    """Run ``code`` with ``tree``'s ``ocp`` and ``tests`` first on the path; its JSON."""
    env = dict(os.environ, PYTHONPATH=f"{tree}{os.pathsep}{tree / 'tests'}")
    out = subprocess.run([sys.executable, "-c", code, *args], env=env, cwd=tree,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, help="git revision to compare against")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--current-refine", default="{}", metavar="JSON",
                    help='extra keyword arguments of the current revision\'s refine, e.g. '
                         '\'{"objective_tol": Infinity}\' for the baseline\'s stopping rule')
    ap.add_argument("--workload", choices=["suite", *WORKLOADS], default="suite",
                    help="suite: the published problems (default); simulator: the exact "
                         "simulator; stiffness: the simulator on LinearGround(2.0); landing: "
                         "the landing OCP end to end; impedance: optimize_impedance on the "
                         "paper's ground and a drag ground; infeasible: the diagnosis of an "
                         "infeasible landing request; work: the actuator's work along exact "
                         "landings and a hop's replay; startup: a fresh process's imports and "
                         "first landing solve; hop: best_impedance_hop(-3) and solve_hop(-2, "
                         "doublings=1) with its exact arcs")
    ap.add_argument("names", nargs="*", help="problems (default: all that both revisions have)")
    args = ap.parse_args()
    if args.repeats < 1:
        ap.error("--repeats must be at least 1")
    try:
        json.loads(args.current_refine)
    except ValueError as err:
        ap.error(f"--current-refine is not JSON: {err}")
    with tempfile.TemporaryDirectory(prefix="bench-rev-") as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base),
                        args.baseline], check=True)
        try:
            if args.workload != "suite":
                if args.names or args.current_refine != "{}":
                    ap.error("problem names and --current-refine apply to --workload suite only")
                compare_workload(base, args.workload, args.repeats)
                return
            both = set(run_in(base, NAMES)) & set(run_in(ROOT, NAMES))
            names = [n for n in run_in(ROOT, NAMES) if n in both
                     and (not args.names or n in args.names)]
            print(f"baseline {args.baseline} against the working tree; medians of "
                  f"{args.repeats} interleaved runs; ratio = current / baseline; current "
                  f"refine options {args.current_refine}")
            print(f"{'problem':22s} {'refine wall':>11s} {'cpu':>6s} {'ratio':>6s} "
                  f"{'cpu':>6s} | {'solve cpu':>9s} {'ratio':>6s} | objective (both)")
            for name in names:
                rows: dict[str, list[dict]] = {"base": [], "now": []}
                for k in range(args.repeats):
                    order = [("base", base), ("now", ROOT)]
                    for key, tree in order if k % 2 == 0 else order[::-1]:
                        extra = [args.current_refine] if key == "now" else []
                        rows[key].append(run_in(tree, CHILD, name, *extra))  # type: ignore

                def med(key: str, field: str, rows: dict = rows) -> float:
                    return statistics.median(r[field] for r in rows[key])

                vb, vn = rows["base"][0]["value"], rows["now"][0]["value"]
                print(f"{name:22s} {med('now', 'refine'):11.3f} {med('now', 'refine_cpu'):6.2f} "
                      f"{med('now', 'refine') / med('base', 'refine'):6.2f} "
                      f"{med('now', 'refine_cpu') / med('base', 'refine_cpu'):6.2f} | "
                      f"{med('now', 'solve_cpu'):9.3f} "
                      f"{med('now', 'solve_cpu') / med('base', 'solve_cpu'):6.2f} | "
                      f"{vn:.10g} {vb:.10g}", flush=True)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)],
                           check=False)


if __name__ == "__main__":
    main()
