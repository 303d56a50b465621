"""The suite: classic optimal control problems with published optima, posed with ``ocp``.

Every problem cites its source. ``published`` is the value as published;
``rtol`` is how closely it can be expected to match, given the published
digits and, where the source itself is a discretisation (the COPS values come
from finite-dimensional NLPs), that discretisation's error. Where a closed
form or an independent computation exists, ``exact`` returns it, and the test
holds the refined solution to ``exact_rtol`` of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve, least_squares

from ocp import MultiPhaseProblem, OptimalControlProblem, Trajectory


@dataclass
class SuiteProblem:
    """One problem of the suite and how to solve and judge it."""

    name: str
    source: str
    published: float
    rtol: float  # agreement with the published value that its precision allows
    build: Callable[[], Any]
    value: Callable[[Any], float] = lambda sol: sol.objective
    exact: Callable[[], float] | None = None  # closed form / independent computation
    exact_rtol: float = 1e-6
    covers: tuple[str, ...] = ()
    bang_bang: bool = False
    intervals: int | list[int] = 10
    degree: int = 3
    tol: float = 1e-7  # mesh-refinement accuracy
    max_rounds: int = 8
    slow: bool = False
    guess: Callable[[], Trajectory] | None = None  # a starting trajectory, if needed
    notes: str = ""
    rockit: dict[str, Any] = field(default_factory=dict)


# ------------------------------------------------------------------ Bryson-Denham
def bryson_denham(ell: float = 1 / 9) -> OptimalControlProblem:
    """min 1/2 int u^2, x'' = u, x(0) = x(1) = 0, x'(0) = 1, x'(1) = -1, x <= ell."""
    p = OptimalControlProblem("bryson_denham")
    x = p.state("x", upper=ell)
    v = p.state("v")
    u = p.control("u")
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 1.0)
    p.terminal_constraint(x, 0.0)
    p.terminal_constraint(v, -1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2 / 2)
    return p


def bryson_denham_phases(ell: float = 1 / 9) -> MultiPhaseProblem:
    """Bryson-Denham as three phases: free arc, boundary arc on x = ell (a static phase
    with its own dynamics x' = v' = 0), free arc; junction times free."""
    mp = MultiPhaseProblem("bryson_denham_3phase")
    a, b, c = mp.phase("rise"), mp.phase("boundary"), mp.phase("fall")
    for ph in (a, c):
        ph.state("x", upper=ell)
        v = ph.state("v")
        u = ph.control("u")
        ph.set_dynamics({"x": v, "v": u})
        ph.minimize_integral(u**2 / 2)
    b.state("x")
    b.state("v")
    b.set_dynamics({"x": 0.0, "v": 0.0})
    a.initial_constraint(a.x[0], 0.0)
    a.initial_constraint(a.x[1], 1.0)
    a.terminal_constraint(a.x[0], ell)  # the phase ends on the state constraint
    a.free_final_time(0.05, 0.5, guess=0.3)
    b.initial_constraint(b.x[1], 0.0)
    b.free_duration(0.0, 1.0, guess=0.4)
    c.terminal_constraint(c.x[0], 0.0)
    c.terminal_constraint(c.x[1], -1.0)
    c.fixed_final_time(1.0)
    mp.link(a, b)
    mp.link(b, c)
    return mp


# ------------------------------------------------------------------ brachistochrone
def brachistochrone() -> OptimalControlProblem:
    """dymos' brachistochrone: (0, 10) to (10, 5), g = 9.80665, minimum time."""
    g = 9.80665
    p = OptimalControlProblem("brachistochrone")
    x, y, v = p.state("x"), p.state("y"), p.state("v")
    th = p.control("theta", 0.0, math.pi)
    p.set_dynamics({"x": v * ca.sin(th), "y": -v * ca.cos(th), "v": g * ca.cos(th)})
    for s, a in ((x, 0.0), (y, 10.0), (v, 0.0)):
        p.initial_constraint(s, a)
    p.terminal_constraint(x, 10.0)
    p.terminal_constraint(y, 5.0)
    p.free_final_time(0.5, 10.0, guess=2.0)
    p.minimize_terminal(p.T)
    return p


def brachistochrone_exact() -> float:
    """The cycloid through both points: (phi - sin phi) / (1 - cos phi) = dx / dy."""
    g, dx, dy = 9.80665, 10.0, 5.0
    phi = brentq(lambda f: (f - math.sin(f)) / (1 - math.cos(f)) - dx / dy, 1e-3,
                 2 * math.pi - 1e-3)
    r = dy / (1 - math.cos(phi))
    return phi * math.sqrt(r / g)


# ------------------------------------------------------------------ moon lander
MOON = {"g": 1.0, "E": 2.349, "umax": 1.227, "h0": 1.0, "v0": -0.783}


def moon_lander() -> OptimalControlProblem:
    """Soft lunar landing with least fuel (Meditch 1964; PSOPT/PROPT 'moon lander')."""
    c = MOON
    p = OptimalControlProblem("moon_lander")
    h, v = p.state("h"), p.state("v")
    m = p.state("m", lower=0.01, upper=1.0)
    u = p.control("u", 0.0, c["umax"])
    p.set_dynamics({"h": v, "v": -c["g"] + u / m, "m": -u / c["E"]})
    for s, a in ((h, c["h0"]), (v, c["v0"]), (m, 1.0)):
        p.initial_constraint(s, a)
    p.terminal_constraint(h, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.1, 10.0, guess=1.5)
    p.minimize_integral(u)
    return p


def moon_lander_exact() -> float:
    """Free fall to a switch time s, then full thrust to touchdown (closed-form arcs)."""
    c = MOON
    g, E, U, h0, v0 = c["g"], c["E"], c["umax"], c["h0"], c["v0"]

    def burn(tau: float, hs: float, vs: float) -> tuple[float, float]:
        m = 1 - U * tau / E  # mass after burning for tau from m = 1
        v = vs - g * tau - E * math.log(m)
        h = hs + vs * tau - g * tau**2 / 2 + E * (tau + (E / U) * m * math.log(m))
        return h, v

    def end(s: float) -> tuple[float, float]:
        hs, vs = h0 + v0 * s - g * s**2 / 2, v0 - g * s
        tau = brentq(lambda t: burn(t, hs, vs)[1], 1e-9, E / U * (1 - 1e-9))
        return burn(tau, hs, vs)[0], tau

    s = brentq(lambda s: end(s)[0], 0.0, 1.0)
    return U * end(s)[1]


# ------------------------------------------------------------------ COPS problems
def goddard() -> OptimalControlProblem:
    """COPS 'rocket' (Goddard): maximise the final altitude; thrust with a singular arc."""
    h0, v0, m0, g0, Tc, hc, vc, mc = 1.0, 0.0, 1.0, 1.0, 3.5, 500.0, 620.0, 0.6
    c = 0.5 * math.sqrt(g0 * h0)
    mf, Dc, Tmax = mc * m0, 0.5 * vc * m0 / g0, Tc * m0 * g0
    p = OptimalControlProblem("goddard")
    h = p.state("h", lower=1.0, guess=(1.0, 1.01))
    v = p.state("v", lower=0.0, guess=0.05)
    m = p.state("m", lower=mf, upper=m0)
    T = p.control("thrust", 0.0, Tmax)
    D = Dc * v**2 * ca.exp(-hc * (h - h0) / h0)
    g = g0 * (h0 / h) ** 2
    p.set_dynamics({"h": v, "v": (T - D - m * g) / m, "m": -T / c})
    for s, a in ((h, h0), (v, v0), (m, m0)):
        p.initial_constraint(s, a)
    p.terminal_constraint(m, mf)
    p.free_final_time(0.05, 1.0, guess=0.2)
    p.minimize_terminal(-h)
    return p


def catalyst_mixing() -> OptimalControlProblem:
    """COPS 'catmix' (Gunn and Thomas 1965): singular control of a catalyst blend."""
    p = OptimalControlProblem("catalyst_mixing")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", 0.0, 1.0)
    p.set_dynamics({"x1": u * (10 * x2 - x1), "x2": u * (x1 - 10 * x2) - (1 - u) * x2})
    p.initial_constraint(x1, 1.0)
    p.initial_constraint(x2, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_terminal(-1 + x1 + x2)
    return p


def robot_arm() -> OptimalControlProblem:
    """COPS 'robot' (Monta\u00f1o 1998): minimum-time motion of a robot arm, three bounded
    torques, bang-bang."""
    L = 5.0
    p = OptimalControlProblem("robot_arm")
    rho = p.state("rho", 0.0, L)
    the = p.state("the", -math.pi, math.pi)
    phi = p.state("phi", 0.0, math.pi)
    rd, td, pd = p.state("rho_dot"), p.state("the_dot"), p.state("phi_dot")
    ur, ut, up = (p.control(n, -1.0, 1.0) for n in ("u_rho", "u_the", "u_phi"))
    i_the = ((L - rho) ** 3 + rho**3) * ca.sin(phi) ** 2 / 3
    i_phi = ((L - rho) ** 3 + rho**3) / 3
    p.set_dynamics({"rho": rd, "the": td, "phi": pd, "rho_dot": ur / L,
                    "the_dot": ut / i_the, "phi_dot": up / i_phi})
    for s, a0, a1 in ((rho, 4.5, 4.5), (the, 0.0, 2 * math.pi / 3), (phi, math.pi / 4,
                                                                      math.pi / 4),
                      (rd, 0.0, 0.0), (td, 0.0, 0.0), (pd, 0.0, 0.0)):
        p.initial_constraint(s, a0)
        p.terminal_constraint(s, a1)
    p.free_final_time(1.0, 20.0, guess=9.0)
    p.minimize_terminal(p.T)
    return p


def hanging_chain() -> OptimalControlProblem:
    """COPS 'chain': the chain of length 4 between heights 1 and 3 with least potential
    energy; an isoperimetric (integral) constraint."""
    p = OptimalControlProblem("hanging_chain")
    x = p.state("x")
    u = p.control("u")
    p.set_dynamics({"x": u})
    p.initial_constraint(x, 1.0)
    p.terminal_constraint(x, 3.0)
    p.integral_constraint(ca.sqrt(1 + u**2), 4.0, name="length")
    p.fixed_final_time(1.0)
    p.minimize_integral(x * ca.sqrt(1 + u**2))
    return p


def hanging_chain_guess() -> Trajectory:
    """COPS' starting point: a parabola through both ends, sagging below them."""
    t = np.linspace(0.0, 1.0, 41)
    x = 4 * 2 * t * (t / 2 - 1 / 4) + 1
    return Trajectory(t, x[:, None], (8 * (t - 1 / 4))[:, None], ("x",), ("u",))


def hanging_chain_exact() -> float:
    """The catenary ``x + lam = C cosh((t - D) / C)`` through both ends with length 4."""
    a, b, L = 1.0, 3.0, 4.0

    def eqs(z: np.ndarray) -> list[float]:
        C, D, lam = z
        return [C * math.cosh(-D / C) - lam - a, C * math.cosh((1 - D) / C) - lam - b,
                C * (math.sinh((1 - D) / C) - math.sinh(-D / C)) - L]

    C, D, lam = fsolve(eqs, [0.3, 0.4, -0.1], xtol=1e-13)
    s0, s1 = -D / C, (1 - D) / C
    cosh2 = (s1 - s0) / 2 + (math.sinh(2 * s1) - math.sinh(2 * s0)) / 4
    return C**2 * cosh2 - lam * L


PINENE_TAU = [1230.0, 3060.0, 4920.0, 7800.0, 10680.0, 15030.0, 22620.0, 36420.0]
PINENE_Z = np.array([
    [88.35, 7.3, 2.3, 0.4, 1.75], [76.4, 15.6, 4.5, 0.7, 2.8], [65.1, 23.1, 5.3, 1.1, 5.8],
    [50.4, 32.9, 6.0, 1.5, 9.3], [37.5, 42.7, 6.0, 1.9, 12.0], [25.9, 49.1, 5.9, 2.2, 17.0],
    [14.0, 57.4, 5.1, 2.6, 21.0], [4.5, 63.1, 3.8, 2.9, 25.7]])


def _pinene_rhs(y: Any, th: Any) -> list[Any]:
    return [-(th[0] + th[1]) * y[0], th[0] * y[0],
            th[1] * y[0] - (th[2] + th[3]) * y[2] + th[4] * y[4],
            th[2] * y[2], th[3] * y[2] - th[4] * y[4]]


def pinene() -> MultiPhaseProblem:
    """COPS 'pinene' (Box et al. 1973): five rate constants of the isomerisation of
    alpha-pinene fitted to eight measurements; one phase per measurement interval,
    the rate constants are decision parameters shared by all phases."""
    mp = MultiPhaseProblem("pinene")
    th = [mp.variable(f"theta{i + 1}", 0.0, 1e-3, guess=g)
          for i, g in enumerate((5.9e-5, 2.9e-5, 2.0e-5, 2.7e-4, 4.0e-5))]
    names = [f"y{i + 1}" for i in range(5)]
    start = 0.0
    prev = None
    J = 0
    for j, tau in enumerate(PINENE_TAU):
        ph = mp.phase(f"to_{int(tau)}")
        ys = [ph.state(n, guess=(float(a), float(b))) for n, a, b in
              zip(names, PINENE_Z[j - 1] if j else [100.0, 0, 0, 0, 0], PINENE_Z[j],
                  strict=True)]
        ph.set_dynamics(dict(zip(names, _pinene_rhs(ys, th), strict=True)))
        ph.fixed_final_time(tau)
        if prev is None:
            ph.fixed_initial_time(start)
            for y, y0 in zip(ys, (100.0, 0.0, 0.0, 0.0, 0.0), strict=True):
                ph.initial_constraint(y, y0)
        else:
            mp.link(prev, ph)
        J = J + sum((ph.at_tf(y) - z) ** 2 for y, z in zip(ys, PINENE_Z[j], strict=True))
        prev = ph
    mp.minimize(J)
    return mp


def pinene_exact() -> float:
    """Least squares on the exact (matrix-exponential) solution of the linear ODE."""
    def resid(th: np.ndarray) -> np.ndarray:
        A = np.array([[-(th[0] + th[1]), 0, 0, 0, 0], [th[0], 0, 0, 0, 0],
                      [th[1], 0, -(th[2] + th[3]), 0, th[4]], [0, 0, th[2], 0, 0],
                      [0, 0, th[3], 0, -th[4]]])
        y0 = np.array([100.0, 0, 0, 0, 0])
        return np.concatenate([expm(A * t) @ y0 - z for t, z in zip(PINENE_TAU, PINENE_Z,
                                                                     strict=True)])
    x0 = np.array([5.9e-5, 2.9e-5, 2.0e-5, 2.7e-4, 4.0e-5])
    r = least_squares(resid, x0, x_scale=x0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return float(np.sum(r.fun**2))


# ------------------------------------------------------------------ others
def orbit_raising() -> OptimalControlProblem:
    """Bryson and Ho's maximum-radius orbit transfer in a fixed time (thrust
    acceleration T / (m0 - |mdot| t): the time symbol in the dynamics). The thrust
    direction is the unit vector (u1, u2), as in GPOPS-II, not an angle."""
    T, mdot, tf = 0.1405, 0.0749, 3.32
    p = OptimalControlProblem("orbit_raising")
    r, th, vr, vt = p.state("r", lower=0.5), p.state("theta"), p.state("vr"), p.state("vt")
    u1, u2 = p.control("u1", -1.0, 1.0, guess=0.5), p.control("u2", -1.0, 1.0, guess=0.5)
    a = T / (1 - mdot * p.t)
    p.set_dynamics({"r": vr, "theta": vt / r, "vr": vt**2 / r - 1 / r**2 + a * u1,
                    "vt": -vr * vt / r + a * u2})
    p.path_constraint(u1**2 + u2**2, 1.0, 1.0, name="unit thrust direction")
    for s, v0 in ((r, 1.0), (th, 0.0), (vr, 0.0), (vt, 1.0)):
        p.initial_constraint(s, v0)
    p.terminal_constraint(vr, 0.0)
    p.terminal_constraint(vt - 1 / ca.sqrt(r), 0.0, name="circular")
    p.fixed_final_time(tf)
    p.minimize_terminal(-r)
    return p


def teo_state_constraint() -> OptimalControlProblem:
    """Teo, Goh and Wong (1991) / MISER3: a time-varying state constraint that is active
    on an arc (the constraint that multiple shooting violates between coarse nodes)."""
    p = OptimalControlProblem("teo_state_constraint")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", -20.0, 20.0)
    p.set_dynamics({"x1": x2, "x2": -x2 + u})
    p.initial_constraint(x1, 0.0)
    p.initial_constraint(x2, -1.0)
    p.path_constraint(8 * (p.t - 0.5) ** 2 - 0.5 - x2, lower=0.0, name="x2 below parabola")
    p.fixed_final_time(1.0)
    p.minimize_integral(x1**2 + x2**2 + 0.005 * u**2)
    return p


def rayleigh_mixed() -> OptimalControlProblem:
    """The Rayleigh problem with the mixed state-control constraint u + x1/6 <= 0
    (Maurer and Augustin 2001; Betts 2010, example 4.10; PSOPT 'rayleigh')."""
    p = OptimalControlProblem("rayleigh_mixed")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u")
    p.set_dynamics({"x1": x2, "x2": -x1 + x2 * (1.4 - 0.14 * x2**2) + 4 * u})
    p.initial_constraint(x1, -5.0)
    p.initial_constraint(x2, -5.0)
    p.path_constraint(u + x1 / 6, upper=0.0, name="u + x1/6 <= 0")
    p.fixed_final_time(4.5)
    p.minimize_integral(u**2 + x1**2)
    return p


PROBLEMS: list[SuiteProblem] = [
    SuiteProblem(
        "bryson_denham", "Bryson and Ho (1975), Applied Optimal Control, sec. 3.11: "
        "J = 4/(9 l) for l <= 1/6; GPOPS-II and PSOPT examples",
        4.0, 1e-6, bryson_denham, exact=lambda: 4 / (9 * (1 / 9)),
        covers=("state-constrained arc (second order)", "state bounds"), intervals=12),
    SuiteProblem(
        "bryson_denham_3phase", "Bryson and Ho (1975) sec. 3.11 posed as free arc / "
        "boundary arc / free arc (junctions 3l and 1 - 3l)",
        4.0, 1e-6, bryson_denham_phases, exact=lambda: 4.0,
        covers=("multi-phase", "phase constraint active (phase ends on x = l)",
                "different dynamics per phase", "free initial times"),
        intervals=[4, 2, 4]),
    SuiteProblem(
        "brachistochrone", "dymos brachistochrone example (T = 1.8016); Bernoulli's cycloid",
        1.8016, 5e-5, brachistochrone, exact=brachistochrone_exact,
        covers=("free final time",), intervals=8),
    SuiteProblem(
        "moon_lander", "Meditch (1964), IEEE TAC 9(4); PSOPT/PROPT 'moon lander' "
        "(exhaust velocity 2.349, thrust <= 1.227)",
        math.nan, 0.0, moon_lander, exact=moon_lander_exact,
        covers=("bang-bang, one control", "free final time", "1/m dynamics"),
        bang_bang=True, intervals=10, tol=1e-8),
    SuiteProblem(
        "goddard", "COPS 3.0 'rocket' (Dolan, More, Munson 2004): h(T) = 1.01283",
        1.01283, 1e-5, goddard, value=lambda sol: -sol.objective,
        covers=("singular arc", "free final time", "state bounds"), intervals=20,
        tol=1e-6),
    SuiteProblem(
        "catalyst_mixing", "COPS 3.0 'catmix' (Gunn and Thomas 1965): J = -4.80556e-2",
        -4.80556e-2, 2e-5, catalyst_mixing, covers=("singular arc",), intervals=20),
    SuiteProblem(
        "robot_arm", "COPS 3.0 'robot' (Montano 1998): t_f = 9.14138",
        9.14138, 1e-4, robot_arm,
        covers=("bang-bang, several controls", "free final time", "state bounds"),
        bang_bang=True, intervals=20, tol=1e-6,
        notes="COPS' value is a trapezoidal discretisation (nh = 200)"),
    SuiteProblem(
        "hanging_chain", "COPS 3.0 'chain' (length 4, ends at 1 and 3): J = 5.06852",
        5.06852, 1e-5, hanging_chain, exact=hanging_chain_exact, guess=hanging_chain_guess,
        covers=("integral (isoperimetric) constraint",), intervals=10),
    SuiteProblem(
        "pinene", "COPS 3.0 'pinene' (Box, Hunter, MacGregor, Erjavec 1973): J = 19.8721",
        19.8721, 5e-6, pinene, exact=pinene_exact,
        covers=("decision parameters", "multi-phase (8 phases)", "fixed interior times"),
        intervals=2),
    SuiteProblem(
        "orbit_raising", "Bryson and Ho (1975) sec. 2.5, maximum-radius orbit transfer: "
        "r(t_f) = 1.5252 (also GPOPS-II, PSOPT)",
        1.5252, 1e-4, orbit_raising, value=lambda sol: -sol.objective,
        covers=("time-dependent dynamics (time symbol)",), intervals=10),
    SuiteProblem(
        "teo_state_constraint", "Teo, Goh, Wong (1991) / MISER3 manual; PROPT "
        "'continuous state constraint' J = 0.169824306",
        0.169824306, 3e-5, teo_state_constraint,
        covers=("state constraint between nodes", "time-varying path constraint"),
        intervals=10,
        notes="PROPT's value comes from a 50-point collocation"),
    SuiteProblem(
        "rayleigh_mixed", "Maurer and Augustin (2001); Betts (2010) ex. 4.10; PSOPT 'rayleigh'",
        44.8044433, 1e-6, rayleigh_mixed,
        covers=("mixed state-control constraint",), intervals=10,
        notes="published value recalled from Betts (2010), not re-read from the text; "
              "also checked against multiple shooting extrapolated (first order)"),
]
