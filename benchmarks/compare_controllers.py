"""Rigid leg vs optimal impedance vs bang-bang force control over impact velocity.

Run:  python -m benchmarks.compare_controllers [--n 11] [--grid 101] [--rm 5] [--s 20]

The paper's Section V comparison, with numbers. For each v0 in [-10, 0]:
the rigid-leg depth 1 + sqrt(1 + v0^2) (analytic), the depth of the
depth-optimal impedance (grid, zooming feasible grid, bisection onto the
stroke limit; exact simulator) and of optimal bang-bang force control
(multiple shooting + Ipopt, switching times refined with exact arcs) with
u_max = 8.2. Prints the table, the ratios to the rigid depth, the paper's
claims checked, and the time each controller's design took in this run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from softlanding import PAPER_ROBOT, Robot
from softlanding.studies.comparison import compare_controllers, comparison_arrays


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=11, help="number of impact velocities")
    ap.add_argument("--grid", type=int, default=101, help="impedance starting grid per axis")
    ap.add_argument("--rm", type=float, default=PAPER_ROBOT.r_m)
    ap.add_argument("--s", type=float, default=PAPER_ROBOT.s)
    ap.add_argument("--umax", type=float, default=PAPER_ROBOT.u_max)
    a = ap.parse_args()

    v0 = np.linspace(0.0, -10.0, a.n)
    t0 = time.perf_counter()
    rows = compare_controllers(v0, Robot(r_m=a.rm, s=a.s, u_max=a.umax), grid=a.grid)
    elapsed = time.perf_counter() - t0
    c = comparison_arrays(rows)
    print(f"Depth -x_f(T), r_m = {a.rm:g}, s = {a.s:g}; bang-bang u_max = {a.umax:g}; "
          f"impedance unsaturated (dimensionless units)")
    print(f"{'v0':>7} {'rigid':>9} {'impedance':>10} {'k_p*':>7} {'k_d*':>7} {'u_peak':>7} "
          f"{'bang-bang':>10} {'switch':>7} {'imp/rigid':>9} {'bb/rigid':>8} {'bb/imp':>7}")
    for r in rows:
        print(f"{r['v0']:>7.2f} {r['rigid']:>9.5f} {r['impedance']:>10.6f} "
              f"{r['impedance_k_p']:>7.4f} {r['impedance_k_d']:>7.4f} "
              f"{r['impedance_u_peak']:>7.3f} {r['bang_bang']:>10.6f} "
              f"{r['bang_bang_switch']:>7.4f} {r['impedance'] / r['rigid']:>9.4f} "
              f"{r['bang_bang'] / r['rigid']:>8.4f} {r['bang_bang'] / r['impedance']:>7.4f}")
    bb_r = c["bang_bang"] / c["rigid"]
    imp_r = c["impedance"] / c["rigid"]
    moving = c["v0"] < 0
    print()
    halves = bool(np.all(bb_r[moving] <= 0.5))
    print(f"bang-bang / rigid: {bb_r.min():.4f} .. {bb_r.max():.4f}; at every v0 < 0 "
          f"<= 1/2 (the paper's 'at least a factor of two'): {halves}")
    print(f"impedance / rigid: {imp_r.min():.4f} .. {imp_r.max():.4f}")
    print(f"bang-bang below impedance at every v0 < 0: "
          f"{bool(np.all(c['bang_bang'][moving] < c['impedance'][moving]))}")
    i = int(np.argmin(c["v0"]))
    print(f"peak force of the optimal impedance at v0 = {c['v0'][i]:g}: "
          f"{c['impedance_u_peak'][i]:.3f} (paper: 8.2, which it uses as u_max)")
    print(f"designs for {a.n} velocities took {elapsed:.1f} s "
          f"({elapsed / a.n:.2f} s per velocity, both controllers)")


if __name__ == "__main__":
    main()
