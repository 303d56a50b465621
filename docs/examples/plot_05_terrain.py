"""
Landing on other grounds
========================

The same impedance landing on the paper's linear ground and under velocity-squared drag
(``f = d + c_d v_f^2``): drag holds the foot up, so it sinks less.
"""

import matplotlib.pyplot as plt

from softlanding import DragGround, Impact, Impedance, LinearGround, Robot, simulate

robot, impact, leg = Robot(r_m=5, s=20), Impact(-4.8), Impedance(0.5, 1.5)
fig, ax = plt.subplots(figsize=(6, 3.5))
grounds = {"linear": LinearGround(), "drag c_d = 0.05": DragGround(0.05),
           "drag c_d = 0.2": DragGround(0.2), "drag c_d = 1": DragGround(1.0)}
for name, ground in grounds.items():
    res = simulate(robot, impact, leg, ground)
    traj = res.trajectory()
    ax.plot(traj.t, traj.x[:, 2], label=f"{name}: depth {res.depth:.3f}")
    print(f"{name:>16}: depth {res.depth:.6f}")
ax.set_xlabel("time tau")
ax.set_ylabel("foot height x_f")
ax.set_title("Impedance k_p = 0.5, k_d = 1.5, v0 = -4.8")
ax.legend()
fig.tight_layout()
