"""
The bang-bang landing and its certificate
=========================================

The paper's optimal control problem at ``v0 = -3`` with the paper's robot (``r_m = 5``,
``s = 20``, ``u_max = 8.2``): transcribed by multiple shooting, solved with Ipopt, the
switching time refined with exact arcs, replayed in the exact simulator, and certified
against Pontryagin's conditions.
"""

from softlanding import PAPER_ROBOT, Impact, solve_landing
from softlanding.plots import plot_bang_bang

bb = solve_landing(Impact(-3), PAPER_ROBOT)
print(f"depth {bb.depth:.9f} (rigid leg: 4.16227766), arcs {' -> '.join(bb.arcs)}, "
      f"switch at {bb.switch_times[0]:.9f}")
print("PMP:", bb.certify().verdict)
plot_bang_bang(bb)
