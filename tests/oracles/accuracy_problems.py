"""Problems of issues 44 and 45 with known optima, for the accuracy of refinement and checks.

Each builder returns the problem; ``*_EXACT`` is its optimum from a closed form or, where
none exists, from an independent computation (said where).
"""

import math

from ocp import OptimalControlProblem

LQ_EXACT = math.tanh(1.0) / 2
"""min int (x^2 + u^2)/2, x' = u, x(0) = 1, T = 1: the Riccati solution P = tanh(1 - t)
gives J = P(0) x0^2 / 2."""

SINGULAR_EXACT = 1.0 / 3.0
"""min int x^2, x' = u, |u| <= 1, x(0) = 1, T = 2: u = -1 until x = 0 at t = 1 (J = 1/3),
then the singular arc u = 0."""

SPEED_EXACT = 3.3
"""x: 0 -> 2 at rest, |u| <= 1, v <= 0.8, min T: accelerate for 0.8 (x = 0.32), cruise at
0.8 for 1.7 (x = 1.68), brake for 0.8: T = 3.3."""

THIRD_ORDER_REFERENCE = 258.578254
"""min int u^2 / 2, x''' = u, (x, x', x'')(0) = (0, 1, 0), (x, x', x'')(1) = (0, -1, 0),
x <= 1/6: no closed form; collocation on 6,400 uniform intervals with the bound imposed at
the collocation points only gives 258.5782512 (from below), with the bound held along the
whole polynomials 258.5782564 (from above); their middle, to +-3e-6."""


def lq() -> OptimalControlProblem:
    """The scalar LQ problem (:data:`LQ_EXACT`): an interior arc only."""
    p = OptimalControlProblem("scalar LQ")
    x, u = p.state("x"), p.control("u")
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral((x**2 + u**2) / 2)
    return p


def singular() -> OptimalControlProblem:
    """A bang arc then a singular arc (:data:`SINGULAR_EXACT`)."""
    p = OptimalControlProblem("singular")
    x, u = p.state("x"), p.control("u", -1.0, 1.0)
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(2.0)
    p.minimize_integral(x**2)
    return p


def speed_limit(form: str = "path") -> OptimalControlProblem:
    """The speed-limited double integrator (:data:`SPEED_EXACT`), the limit written as a
    path constraint (``form="path"``) or as a state bound (``"bound"``)."""
    p = OptimalControlProblem(f"speed limit ({form})")
    x = p.state("x")
    v = p.state("v", upper=0.8) if form == "bound" else p.state("v")
    if form != "bound":
        p.path_constraint(v, upper=0.8, name="speed limit")
    u = p.control("u", -1.0, 1.0)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x, 2.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.5, 10.0, guess=3.0)
    p.minimize_terminal(p.T)
    return p


def third_order(form: str = "bound", ell: float = 1 / 6) -> OptimalControlProblem:
    """A state constraint of order 3 (:data:`THIRD_ORDER_REFERENCE`), ``x <= ell`` as a
    state bound or a path constraint."""
    p = OptimalControlProblem(f"third-order state constraint ({form})")
    x = p.state("x", upper=ell) if form == "bound" else p.state("x")
    if form != "bound":
        p.path_constraint(x, upper=ell, name="x <= l")
    v, a, u = p.state("v"), p.state("a"), p.control("u")
    p.set_dynamics({"x": v, "v": a, "a": u})
    for s, start, end in ((x, 0.0, 0.0), (v, 1.0, -1.0), (a, 0.0, 0.0)):
        p.initial_constraint(s, start)
        p.terminal_constraint(s, end)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2 / 2)
    return p
