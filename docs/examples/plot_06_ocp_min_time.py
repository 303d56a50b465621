"""
The ``ocp`` layer on its own: a minimum-time problem
====================================================

``ocp`` knows nothing of landing. A double integrator moved a distance ``d`` and stopped in
minimum time with ``|u| <= 1``: multiple shooting, then the switching time refined with exact
arcs (``T = 2 sqrt(d)`` to rounding), then Pontryagin's certificate, and a re-solve for
another ``d`` without rebuilding anything.
"""

import math

from ocp import MultipleShooting, OptimalControlProblem, certify, plot_certificate, refine_switching

p = OptimalControlProblem("min_time")
x, v = p.state("x"), p.state("v")
u = p.control("u", lower=-1, upper=1)
d = p.parameter("d")
p.set_dynamics({"x": v, "v": u})
p.initial_constraint(x, 0.0)
p.initial_constraint(v, 0.0)
p.terminal_constraint(x - d, 0.0)
p.terminal_constraint(v, 0.0)
p.free_final_time(lower=0.01, upper=100)
p.minimize_terminal(p.T)

ms = MultipleShooting(p, nodes=40)  # built once
sol = ms.solve({"d": 2.0})
r = refine_switching(sol)
arcs = [m[0].kind for m in r.modes]  # one control: its arc on each interval
print(f"arcs {arcs}, T = {r.T:.15f} (2 sqrt 2 = {2 * math.sqrt(2):.15f})")
cert = certify(sol, r)
print("certificate:", cert.verdict)
sol3 = ms.solve({"d": 3.0}, warm_start=sol)
print(f"d = 3: T = {sol3.T:.6f} (transcribed), builds: {ms.n_builds}")
fig = plot_certificate(cert)
# H is constant to ~1e-14: left to autoscale, its axis would read as an offset
# ("1e-12-10e-1"); show it on the scale of H itself, a flat line
h = cert.H / cert.H_scale
fig.axes[0].set_ylim(h.mean() - 1, h.mean() + 1)
