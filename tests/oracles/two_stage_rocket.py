"""A two-stage ascent in SI units: velocities from 0 to about 7e3 m/s, positions to 1e6 m.

Posed as a researcher would, with the public API and no ``ref``: a point mass over a
flat Earth (g = 9.81 m/s^2) in three dimensions, thrust of fixed magnitude along the
unit vector ``u`` (``|u| = 1``), stage 1 burning from rest for 120 s, its dry mass
dropped, stage 2 burning 180 s more; reach an altitude of 200 km with no vertical
speed, maximising the horizontal speed. Every velocity starts at a fixed 0, so its
default guess (0) says nothing of its size, and the bounds give none.

Independent check (:func:`rocket_exact`): with constant thrust and flat gravity the
costates of position are constant and those of velocity linear in time, so the
optimal direction obeys the linear tangent law ``tan(theta) = c1 + c2 t`` (Bryson and
Ho, section 2.7) in the vertical plane of the horizontal velocity; scipy's
``solve_ivp`` integrates the ascent and ``fsolve`` finds ``(c1, c2)`` meeting the
altitude and vertical-speed targets. No part of ``ocp`` is used.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from ocp import MultiPhaseProblem

G = 9.81
M0 = 1.2e5  # kg, lift-off mass
DRY1 = 1.2e4  # kg, stage 1's dry mass, dropped at separation
STAGES = ((2.0e6, 280.0, 120.0), (3.0e5, 340.0, 180.0))  # thrust N, Isp s, burn s
Z_TARGET = 2.0e5  # m


def rocket(refs: bool = False) -> MultiPhaseProblem:
    """The ascent as two phases; ``refs`` gives the three velocities ``ref=1e4``.

    Parameters
    ----------
    refs : bool
        Hand-set ``ref`` on the velocities (the dymos habit), for comparison.
    """
    mp = MultiPhaseProblem("two_stage_ascent")
    phases = [mp.phase("stage1"), mp.phase("stage2")]
    t = 0.0
    for ph, (thrust, isp, burn) in zip(phases, STAGES, strict=True):
        for n in ("x", "y"):
            ph.state(n)
        ph.state("z", lower=0.0)
        vel = [ph.state(n, **({"ref": 1e4} if refs else {})) for n in ("vx", "vy", "vz")]
        m = ph.state("m", lower=1e3, upper=M0)
        u = [ph.control(n, lower=-1.0, upper=1.0, guess=g)
             for n, g in (("ux", 0.6), ("uy", 0.0), ("uz", 0.8))]
        a = [thrust * c / m for c in u]
        ph.set_dynamics({"x": vel[0], "y": vel[1], "z": vel[2], "vx": a[0], "vy": a[1],
                         "vz": a[2] - G, "m": -thrust / (isp * 9.80665) + 0 * m})
        ph.path_constraint(u[0] ** 2 + u[1] ** 2 + u[2] ** 2, 1.0, 1.0, name="unit thrust")
        if ph is phases[0]:
            ph.fixed_final_time(burn)
        else:
            ph.fixed_duration(burn)
        t += burn
    first, second = phases
    for k, n in enumerate(("x", "y", "z", "vx", "vy", "vz")):
        first.initial_constraint(first.x[k], 0.0, name=f"{n}(0)")
    first.initial_constraint(first.x[6], M0, name="m(0)")
    mp.link(first, second, states=("x", "y", "z", "vx", "vy", "vz"))
    mp.link_constraint(second.at_t0(second.x[6]) - first.at_tf(first.x[6]), -DRY1,
                       name="separation")
    second.terminal_constraint(second.x[2], Z_TARGET, name="altitude")
    second.terminal_constraint(second.x[5], 0.0, name="vertical speed")
    mp.minimize(-second.at_tf(second.x[3]))
    return mp


def _flight(c: np.ndarray) -> np.ndarray:
    """Final (z, vz, vx) under the linear tangent law ``tan(theta) = c1 + c2 t``."""
    y = np.array([0.0, 0.0, 0.0, 0.0, M0])  # x, z, vx, vz, m
    t0 = 0.0
    for k, (thrust, isp, burn) in enumerate(STAGES):
        if k:
            y[4] -= DRY1
        rate = thrust / (isp * 9.80665)

        def rhs(t: float, s: np.ndarray, thrust: float = thrust,
                rate: float = rate) -> list[float]:
            th = math.atan(c[0] + c[1] * t)
            a = thrust / s[4]
            return [s[2], s[3], a * math.cos(th), a * math.sin(th) - G, -rate]

        y = solve_ivp(rhs, (t0, t0 + burn), y, method="DOP853", rtol=1e-12,
                      atol=1e-9).y[:, -1]
        t0 += burn
    return np.array([y[1], y[3], y[2]])


@cache
def rocket_exact() -> tuple[float, float, float]:
    """(final horizontal speed, c1, c2) of the linear tangent law meeting the targets."""
    c = fsolve(lambda c: (_flight(c)[:2] - [Z_TARGET, 0.0]) / [1e5, 1e3], [1.0, -0.01],
               xtol=1e-13)
    return float(_flight(c)[2]), float(c[0]), float(c[1])
