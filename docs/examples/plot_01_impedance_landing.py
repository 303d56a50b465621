"""
An impedance landing, simulated exactly
=======================================

The paper's stepped-intrusion case: impact at ``v0 = -1`` with stiffness ``k_p = 0.2`` and
damping ``k_d = 0.18``. The simulator is exact (matrix exponentials, root-found events), and
rest is proven, not assumed after a horizon.
"""

from softlanding import Impact, Impedance, Robot, simulate
from softlanding.plots import plot_trajectory

robot = Robot(r_m=5, s=20)  # no force limit
res = simulate(robot, Impact(-1), Impedance(k_p=0.2, k_d=0.18))
print(f"depth {res.depth:.6f}, {res.steps} intrusion steps, status: {res.status}")
print(f"energy: ground {res.energy.ground:.4f}, actuator {res.energy.actuator:.4f}, "
      f"CoT {res.energy.cot:.3f}")
plot_trajectory(res)
