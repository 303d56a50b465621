"""
A map of impedance gains
========================

Every landing of a 101 x 101 grid of gains at ``v0 = -3`` in one call (all cores), then the
optimal gains found by the zooming grid search. Blank: gains that leave the stroke limits.
"""

from softlanding import Impact, Robot, optimize_impedance
from softlanding.plots import plot_depth_map
from softlanding.studies import depth_map

robot = Robot(r_m=5, s=20)
ds = depth_map(Impact(-3), robot, n=101)
best = optimize_impedance(Impact(-3), robot)
print(f"optimal k_p = {best.k_p:.4f}, k_d = {best.k_d:.4f}, depth {best.depth:.6f}")
plot_depth_map(ds, optimum=best)
