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

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from softlanding.errors import ParameterError, check_count
from softlanding.model.controllers import Impedance
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, Impact, Robot
from softlanding.simulation.simulator import BatchResult, simulate, simulate_batch
from softlanding.util.jsonable import json_safe

OBJECTIVES = ("depth", "cot", "cot-lossless")
GAIN_RANGE = (0.0, 1.0)
MAX_GRID = 2001
"""Largest starting grid per axis (4 million landings)."""


def _objective_values(b: BatchResult, objective: str) -> np.ndarray:
    if objective == "depth":
        v = b.depth
    elif objective == "cot":
        v = b.cot
    else:
        v = b.cot_lossless
    return np.where(b.strictly_feasible & np.isfinite(v), v, np.inf)


@dataclass
class ImpedanceOptimum:
    """Optimal impedance gains and the landing they give.

    Parameters
    ----------
    objective : str
        ``"depth"``, ``"cot"`` or ``"cot-lossless"``.
    robot, impact, ground
        The problem solved.
    k_p, k_d : float
        Optimal gains.
    value : float
        Objective at the optimum.
    depth, steps, u_peak, stroke_min, stroke_max, cot, cot_lossless
        The optimal landing's figures
        (see :class:`~softlanding.simulation.simulator.LandingResult`).
    on_stroke_boundary : bool
        The stroke margin at the optimum is below 1e-6 (the paper finds all depth
        optima there).
    active_constraint : str or None
        Which stroke limit, when on the boundary.
    grid_best : dict
        ``k_p, k_d, value`` of the best point of the starting grid.
    evaluations : int
        Landings simulated.
    """

    objective: str
    robot: Robot
    impact: Impact
    k_p: float
    k_d: float
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
    grid_best: dict[str, float]
    evaluations: int
    ground: Ground = field(default=LINEAR_GROUND)

    @property
    def v0(self) -> float:
        """The impact velocity."""
        return self.impact.v0

    @property
    def controller(self) -> Impedance:
        """The optimal impedance."""
        return Impedance(self.k_p, self.k_d)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (non-finite numbers become None)."""
        d = {k: getattr(self, k) for k in (
            "objective", "v0", "k_p", "k_d", "value", "depth", "steps", "u_peak", "stroke_min",
            "stroke_max", "cot", "cot_lossless", "on_stroke_boundary", "active_constraint",
            "grid_best", "evaluations")}
        d.update(robot=self.robot.to_dict(), ground=self.ground.to_dict())
        return json_safe(d)


def _check(impact: Impact, objective: str, grid: int) -> None:
    if objective not in OBJECTIVES:
        raise ParameterError("objective", f"must be one of {', '.join(OBJECTIVES)}, "
                                          f"got {objective!r}")
    if objective != "depth" and impact.v0 == 0.0:
        raise ParameterError("v0", "CoT is undefined at v0 = 0 (no impact energy)")
    check_count("grid", grid, 2, MAX_GRID)


def _zoom(batch, best: tuple[float, float, float], h: tuple[float, float], kp_range,
          kd_range, tol: float, n: int = 21) -> tuple[tuple[float, float, float], int]:
    """Zooming feasible grid around the incumbent until the spacing is below ``tol``."""
    evals = 0
    while max(h) > tol:
        cp = np.clip(np.linspace(best[0] - h[0], best[0] + h[0], n), *kp_range)
        cd = np.clip(np.linspace(best[1] - h[1], best[1] + h[1], n), *kd_range)
        J = batch(cp[:, None], cd[None, :])
        evals += J.size
        a, c = np.unravel_index(np.argmin(J), J.shape)
        if J[a, c] < best[2]:
            best = (float(cp[a]), float(cd[c]), float(J[a, c]))
        h = (2 * h[0] / (n - 1), 2 * h[1] / (n - 1))
    return best, evals


def _onto_boundary(batch, best: tuple[float, float, float],
                   tol: float) -> tuple[tuple[float, float, float], int]:
    """A boundary optimum: bisect ``k_p`` onto the stroke limit (feasible side) to 1e-12."""
    kp_s, kd_s, val = best
    probe = batch(np.array([kp_s - 2 * tol, kp_s]), kd_s)
    evals = 2
    if not (np.isinf(probe[0]) and np.isfinite(probe[1])):
        return best, evals
    lo, hi = kp_s - 2 * tol, kp_s
    while hi - lo > 1e-12:
        mids = np.linspace(lo, hi, 34)[1:-1]
        feas = np.isfinite(batch(mids, kd_s))
        evals += mids.size
        if feas.any():
            k = int(np.argmax(feas))
            hi = mids[k]
            lo = mids[k - 1] if k > 0 else lo
        else:
            lo = mids[-1]
    v_hi = float(batch(np.array([hi]), kd_s)[0])
    return ((hi, kd_s, v_hi) if v_hi <= val else best), evals + 1


def optimize_impedance(impact: Impact | float, robot: Robot = PAPER_IMPEDANCE_ROBOT,
                       ground: Ground = LINEAR_GROUND, *, objective: str = "depth",
                       grid: int = 101, kp_range: tuple[float, float] = GAIN_RANGE,
                       kd_range: tuple[float, float] = GAIN_RANGE,
                       tol: float = 1e-8) -> ImpedanceOptimum:
    """Minimise depth (or CoT) over the gains, subject to the stroke limits.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot (its force limit saturates the impedance; the paper's study has none).
    ground : Ground
        Ground model.
    objective : {"depth", "cot", "cot-lossless"}
        ``cot`` counts ground and actuator losses, ``cot-lossless`` the ground only.
    grid : int
        Points per axis of the starting grid (the paper: 101, steps of 0.01).
    kp_range, kd_range : (float, float)
        Gain box searched.
    tol : float
        Final grid spacing of the refinement.

    Returns
    -------
    ImpedanceOptimum

    Raises
    ------
    ParameterError
        Bad parameters, or no feasible gains in the box.
    """
    impact = Impact.of(impact)
    _check(impact, objective, grid)
    energy = objective != "depth"

    def batch(kp, kd) -> np.ndarray:
        b = simulate_batch(robot, impact.v0, kp, kd, ground, energy=energy)
        return _objective_values(b, objective)

    kp = np.linspace(*kp_range, grid)
    kd = np.linspace(*kd_range, grid)
    J = batch(kp[:, None], kd[None, :])
    evals = J.size
    if not np.isfinite(J).any():
        raise ParameterError("k_p", "no feasible gains in the box: every landing leaves the "
                                    "stroke limits or never comes to rest")
    i, j = np.unravel_index(np.argmin(J), J.shape)
    best = (float(kp[i]), float(kd[j]), float(J[i, j]))
    grid_best = {"k_p": best[0], "k_d": best[1], "value": best[2]}
    best, n1 = _zoom(batch, best, (kp[1] - kp[0], kd[1] - kd[0]), kp_range, kd_range, tol)
    best, n2 = _onto_boundary(batch, best, tol)
    return _optimum(objective, robot, impact, ground, best, grid_best, evals + n1 + n2)


def _optimum(objective, robot, impact, ground, best, grid_best, evals) -> ImpedanceOptimum:
    """Re-simulate the optimum (never report infeasible gains) and describe it."""
    kp_s, kd_s, val = best
    res = simulate(robot, impact, Impedance(kp_s, kd_s), ground)
    if not (res.rest_proven and res.stroke_min >= 0 and res.stroke_max <= robot.s):
        raise RuntimeError("refined gains are infeasible on re-simulation; please report")
    margin = min(res.stroke_min, robot.s - res.stroke_max)
    on_boundary = margin <= 1e-6
    active = None
    if on_boundary:
        active = ("stroke lower limit x_b - x_f >= 0"
                  if res.stroke_min <= robot.s - res.stroke_max
                  else "stroke upper limit x_b - x_f <= s")
    return ImpedanceOptimum(
        objective=objective, robot=robot, impact=impact, ground=ground, k_p=kp_s, k_d=kd_s,
        value=val, depth=res.depth, steps=res.steps, u_peak=res.u_peak,
        stroke_min=res.stroke_min, stroke_max=res.stroke_max, cot=res.energy.cot,
        cot_lossless=res.energy.cot_lossless, on_stroke_boundary=on_boundary,
        active_constraint=active, grid_best=grid_best, evaluations=evals)


__all__ = ["GAIN_RANGE", "ImpedanceOptimum", "OBJECTIVES", "optimize_impedance"]
