"""Time-optimal control of the Rayleigh oscillator (Maurer and Osmolovskii 2004).

``x1' = x2``, ``x2' = -x1 + x2 (1.4 - 0.14 x2^2) + u``, ``|u| <= 4``, from
``(-5, -5)`` to the origin in minimum time. Maurer and Osmolovskii, "Second
order sufficient conditions for time-optimal bang-bang control", SIAM J.
Control Optim. 42(6) 2004, report the bang-bang control ``4, -4, 4`` with
switching times ``t1 = 1.12051``, ``t2 = 3.31005`` and ``t_f = 3.66817`` (and
prove it optimal by second-order conditions). The dynamics are nonlinear in the
state, so the switching-time refinement integrates its arcs with RK8.

The independent check, :func:`rayleigh_min_time_pmp`, solves Pontryagin's
boundary-value problem with scipy alone (DOP853 at 1e-13, ``fsolve``), started
from the published switching times: its costate guess comes from the adjoint
integrated along the published trajectory, normalised by ``H = -1``.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from ocp import OptimalControlProblem, Trajectory
from tests.oracles.ocp_suite.problems import SuiteProblem

PUBLISHED = {"t1": 1.12051, "t2": 3.31005, "tf": 3.66817}
IVP = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}
U_MAX = 4.0
X0 = (-5.0, -5.0)


def rayleigh_min_time() -> OptimalControlProblem:
    """The problem as Maurer and Osmolovskii pose it (|u| <= 4, free final time)."""
    p = OptimalControlProblem("rayleigh_min_time")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", -U_MAX, U_MAX)
    p.set_dynamics({"x1": x2, "x2": -x1 + x2 * (1.4 - 0.14 * x2**2) + u})
    p.initial_constraint(x1, X0[0])
    p.initial_constraint(x2, X0[1])
    p.terminal_constraint(x1, 0.0)
    p.terminal_constraint(x2, 0.0)
    p.free_final_time(0.1, 20.0, guess=3.7)
    p.minimize_terminal(p.T)
    return p


def rayleigh_min_time_guess() -> Trajectory:
    """A straight line from the start to the origin over 3.7, control 0."""
    t = np.linspace(0.0, 3.7, 41)
    s = t / t[-1]
    x = np.column_stack([X0[0] * (1 - s), np.zeros_like(s)])
    return Trajectory(t, x, np.zeros((len(t), 1)), ("x1", "x2"), ("u",))


def _rhs(t: float, y: np.ndarray, u: float) -> list[float]:
    """State and costate (minimum principle, ``H = l1 x2 + l2 f2``)."""
    x1, x2, l1, l2 = y
    return [x2, -x1 + x2 * (1.4 - 0.14 * x2**2) + u, l2, -(l1 + l2 * (1.4 - 0.42 * x2**2))]


def _shoot(z: np.ndarray) -> tuple[np.ndarray, list[float]]:
    """Integrate the bang arcs 4, -4, 4 from ``z = (l1(0), l2(0), t1, t2, tf)``: the end
    state and costate, and sigma = l2 at the two switches."""
    y = np.array([X0[0], X0[1], z[0], z[1]])
    sig = []
    for a, b, u in ((0.0, z[2], U_MAX), (z[2], z[3], -U_MAX), (z[3], z[4], U_MAX)):
        y = solve_ivp(_rhs, (a, b), y, args=(u,), **IVP).y[:, -1]
        sig.append(float(y[3]))
    return y, sig[:2]


def _costate_guess(t1: float, t2: float, tf: float) -> np.ndarray:
    """l(0) from the adjoint integrated backward along the trajectory of given switching
    times, from ``l(t2) = (-1 / x2(t2), 0)`` (sigma(t2) = 0 and H = -1 there)."""
    y = np.array([X0[0], X0[1], 0.0, 0.0])
    y = solve_ivp(_rhs, (0.0, t1), y, args=(U_MAX,), **IVP).y[:, -1]
    y = solve_ivp(_rhs, (t1, t2), y, args=(-U_MAX,), **IVP).y[:, -1]
    y[2:] = [-1.0 / y[1], 0.0]
    y = solve_ivp(_rhs, (t2, t1), y, args=(-U_MAX,), **IVP).y[:, -1]
    y = solve_ivp(_rhs, (t1, 0.0), y, args=(U_MAX,), **IVP).y[:, -1]
    return y[2:]


def rayleigh_min_time_pmp() -> dict[str, float]:
    """Pontryagin's conditions for the 4, -4, 4 structure solved with scipy only.

    Unknowns ``l(0), t1, t2, tf``; equations: the origin reached, ``sigma = l2 = 0`` at
    both switches, ``H(0) = -1`` (minimum time, autonomous).

    Returns
    -------
    dict
        ``t1``, ``t2``, ``tf`` and ``residual`` (largest equation residual).
    """
    p = PUBLISHED

    def residual(z: np.ndarray) -> list[float]:
        y, sig = _shoot(z)
        l1, l2 = z[0], z[1]
        H0 = l1 * X0[1] + l2 * (-X0[0] + X0[1] * (1.4 - 0.14 * X0[1] ** 2) + U_MAX)
        return [y[0], y[1], *sig, H0 + 1.0]

    z0 = np.r_[_costate_guess(p["t1"], p["t2"], p["tf"]), p["t1"], p["t2"], p["tf"]]
    with warnings.catch_warnings():  # it stalls at rounding level (the residual says so)
        warnings.simplefilter("ignore", RuntimeWarning)
        z = fsolve(residual, z0, xtol=1e-14)
    return {"t1": float(z[2]), "t2": float(z[3]), "tf": float(z[4]),
            "residual": float(np.max(np.abs(residual(z))))}


def rayleigh_min_time_exact() -> float:
    """The minimum time from :func:`rayleigh_min_time_pmp`."""
    return rayleigh_min_time_pmp()["tf"]


PROBLEM = SuiteProblem(
    "rayleigh_min_time", "Maurer and Osmolovskii (2004), SIAM J. Control Optim. 42(6), "
    "Rayleigh problem: t1 = 1.12051, t2 = 3.31005, t_f = 3.66817",
    PUBLISHED["tf"], 2e-6, rayleigh_min_time, exact=rayleigh_min_time_exact,
    covers=("bang-bang, one control", "free final time", "dynamics nonlinear in the state",
            "bang-bang solved by collocation and certified"),
    bang_bang=True, intervals=20, tol=1e-7, guess=rayleigh_min_time_guess,
    notes="exact: Pontryagin's boundary-value problem solved with scipy (DOP853, fsolve)")
