"""Minimum-fuel rest-to-rest transfer of a planar double integrator by four on/off thrusters.

Four thrusters push along +x, -x, +y and -y (``u1 .. u4`` in [0, 1]); a pair on
one axis may not fire together (``u1 + u2 <= 1``, ``u3 + u4 <= 1``: control-only
coupling constraints, the control set of each axis is the triangle with
vertices off, +, -). From rest at ``(dx, dy)`` to rest at the origin in the
fixed time ``T``, minimise the fuel ``int u1 + u2 + u3 + u4``.

Each axis is the fuel-optimal double integral plant of Athans and Falb (1966),
*Optimal Control*, ch. 8 (``x'' = u``, ``|u| <= 1``, fuel ``int |u|``, fixed
time): bang-off-bang. For a rest-to-rest transfer over ``d`` in time ``T``
(``T^2 > 4 d``) the burn lasts ``t1`` at each end with ``t1 (T - t1) = d``, so
``t1 = (T - sqrt(T^2 - 4 d)) / 2`` and the fuel is ``2 t1 = T - sqrt(T^2 - 4 d)``.
The published value below is that formula at this data (the textbook gives
the structure and the formula, not this number); :func:`thrusters_2d_simulated`
checks it independently by integrating the switching structure with
``scipy.integrate.solve_ivp``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ocp import OptimalControlProblem
from tests.oracles.ocp_suite.problems import SuiteProblem

DATA = {"dx": 1.0, "dy": 0.5, "T": 3.0}


def thrusters_2d(dx: float = DATA["dx"], dy: float = DATA["dy"], T: float = DATA["T"],
                 umax: float = 1.0) -> OptimalControlProblem:
    """The problem: four on/off thrusters, two coupling constraints, minimum fuel.

    With ``umax > 1`` each thruster alone could push harder than the pair's limit
    allows (a shared supply): the optimum is the same, but a thruster on sits at
    a vertex of its axis' triangle strictly inside its own bounds.
    """
    p = OptimalControlProblem("thrusters_2d")
    x, vx, y, vy = p.state("x"), p.state("vx"), p.state("y"), p.state("vy")
    u = [p.control(f"u{i}", 0.0, umax) for i in range(1, 5)]
    p.set_dynamics({"x": vx, "vx": u[0] - u[1], "y": vy, "vy": u[2] - u[3]})
    p.path_constraint(u[0] + u[1], upper=1.0, name="u1 + u2 <= 1")
    p.path_constraint(u[2] + u[3], upper=1.0, name="u3 + u4 <= 1")
    for s, a in ((x, dx), (vx, 0.0), (y, dy), (vy, 0.0)):
        p.initial_constraint(s, a)
    for s in (x, vx, y, vy):
        p.terminal_constraint(s, 0.0)
    p.fixed_final_time(T)
    p.minimize_integral(u[0] + u[1] + u[2] + u[3])
    return p


def burn_time(d: float, T: float) -> float:
    """Length of each burn of a fuel-optimal rest-to-rest transfer over ``|d|`` in ``T``."""
    return (T - math.sqrt(T * T - 4 * abs(d))) / 2


def thrusters_2d_exact(dx: float = DATA["dx"], dy: float = DATA["dy"],
                       T: float = DATA["T"]) -> float:
    """Closed-form minimum fuel: ``2 t1(dx) + 2 t1(dy)``."""
    return 2 * burn_time(dx, T) + 2 * burn_time(dy, T)


def thrusters_2d_switch_times(dx: float = DATA["dx"], dy: float = DATA["dy"],
                              T: float = DATA["T"]) -> list[float]:
    """All switch times, sorted: each axis switches at ``t1`` and ``T - t1``."""
    a, b = burn_time(dx, T), burn_time(dy, T)
    return sorted([a, T - a, b, T - b])


def thrusters_2d_simulated(dx: float = DATA["dx"], dy: float = DATA["dy"],
                           T: float = DATA["T"]) -> tuple[np.ndarray, float]:
    """Final state and fuel of the closed-form bang-off-bang controls, by ``solve_ivp``
    (RK45 at tolerance 1e-12, stopped at every switch)."""
    ta, tb = burn_time(dx, T), burn_time(dy, T)

    def controls(t: float) -> np.ndarray:
        ux = -1.0 if t < ta else (1.0 if t > T - ta else 0.0)
        uy = -1.0 if t < tb else (1.0 if t > T - tb else 0.0)
        return np.array([max(ux, 0), max(-ux, 0), max(uy, 0), max(-uy, 0)])

    z = np.array([dx, 0.0, dy, 0.0, 0.0])
    edges = [0.0, *thrusters_2d_switch_times(dx, dy, T), T]
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        u = controls(0.5 * (a + b))

        def rhs(_t: float, s: np.ndarray, u: np.ndarray = u) -> np.ndarray:
            return np.array([s[1], u[0] - u[1], s[3], u[2] - u[3], float(np.sum(u))])

        z = solve_ivp(rhs, (a, b), z, rtol=1e-12, atol=1e-13).y[:, -1]
    return z[:4], float(z[4])


PROBLEM = SuiteProblem(
    "thrusters_2d",
    "Athans and Falb (1966), Optimal Control, ch. 8: fuel-optimal double integral plant "
    "with fixed time (bang-off-bang, fuel T - sqrt(T^2 - 4 d)), one per axis; four on/off "
    "thrusters with u1 + u2 <= 1, u3 + u4 <= 1 (dx = 1, dy = 0.5, T = 3)",
    thrusters_2d_exact(), 1e-6, thrusters_2d, exact=lambda: thrusters_2d_simulated()[1],
    covers=("control-only coupling constraints (inequality)", "bang-bang, several controls",
            "L1 (fuel) cost"),
    bang_bang=True, intervals=12, tol=1e-8,
    notes="published = the textbook's closed form at this data; exact = solve_ivp of the "
          "closed-form switching structure")
