"""A double integrator switched between three modes, in outer convexification (one mode on).

Modes accelerate (``x'' = +1``), coast (``x'' = 0``) and brake (``x'' = -1``)
are chosen by on/off controls ``w1, w2, w3`` in [0, 1] with exactly one on:
``w1 + w2 + w3 = 1`` (an equality coupling: the control set is the simplex,
whose vertices are the modes). This is the outer convexification of a
switched system with an SOS1 constraint (Sager, Bock and Diehl (2012), "The
integer approximation error in mixed-integer optimal control", Math. Program.
133; the mintOC library's form of switched problems such as Egerstedt's).
Minimise the fuel ``int w1 + w3`` from rest at ``x = d`` to rest at the origin
in the fixed time ``T``.

Relaxed or not, the optimum is the fuel-optimal double integral plant of
Athans and Falb (1966), *Optimal Control*, ch. 8: brake for ``t1``, coast,
accelerate for ``t1`` with ``t1 (T - t1) = d``; fuel ``T - sqrt(T^2 - 4 d)``.
The published value is that formula at this data; :func:`modal_simulated`
checks it by ``scipy.integrate.solve_ivp`` of the mode sequence.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ocp import OptimalControlProblem
from tests.oracles.ocp_suite.problems import SuiteProblem

DATA = {"d": 2.0, "T": 4.0}


def modal_double_integrator(d: float = DATA["d"], T: float = DATA["T"]) -> OptimalControlProblem:
    """The problem: three mode controls on the simplex, minimum fuel, fixed time."""
    p = OptimalControlProblem("modal_double_integrator")
    x, v = p.state("x"), p.state("v")
    w = [p.control(f"w{i}", 0.0, 1.0) for i in range(1, 4)]
    p.set_dynamics({"x": v, "v": w[0] - w[2]})
    p.path_constraint(w[0] + w[1] + w[2], 1.0, 1.0, name="one mode on")
    p.initial_constraint(x, d)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x, 0.0)
    p.terminal_constraint(v, 0.0)
    p.fixed_final_time(T)
    p.minimize_integral(w[0] + w[2])
    return p


def modal_switch_times(d: float = DATA["d"], T: float = DATA["T"]) -> list[float]:
    """Brake until ``t1``, coast until ``T - t1``, accelerate to ``T``."""
    t1 = (T - math.sqrt(T * T - 4 * abs(d))) / 2
    return [t1, T - t1]


def modal_exact(d: float = DATA["d"], T: float = DATA["T"]) -> float:
    """Closed-form minimum fuel ``T - sqrt(T^2 - 4 d)``."""
    return T - math.sqrt(T * T - 4 * abs(d))


def modal_simulated(d: float = DATA["d"], T: float = DATA["T"]) -> tuple[np.ndarray, float]:
    """Final state and fuel of the closed-form mode sequence, by ``solve_ivp``."""
    t1, t2 = modal_switch_times(d, T)
    z = np.array([d, 0.0, 0.0])
    for (a, b), w in zip(((0.0, t1), (t1, t2), (t2, T)),
                         ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)), strict=True):
        def rhs(_t: float, s: np.ndarray, w: tuple = w) -> np.ndarray:
            return np.array([s[1], w[0] - w[2], w[0] + w[2]])

        z = solve_ivp(rhs, (a, b), z, rtol=1e-12, atol=1e-13).y[:, -1]
    return z[:2], float(z[2])


PROBLEM = SuiteProblem(
    "modal_double_integrator",
    "Athans and Falb (1966), Optimal Control, ch. 8 (fuel-optimal double integral plant, "
    "fixed time: fuel T - sqrt(T^2 - 4 d)), in the SOS1 outer convexification of Sager, Bock "
    "and Diehl (2012): modes w1 + w2 + w3 = 1 (d = 2, T = 4)",
    modal_exact(), 1e-6, modal_double_integrator, exact=lambda: modal_simulated()[1],
    covers=("control-only coupling constraints (equality, SOS1 simplex)",
            "bang-bang, several controls", "L1 (fuel) cost"),
    bang_bang=True, intervals=12, tol=1e-8,
    notes="published = the textbook's closed form at this data; exact = solve_ivp of the "
          "closed-form mode sequence")
