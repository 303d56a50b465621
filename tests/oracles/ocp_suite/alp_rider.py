"""Betts' alp rider: a linear system riding over a terrain of Gaussian ridges.

Betts (2010), *Practical Methods for Optimal Control and Estimation Using
Nonlinear Programming*, 2nd ed., SIAM, pp. 163-165: J* = 2030.85609.
A stiff (rates -10 .. -2), state-constrained problem whose constraint is
active in four narrow spikes: a mesh-refinement workload (``benchmarks``), not
part of the fast suite (:data:`PROBLEM` is ``slow``).
"""

from __future__ import annotations

import casadi as ca

from ocp import OptimalControlProblem

from .problems import SuiteProblem

PUBLISHED = 2030.85609
"""Betts (2010) p. 165."""


def ridge(t: ca.SX, a: float, b: float) -> ca.SX:
    """``p(t, a, b) = exp(-b (t - a)^2)``."""
    return ca.exp(-b * (t - a) ** 2)


def alp_rider() -> OptimalControlProblem:
    """min int_0^20 100 |y|^2 + 0.01 |u|^2 over the terrain |y|^2 >= sum of ridges + 0.01."""
    p = OptimalControlProblem("alp_rider")
    y = [p.state(f"y{i}") for i in range(1, 5)]
    u1, u2 = p.control("u1"), p.control("u2")
    p.set_dynamics({"y1": -10 * y[0] + u1 + u2, "y2": -2 * y[1] + u1 + 2 * u2,
                    "y3": -3 * y[2] + 5 * y[3] + u1 - u2,
                    "y4": 5 * y[2] - 3 * y[3] + u1 + 3 * u2})
    for s, a, b in zip(y, (2.0, 1.0, 2.0, 1.0), (2.0, 3.0, 1.0, -2.0), strict=True):
        p.initial_constraint(s, a)
        p.terminal_constraint(s, b)
    t = p.t
    terrain = (3 * ridge(t, 3, 12) + 3 * ridge(t, 6, 10) + 3 * ridge(t, 10, 6)
               + 8 * ridge(t, 15, 4) + 0.01)
    r2 = sum(s**2 for s in y)
    p.path_constraint(r2 - terrain, lower=0.0, name="terrain")
    p.fixed_final_time(20.0)
    p.minimize_integral(100 * r2 + 0.01 * (u1**2 + u2**2))
    return p


PROBLEM = SuiteProblem(
    "alp_rider", "Betts (2010), Practical Methods, 2nd ed., pp. 163-165: J = 2030.85609",
    PUBLISHED, 1e-6, alp_rider, covers=("state constraint active in narrow spikes",),
    intervals=50, tol=1e-6, max_rounds=10, slow=True)
