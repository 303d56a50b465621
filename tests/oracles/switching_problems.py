"""Problems with known (or independently computable) answers for the switching tests."""

from __future__ import annotations

import casadi as ca
import numpy as np

from ocp import MultipleShooting, OptimalControlProblem


def rayleigh() -> OptimalControlProblem:
    """Time-optimal Rayleigh oscillator (Maurer and Osmolovskii's example).

    ``x1' = x2, x2' = -x1 + x2 (1.4 - 0.14 x2^2) + u``, ``|u| <= 4``, from
    (-5, -5) to the origin in minimum time: bang-bang ``4, -4, 4`` with two
    switches; dynamics nonlinear in the state.
    """
    p = OptimalControlProblem("rayleigh")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", lower=-4, upper=4)
    p.set_dynamics([x2, -x1 + x2 * (1.4 - 0.14 * x2**2) + u])
    p.initial_constraint(x1, -5.0)
    p.initial_constraint(x2, -5.0)
    p.terminal_constraint(x1, 0.0)
    p.terminal_constraint(x2, 0.0)
    p.free_final_time(0.1, 20, 4.0)
    p.minimize_terminal(p.T)
    return p


def solve_rayleigh(nodes: int = 100):
    ms = MultipleShooting(rayleigh(), nodes=nodes)
    return ms.solve({}, guess=ms.initial_guess(T=3.7, x=lambda s: [-5 * (1 - s), 0.0], u=[0.0]))


def van_der_pol() -> OptimalControlProblem:
    """Time-optimal van der Pol oscillator: ``x1' = x2, x2' = -x1 + (1 - x1^2) x2 + u``,
    ``|u| <= 1``, from (1, 1) to the origin: bang-bang ``-1, 1``, nonlinear in the state."""
    p = OptimalControlProblem("van_der_pol")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", lower=-1, upper=1)
    p.set_dynamics([x2, -x1 + (1 - x1**2) * x2 + u])
    p.initial_constraint(x1, 1.0)
    p.initial_constraint(x2, 1.0)
    p.terminal_constraint(x1, 0.0)
    p.terminal_constraint(x2, 0.0)
    p.free_final_time(0.1, 20, 3.0)
    p.minimize_terminal(p.T)
    return p


def solve_van_der_pol(nodes: int = 100):
    ms = MultipleShooting(van_der_pol(), nodes=nodes)
    return ms.solve({}, guess=ms.initial_guess(T=2.0, x=lambda s: [1 - s, 1 - s], u=[-1.0]))


def two_masses() -> OptimalControlProblem:
    """Two masses joined by a spring, each pushed by its own force ``|u_i| <= 1``.

    ``x1'' = -k (x1 - x2) + u1``, ``x2'' = -k (x2 - x1) + u2``; rest to rest from
    the origin to ``(d1, d2)`` in minimum time. Either force alone controls the
    system, so both controls are bang-bang with their own switch times.
    """
    p = OptimalControlProblem("two_masses")
    x1, v1, x2, v2 = (p.state(n) for n in ("x1", "v1", "x2", "v2"))
    u1 = p.control("u1", lower=-1, upper=1)
    u2 = p.control("u2", lower=-1, upper=1)
    k, d1, d2 = p.parameter("k"), p.parameter("d1"), p.parameter("d2")
    p.set_dynamics([v1, -k * (x1 - x2) + u1, v2, -k * (x2 - x1) + u2])
    for s in (x1, v1, x2, v2):
        p.initial_constraint(s, 0.0)
    p.terminal_constraint(x1 - d1, 0.0)
    p.terminal_constraint(v1, 0.0)
    p.terminal_constraint(x2 - d2, 0.0)
    p.terminal_constraint(v2, 0.0)
    p.free_final_time(0.1, 20, 3.0)
    p.minimize_terminal(p.T)
    return p


def solve_two_masses(params: dict, nodes: int = 120):
    ms = MultipleShooting(two_masses(), nodes=nodes)
    guess = ms.initial_guess(T=3.0, x=lambda s: [params["d1"] * s, 0, params["d2"] * s, 0],
                             u=[0.0, 0.0])
    return ms.solve(params, guess=guess)


def speed_limited() -> OptimalControlProblem:
    """Minimum-time double integrator with a speed limit ``v <= vmax`` (relative degree 1).

    Rest to rest over ``d >= vmax^2``: full thrust until ``v = vmax`` at
    ``t = vmax``, cruise (u = 0, a boundary arc) until ``d / vmax``, full brake;
    ``T = d / vmax + vmax``.
    """
    p = OptimalControlProblem("speed_limited")
    x, v = p.state("x"), p.state("v")
    p.control("u", lower=-1, upper=1)
    d, vmax = p.parameter("d"), p.parameter("vmax")
    p.set_dynamics([v, p.u[0]])
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - d, 0.0)
    p.terminal_constraint(v, 0.0)
    p.path_constraint(v, -ca.inf, vmax, name="speed limit")
    p.free_final_time(0.01, 100, 3.0)
    p.minimize_terminal(p.T)
    return p


def ceiling() -> OptimalControlProblem:
    """Maximise ``int_0^4 x dt`` for ``x'' = u``, ``|u| <= 1``, rest to rest at 0, ``x <= l``.

    A constraint of relative degree 2. For ``l < 1`` (below the free peak) the
    optimum rises as fast as it can to the ceiling (``u = 1`` on ``[0, a]``,
    ``-1`` on ``[a, 2a]``, ``a = sqrt(l)``), stays on it (``u = 0``) and
    returns symmetrically: ``J = -(4 l - 2 l^1.5)`` (x(t) is pointwise the
    largest any admissible trajectory can have).
    """
    p = OptimalControlProblem("ceiling")
    x, v = p.state("x"), p.state("v")
    p.control("u", lower=-1, upper=1)
    l_ = p.parameter("l")
    p.set_dynamics([v, p.u[0]])
    for s in (x, v):
        p.initial_constraint(s, 0.0)
        p.terminal_constraint(s, 0.0)
    p.path_constraint(x, -ca.inf, l_, name="ceiling")
    p.fixed_final_time(4.0)
    p.minimize_integral(-x)
    return p


def bryson_denham() -> OptimalControlProblem:
    """Bryson-Denham: ``min 1/2 int u^2``, ``x'' = u``, ``x(0)=0, v(0)=1, x(1)=0,
    v(1)=-1``, ``x <= l``. For ``l <= 1/6`` the boundary arc is ``[3l, 1-3l]`` and
    ``J = 4 / (9 l)``; the other arcs have u linear in t (not bang-bang)."""
    p = OptimalControlProblem("bryson_denham")
    x, v = p.state("x"), p.state("v")
    u = p.control("u")
    l_ = p.parameter("l")
    p.set_dynamics([v, u])
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 1.0)
    p.terminal_constraint(x, 0.0)
    p.terminal_constraint(v, -1.0)
    p.path_constraint(x, -ca.inf, l_, name="x <= l")
    p.fixed_final_time(1.0)
    p.minimize_integral(0.5 * u**2)
    return p


def solve_bryson_denham(l_: float, nodes: int = 90):
    ms = MultipleShooting(bryson_denham(), nodes=nodes)
    return ms.solve({"l": l_}, guess=ms.initial_guess(
        x=lambda s: [l_ * np.sin(np.pi * s), 1 - 2 * s], u=[-2.0]))
