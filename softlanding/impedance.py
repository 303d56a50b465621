"""Impedance control: depth maps over (k_p, k_d), optimal gains, curves over v0.

Everything here runs the exact simulator (:func:`softlanding.simulate_batch`)
on the same dynamics as the rest of the toolkit. Landings that leave the
stroke ``0 <= x_b - x_f <= s`` are infeasible and excluded from optima, as in
the paper.

Gain optimisation goes beyond the paper's grid search. The depth surface has
kinks where the number of intrusion steps changes, and the optimum lies on the
stroke-limit boundary, so gradients are unreliable and an unconstrained
minimiser would step into the infeasible region. We therefore refine by a
*zooming feasible grid*: 21 x 21 gains around the incumbent, each level ten
times finer than the last, infeasible points excluded, until the spacing is
below 1e-8; a final bisection in ``k_p`` then puts a boundary optimum on the
stroke limit to 1e-12. The result is never worse than the best grid point
(the incumbent is kept at every level) and is re-simulated to confirm it is
feasible.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .errors import ParameterError, check_impact_velocity, check_positive
from .scaling import DimensionlessParams
from .simulate import Impedance, simulate, simulate_batch

OBJECTIVES = ("depth", "cot", "cot-lossless")
GAIN_RANGE = (0.0, 1.0)


def _objective_values(b, objective: str) -> np.ndarray:
    if objective == "depth":
        v = b.depth
    elif objective == "cot":
        v = b.cot
    elif objective == "cot-lossless":
        v = b.cot_lossless
    else:
        raise ParameterError("objective", f"must be one of {OBJECTIVES}, got {objective!r}")
    return np.where(strictly_feasible(b) & np.isfinite(v), v, np.inf)


def stroke_margin(b) -> np.ndarray:
    """Distance to the nearer stroke limit (negative when a limit is crossed)."""
    s = b.inputs["s"]
    return np.minimum(b.stroke_min, s - b.stroke_max)


def strictly_feasible(b) -> np.ndarray:
    """Rest proven and the stroke limits kept exactly (the simulator's ``feasible``
    allows 1e-9 s of rounding at a limit; an optimiser would exploit that)."""
    return (b.status == 0) & (stroke_margin(b) >= 0.0)


@dataclass
class ImpedanceOptimum:
    """Optimal impedance gains and the landing they give.

    ``on_stroke_boundary`` is true when the stroke margin at the optimum is
    below 1e-6 (the paper finds all depth optima there); ``active_constraint``
    names the limit. ``grid_best`` is the best point of the starting grid.
    """

    objective: str
    v0: float
    r_m: float
    s: float
    kp: float
    kd: float
    value: float
    depth: float
    steps: int
    u_peak: float
    stroke_min: float
    stroke_max: float
    cot: float
    cot_lossless: float
    on_stroke_boundary: bool
    active_constraint: str | None
    grid_best: dict
    evaluations: int

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in d.items()}


def _check(v0, r_m, s, objective):
    check_impact_velocity("v0", v0)
    check_positive("r_m", r_m)
    check_positive("s", s)
    if objective not in OBJECTIVES:
        raise ParameterError("objective", f"must be one of {OBJECTIVES}, got {objective!r}")
    if objective != "depth" and v0 == 0.0:
        raise ParameterError("v0", "CoT is undefined at v0 = 0 (no impact energy)")


def optimize_impedance(v0: float, r_m: float = 5.0, s: float = 20.0, *,
                       objective: str = "depth", grid: int = 101,
                       kp_range: tuple[float, float] = GAIN_RANGE,
                       kd_range: tuple[float, float] = GAIN_RANGE,
                       u_max: float | None = None, tol: float = 1e-8) -> ImpedanceOptimum:
    """Minimise depth (or CoT) over the gains, subject to the stroke limits.

    Parameters
    ----------
    v0, r_m, s : float
        Impact velocity and model parameters.
    objective : {"depth", "cot", "cot-lossless"}
        ``cot`` counts ground and actuator losses, ``cot-lossless`` the ground only.
    grid : int
        Points per axis of the starting grid (the paper: 101, steps of 0.01).
    kp_range, kd_range : (float, float)
        Gain box searched.
    u_max : float, optional
        Saturate the force.
    tol : float
        Final grid spacing of the refinement.

    Raises
    ------
    ParameterError
        Bad parameters, or no feasible gains in the box.
    """
    _check(v0, r_m, s, objective)
    energy = objective != "depth"
    kp = np.linspace(*kp_range, grid)
    kd = np.linspace(*kd_range, grid)
    b = simulate_batch(kp[:, None], kd[None, :], v0, r_m, s, u_max, energy=energy)
    J = _objective_values(b, objective)
    evals = J.size
    if not np.isfinite(J).any():
        raise ParameterError("k_p", "no feasible gains in the box: every landing leaves the "
                                    "stroke limits")
    i, j = np.unravel_index(np.argmin(J), J.shape)
    best = (float(kp[i]), float(kd[j]), float(J[i, j]))
    grid_best = {"kp": best[0], "kd": best[1], "value": best[2]}
    h = (kp[1] - kp[0], kd[1] - kd[0])
    n = 21
    while max(h) > tol:
        cp = np.clip(np.linspace(best[0] - h[0], best[0] + h[0], n), *kp_range)
        cd = np.clip(np.linspace(best[1] - h[1], best[1] + h[1], n), *kd_range)
        b = simulate_batch(cp[:, None], cd[None, :], v0, r_m, s, u_max, energy=energy)
        Jz = _objective_values(b, objective)
        evals += Jz.size
        a, c = np.unravel_index(np.argmin(Jz), Jz.shape)
        if Jz[a, c] < best[2]:
            best = (float(cp[a]), float(cd[c]), float(Jz[a, c]))
        h = (2 * h[0] / (n - 1), 2 * h[1] / (n - 1))
    kp_s, kd_s, val = best
    # a boundary optimum: bisect k_p onto the stroke limit (feasible side)
    probe = simulate_batch([kp_s - 2 * tol, kp_s], kd_s, v0, r_m, s, u_max, energy=energy)
    evals += 2
    pf = strictly_feasible(probe)
    if not pf[0] and pf[1]:
        lo, hi = kp_s - 2 * tol, kp_s
        while hi - lo > 1e-12:
            mids = np.linspace(lo, hi, 34)[1:-1]
            pb = simulate_batch(mids, kd_s, v0, r_m, s, u_max, energy=energy)
            evals += mids.size
            feas = strictly_feasible(pb)
            if feas.any():
                k = int(np.argmax(feas))
                hi = mids[k]
                lo = mids[k - 1] if k > 0 else lo
            else:
                lo = mids[-1]
        fin = simulate_batch([hi], kd_s, v0, r_m, s, u_max, energy=energy)
        v_hi = float(_objective_values(fin, objective)[0])
        if v_hi <= val:
            kp_s, val = hi, v_hi
    p = DimensionlessParams(r_m=r_m, s=s, v0=v0)
    res = simulate(p, Impedance(kp_s, kd_s, u_max))
    if not (res.rest_proven and res.stroke_min >= 0 and res.stroke_max <= s):
        # never report infeasible gains
        raise RuntimeError("refined gains are infeasible on re-simulation; please report")
    margin = min(res.stroke_min, s - res.stroke_max)
    on_boundary = margin <= 1e-6
    active = None
    if on_boundary:
        active = ("stroke lower limit x_b - x_f >= 0" if res.stroke_min <= s - res.stroke_max
                  else "stroke upper limit x_b - x_f <= s")
    return ImpedanceOptimum(
        objective=objective, v0=v0, r_m=r_m, s=s, kp=kp_s, kd=kd_s, value=val,
        depth=res.depth, steps=res.steps, u_peak=res.u_peak, stroke_min=res.stroke_min,
        stroke_max=res.stroke_max, cot=res.energy.cot, cot_lossless=res.energy.cot_lossless,
        on_stroke_boundary=on_boundary, active_constraint=active, grid_best=grid_best,
        evaluations=evals)
