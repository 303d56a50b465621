"""The MPC's step time (issue 25: median <= 1 ms, 99th percentile <= 5 ms), baseline vs now.

Run:  python -m benchmarks.bench_mpc_step [--cases 12] [--repeats 2] [--baseline 865cfde]
      [--warm]

The baseline is ``softlanding/control/mpc.py`` as of the commit ``--baseline`` (default
865cfde, before the step-time work), loaded from ``git show`` into a temporary module that
runs on this tree's ``ocp`` and simulator (so only the controller differs). The contenders
land case by case, interleaved (the baseline first on even repeats, the current code on odd
ones), so that a drift of the shared machine's load falls on both. Before every landing the
refinement NLPs cached in the process are forgotten (``ocp.structure.switching.clear_cache``): each
landing is a controller's first after boot, whose one-time builds fall in its setup or in
its steps, as the contender puts them (``--warm`` keeps them, as the unknown-ground study
does). One untimed landing per contender first takes the process-wide compilations
(numba's simulator, CasADi's code) out of both.

Each sample's estimate and re-plan is timed in wall time (``time.perf_counter``, what
``MPCLanding.step_times_ms`` records) and in CPU time (``time.process_time``, read at the
same instants). Printed: the median and 99th percentile over every step of every landing,
wall and CPU, for both contenders and their ratio (below 1: faster now); whether the goals
hold; the sample period on the paper's rig next to them; the depths of both, which must
agree within the 2 % goal.
"""

from __future__ import annotations

import argparse
import importlib.util
import itertools
import subprocess
import sys
import tempfile
import time
import types
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: v0 x (K, c_d): every impact velocity on a soft drag-free, a nominal dragging and a stiff
#: draggy ground (the soft one takes the creep's transcriptions, the draggy ones the
#: structure changes of the first estimates).
CASES = [(v0, k, c) for v0, (k, c) in itertools.product(
    (-1.0, -3.0, -6.0, -10.0), ((0.5, 0.0), (1.0, 0.2), (2.0, 1.0)))]


class _TwoClocks:
    """A stand-in for the ``time`` module of a contender: ``perf_counter`` also reads
    ``process_time`` at the same instant (the MPC loop calls it at its setup's start and
    end, then at every step's start and end)."""

    def __init__(self) -> None:
        self.reads: list[tuple[float, float]] = []

    def perf_counter(self) -> float:
        w, c = time.perf_counter(), time.process_time()
        self.reads.append((w, c))
        return w

    def __getattr__(self, name: str) -> Any:
        return getattr(time, name)


def baseline_module(rev: str) -> types.ModuleType:
    """``softlanding/control/mpc.py`` of ``rev`` as a module of its own.

    Parameters
    ----------
    rev : str
        A commit, tag or branch.
    """
    src = subprocess.run(["git", "show", f"{rev}:softlanding/control/mpc.py"], cwd=ROOT,
                         check=True, capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp()) / f"mpc_{rev}.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location(f"mpc_baseline_{rev}", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # (its dataclasses look their module up)
    spec.loader.exec_module(mod)
    return mod


def land(mod: types.ModuleType, case: tuple[float, float, float],
         warm: bool) -> tuple[list[float], list[float], float, float]:
    """One landing: step wall and CPU times (ms), the depth, the setup (ms).

    Parameters
    ----------
    mod : module
        A contender (has ``mpc_landing``).
    case : (v0, K, c_d)
        The landing.
    warm : bool
        Keep the refinement NLPs cached by earlier landings.
    """
    from ocp.structure.switching import clear_cache
    from softlanding.model.robot import PAPER_ROBOT
    from softlanding.studies.unknown_ground import true_ground

    if not warm:
        clear_cache()
    clocks = _TwoClocks()
    mod.time = clocks  # type: ignore[attr-defined]
    try:
        import inspect

        # --warm: the current code clears its own caches unless told to reuse them; it
        # runs the compiled controller unless told the re-planning MPC
        params = inspect.signature(mod.mpc_landing).parameters
        extra = {"reuse": True} if warm and "reuse" in params else {}
        if "controller" in params:
            extra["controller"] = "replan"
        m = mod.mpc_landing(case[0], PAPER_ROBOT, true_ground(case[1], case[2]), **extra)
    finally:
        mod.time = time  # type: ignore[attr-defined]
    steps = clocks.reads[2:]
    if not steps:  # (the loop's controllers time themselves: their CPU time is recorded)
        return list(m.step_times_ms), list(m.step_cpu_ms), float(m.depth), float(m.setup_ms)
    cpu = [1e3 * (steps[2 * k + 1][1] - steps[2 * k][1]) for k in range(len(steps) // 2)]
    assert len(cpu) == len(m.step_times_ms)
    return list(m.step_times_ms), cpu, float(m.depth), float(m.setup_ms)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=len(CASES), help="the first N of the 12 cases")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--baseline", default="865cfde", help="the commit of the baseline mpc.py")
    ap.add_argument("--warm", action="store_true", help="keep the refinement NLPs cached "
                                                        "between landings")
    a = ap.parse_args()
    from softlanding.control import mpc as current
    from softlanding.control.mpc import DEFAULT_PERIOD
    from softlanding.model.terrain import paper_rig_units

    contenders = {f"baseline {a.baseline}": baseline_module(a.baseline), "current": current}
    cases = CASES[:max(1, a.cases)]
    stats: dict[str, dict[str, list[float]]] = {n: {"wall": [], "cpu": [], "setup": []}
                                                for n in contenders}
    depths: dict[str, dict[tuple, float]] = {n: {} for n in contenders}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for mod in contenders.values():  # process-wide compilations, untimed
            land(mod, cases[0], a.warm)
        t0 = time.perf_counter()
        for rep in range(a.repeats):
            order = list(contenders.items())
            if rep % 2:
                order.reverse()
            for case in cases:
                for name, mod in order:
                    wall, cpu, depth, setup = land(mod, case, a.warm)
                    stats[name]["wall"] += wall
                    stats[name]["cpu"] += cpu
                    stats[name]["setup"].append(setup)
                    depths[name][case] = depth
    tau = paper_rig_units().time
    rig = 1e3 * DEFAULT_PERIOD * tau
    print(f"{len(cases)} cases x {a.repeats} repeats, interleaved, "
          f"{'warm caches' if a.warm else 'refinement caches cleared before each landing'}; "
          f"{time.perf_counter() - t0:.0f} s")
    print(f"sample period {DEFAULT_PERIOD:g} = {rig:.3f} ms on the paper's rig "
          f"(tau_s = {tau:.4f} s)")
    print(f"{'':22} {'steps':>6} {'median wall':>12} {'p99 wall':>10} {'median CPU':>11} "
          f"{'p99 CPU':>9} {'setup med':>10}   (ms)")
    rows = {}
    for name, s in stats.items():
        w, c = np.array(s["wall"]), np.array(s["cpu"])
        rows[name] = (np.median(w), np.percentile(w, 99), np.median(c), np.percentile(c, 99))
        print(f"{name:22} {len(w):6d} {rows[name][0]:12.3f} {rows[name][1]:10.2f} "
              f"{rows[name][2]:11.3f} {rows[name][3]:9.2f} {np.median(s['setup']):10.1f}")
    base, cur = rows[f"baseline {a.baseline}"], rows["current"]
    print(f"{'ratio current/base':22} {'':6} {cur[0] / base[0]:12.3f} {cur[1] / base[1]:10.3f} "
          f"{cur[2] / base[2]:11.3f} {cur[3] / base[3]:9.3f}")
    for name, (med, p99, cmed, cp99) in rows.items():
        ok = med <= 1.0 and p99 <= 5.0
        print(f"goals (median <= 1 ms, p99 <= 5 ms, wall) {name}: {'met' if ok else 'NOT met'}"
              f" (median {med:.3f} ms = {med / rig:.1f} rig periods of {rig:.3f} ms; "
              f"p99 {p99:.2f} ms; CPU {cmed:.3f} / {cp99:.2f} ms)")
    worst = max(abs(depths["current"][c] / depths[f"baseline {a.baseline}"][c] - 1)
                for c in cases)
    print(f"depths: largest relative difference current vs baseline {worst:.2e}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
