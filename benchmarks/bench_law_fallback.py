"""A ground law without a C compiler (evaluated in Python) against the compiled law.

Run:  python -m benchmarks.bench_law_fallback [--n 20] [--repeats 2]

``simulate_batch`` of ``n x n`` impedance landings (v0 = -3) on a drag ground of stiffness
K = 2 (a law the kernel does not have built in: compiled to C, or without a compiler a ctypes
callback of the same CasADi function), the two contenders alternating, each run on a law not
built before in this process (the cost of building it included: CasADi's code generation,
and for the compiled law the C compiler's time, a child process, counted in CPU). Prints the
median CPU and wall time of each, their ratio against the compiled law (the baseline), and
the largest depth difference between the two.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time

import numpy as np


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)  # the C compiler
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="landings per side of the gain grid")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    os.environ["SOFTLANDING_CACHE"] = tempfile.mkdtemp(prefix="bench-law-")  # a cold cache
    from softlanding.model.ground import DragGround
    from softlanding.model.robot import PAPER_ROBOT
    from softlanding.simulation.simulator import simulate_batch

    g = np.linspace(0.1, 1.0, args.n)
    kp, kd = np.meshgrid(g, g)
    simulate_batch(PAPER_ROBOT, -3.0, kp, kd, DragGround(0.2, 1.5))  # load the kernel
    times: dict[str, list[tuple[float, float]]] = {"compiled": [], "python": []}
    depths: dict[str, np.ndarray] = {}
    k = 2.0
    for _ in range(args.repeats):
        for name in ("compiled", "python"):
            if name == "python":
                os.environ["CC"] = "/nonexistent/cc"
            else:
                os.environ.pop("CC", None)
            k = np.nextafter(k, 3.0)  # a law not built yet (the same ground to 1e-16)
            c, w = _cpu(), time.perf_counter()
            b = simulate_batch(PAPER_ROBOT, -3.0, kp, kd, DragGround(0.2, k))
            times[name].append((_cpu() - c, time.perf_counter() - w))
            depths[name] = np.asarray(b.depth)
    base = [statistics.median(x[i] for x in times["compiled"]) for i in (0, 1)]
    print(f"{args.n ** 2} landings on a drag ground (K = 2), median of {args.repeats}:")
    for name, runs in times.items():
        cpu, wall = (statistics.median(x[i] for x in runs) for i in (0, 1))
        print(f"  {name:<9} CPU {cpu:7.3f} s  wall {wall:7.3f} s  "
              f"ratio CPU {cpu / base[0]:6.1f}  wall {wall / base[1]:6.1f}")
    diff = np.nanmax(np.abs(depths["compiled"] - depths["python"]))
    print(f"  largest depth difference {diff:.2e}; load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
