"""
Stepped intrusions
==================

Less damping, more intrusion steps (the paper's Fig. 3a): at ``v0 = -1``, ``k_p = 0.2``,
damping 0.4, 0.18 and 0 give one, two and three steps.
"""

from softlanding import Impact, Impedance, Robot, simulate
from softlanding.plots import plot_stepped_intrusions

robot = Robot(r_m=5, s=20)
results = [simulate(robot, Impact(-1), Impedance(0.2, k_d)) for k_d in (0.4, 0.18, 0.0)]
for k_d, r in zip((0.4, 0.18, 0.0), results, strict=True):
    print(f"k_d = {k_d:<4}  {r.steps} step(s), depth {r.depth:.6f}")
plot_stepped_intrusions(results)
