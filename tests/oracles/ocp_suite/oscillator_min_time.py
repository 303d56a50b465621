"""Time-optimal control of the harmonic oscillator (Pontryagin et al. 1962).

``x1' = x2``, ``x2' = -x1 + u``, ``|u| <= 1``, from ``(1, 0)`` to the origin in
minimum time: the example with which Pontryagin, Boltyanskii, Gamkrelidze and
Mishchenko, *The Mathematical Theory of Optimal Processes* (1962), ch. 1, build the
synthesis of time-optimal controls (switching curve of unit semicircles; the
transfer from ``(1, 0)`` is also an exercise of Knowles, *An Introduction to
Applied Optimal Control*, 1981, which asks for its minimum time and switching
times). In the phase plane a bang arc ``u`` turns the state
clockwise at unit angular speed about ``(u, 0)``. From ``(1, 0)``, the centre of
the ``u = +1`` circles, the control must start at ``-1`` (the circle of radius 2
about ``(-1, 0)``) and switch to ``+1`` where that circle meets the unit circle
about ``(1, 0)`` through the origin, at ``(3/4, -sqrt(15)/4)``:

* switch at ``t1 = arccos(7/8) = 0.5053605...``,
* final time ``T = arccos(-1/4) = 1.8234766...`` (both arcs shorter than pi, as
  the synthesis requires).

The problem is linear, so the refinement is exact (matrix exponentials);
:func:`oscillator_min_time_check` re-integrates the closed-form control with
scipy's ``solve_ivp`` to confirm that it reaches the origin.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from ocp import OptimalControlProblem
from tests.oracles.ocp_suite.problems import SuiteProblem

T_SWITCH = math.acos(7 / 8)
T_FINAL = math.acos(-1 / 4)


def oscillator_min_time() -> OptimalControlProblem:
    """Rest at ``x1 = 1`` to the origin in minimum time, ``|u| <= 1``."""
    p = OptimalControlProblem("oscillator_min_time")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", -1.0, 1.0)
    p.set_dynamics({"x1": x2, "x2": -x1 + u})
    p.initial_constraint(x1, 1.0)
    p.initial_constraint(x2, 0.0)
    p.terminal_constraint(x1, 0.0)
    p.terminal_constraint(x2, 0.0)
    p.free_final_time(0.1, 10.0, guess=2.0)
    p.minimize_terminal(p.T)
    return p


def oscillator_min_time_check() -> np.ndarray:
    """The end state of the closed-form control (-1 until arccos(7/8), then +1 until
    arccos(-1/4)) integrated by scipy (DOP853 at 1e-13): the origin to ~1e-13."""
    def rhs(t: float, y: np.ndarray, u: float) -> list[float]:
        return [y[1], -y[0] + u]

    opts = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}
    y = solve_ivp(rhs, (0.0, T_SWITCH), [1.0, 0.0], args=(-1.0,), **opts).y[:, -1]
    return solve_ivp(rhs, (T_SWITCH, T_FINAL), y, args=(1.0,), **opts).y[:, -1]


PROBLEM = SuiteProblem(
    "oscillator_min_time", "Pontryagin, Boltyanskii, Gamkrelidze, Mishchenko (1962) ch. 1, "
    "time-optimal synthesis for x'' + x = u: from (1, 0), T = arccos(-1/4) "
    "= 1.8234766, one switch at arccos(7/8)",
    T_FINAL, 1e-7, oscillator_min_time, exact=lambda: T_FINAL,
    covers=("bang-bang, one control", "free final time", "closed form",
            "bang-bang solved by collocation and certified"),
    bang_bang=True, intervals=10, tol=1e-8,
    notes="the published synthesis gives the closed form; the check re-integrates it")
