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
stroke limit to 1e-12. A boundary optimum is then followed along the boundary: the
feasible region can be a thin wedge between the stroke limit and the gains whose
static rest reaches the stroke's end (under drag, at ``v0 = -10``, lowering ``k_p`` pays
only with more ``k_d``), which a grid around one point cannot enter. So the lowest
feasible ``k_p`` is found at 21 values of ``k_d`` at once (32 points each, then the first
feasible one's bracket closed to 1e-12 by Chandrupatla's method on the stroke margin,
:func:`scipy.optimize.elementwise.find_root`), and the best of them zoomed in ``k_d`` the
same way. The result is never worse than the best grid point
(the incumbent is kept at every step) and is re-simulated to confirm it is feasible.

Gains for an unknown ground: given a sequence of grounds, :func:`optimize_impedance` tunes
for the worst case. The objective of a gain pair is its largest value over the grounds,
and it is feasible only if it is strictly feasible on every ground; the same grid, zoom
and boundary search then run on that function (the stroke boundary is now that of the
intersection of the feasible sets, and the optimum may also sit on a kink where two
grounds' values cross, which the derivative-free grid handles alike). The result names
the worst (active) grounds and gives every ground's value and depth.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from softlanding.errors import ParameterError, check_count, expect
from softlanding.model.controllers import Impedance
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, Impact, Robot
from softlanding.simulation.simulator import BatchResult, simulate, simulate_batch
from softlanding.util.jsonable import json_safe

OBJECTIVES = ("depth", "cot", "cot-lossless")
GAIN_RANGE = (0.0, 1.0)
MAX_GRID = 2001
"""Largest starting grid per axis (4 million landings)."""
ACTIVE_TOL = 1e-6
"""A ground is among the worst (active) when its value is within this (absolute, or
relative above 1) of the largest; the refinement resolves the gains to ``tol``, so the
values of grounds balanced at a worst-case optimum agree to about that."""


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
        Landings simulated, over all grounds (a further ground is not simulated at gains
        already infeasible on one: the worst case is infinite there whatever it gives).
    ground : Ground
        The ground of the landing described (``depth``, ``steps``, ...): the one given, or
        with several grounds the worst one (the first of ``worst``).
    grounds : tuple of Ground
        Every ground the gains were tuned for (``(ground,)`` for one).
    worst : tuple of int
        Indices into ``grounds`` of the worst (active) grounds: those whose value is within
        :data:`ACTIVE_TOL` of ``value``.
    ground_values, ground_depths : tuple of float
        The objective and the depth on each ground, re-simulated at the optimal gains
        (``value`` is the largest of ``ground_values``).
    ground_margins : tuple of float
        The stroke margin ``min(stroke_min, s - stroke_max)`` on each ground
        (``on_stroke_boundary`` and ``active_constraint`` are those of the smallest).
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
    grounds: tuple[Ground, ...] = ()
    worst: tuple[int, ...] = (0,)
    ground_values: tuple[float, ...] = ()
    ground_depths: tuple[float, ...] = ()
    ground_margins: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if not self.grounds:
            self.grounds = (self.ground,)

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
        d.update(robot=self.robot.to_dict(), ground=self.ground.to_dict(),
                 grounds=[g.to_dict() for g in self.grounds], worst=list(self.worst),
                 ground_values=list(self.ground_values),
                 ground_depths=list(self.ground_depths),
                 ground_margins=list(self.ground_margins))
        return json_safe(d)


def _check(impact: Impact, objective: str, grid: int) -> None:
    if objective not in OBJECTIVES:
        raise ParameterError("objective", f"must be one of {', '.join(OBJECTIVES)}, "
                                          f"got {objective!r}")
    if objective != "depth" and impact.v0 == 0.0:
        raise ParameterError("v0", "CoT is undefined at v0 = 0 (no impact energy)")
    check_count("grid", grid, 2, MAX_GRID)


def _zoom(batch, best: tuple[float, float, float], h: tuple[float, float], kp_range,
          kd_range, tol: float, n: int = 21) -> tuple[float, float, float]:
    """Zooming feasible grid around the incumbent until the spacing is below ``tol``."""
    while max(h) > tol:
        cp = np.clip(np.linspace(best[0] - h[0], best[0] + h[0], n), *kp_range)
        cd = np.clip(np.linspace(best[1] - h[1], best[1] + h[1], n), *kd_range)
        J = batch(cp[:, None], cd[None, :])
        a, c = np.unravel_index(np.argmin(J), J.shape)
        if J[a, c] < best[2]:
            best = (float(cp[a]), float(cd[c]), float(J[a, c]))
        h = (2 * h[0] / (n - 1), 2 * h[1] / (n - 1))
    return best


def _onto_boundary(batch, best: tuple[float, float, float],
                   tol: float) -> tuple[float, float, float]:
    """A boundary optimum: bisect ``k_p`` onto the stroke limit (feasible side) to 1e-12."""
    kp_s, kd_s, val = best
    probe = batch(np.array([kp_s - 2 * tol, kp_s]), kd_s)
    if not (np.isinf(probe[0]) and np.isfinite(probe[1])):
        return best
    lo, hi = kp_s - 2 * tol, kp_s
    while hi - lo > 1e-12:
        mids = np.linspace(lo, hi, 34)[1:-1]
        feas = np.isfinite(batch(mids, kd_s))
        if feas.any():
            k = int(np.argmax(feas))
            hi = mids[k]
            lo = mids[k - 1] if k > 0 else lo
        else:
            lo = mids[-1]
    v_hi = float(batch(np.array([hi]), kd_s)[0])
    return (hi, kd_s, v_hi) if v_hi <= val else best


def _signed(J: np.ndarray, margin: np.ndarray) -> np.ndarray:
    """A value whose sign is the gains' feasibility: the stroke margin where it decides it
    (a feasible point's, at least the smallest positive float), else the smallest negative
    float (no rest proven, or the objective undefined: only the sign is known). Finite, for
    the root finder."""
    tiny = np.finfo(float).tiny
    m = np.nan_to_num(np.asarray(margin, dtype=float), nan=-tiny, posinf=1e300, neginf=-1e300)
    return np.where(np.isfinite(J), np.maximum(m, tiny), np.minimum(m, -tiny))


def _lowest_feasible_kp(evaluate, kd: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                        f_hi: np.ndarray) -> np.ndarray:
    """The lowest feasible ``k_p`` on the stroke limit at each ``k_d``, to 1e-12.

    ``hi`` must be feasible (``f_hi``: its :func:`_signed` value). One round of 32 points per
    ``k_d`` finds the first feasible one (the lowest, should feasibility come and go between
    ``lo`` and ``hi``). That point's bracket is then closed to 1e-12 by Chandrupatla's
    method (:func:`scipy.optimize.elementwise.find_root`, all ``k_d`` at once) on the signed
    stroke margin, which is smooth where it decides feasibility: 3 to 4 landings per ``k_d``
    where halving took 17 to 32 (measured at v0 = -3 and -10, grid 41). Where the margin
    does not decide (no rest proven) the method falls back to bisection steps of its own;
    should it not close a bracket, halving does.
    """
    from scipy.optimize.elementwise import find_root

    frac = np.linspace(0.0, 1.0, 34)[1:-1]
    mids = lo[:, None] + (hi - lo)[:, None] * frac[None, :]
    fm = _signed(*evaluate(mids, np.broadcast_to(kd[:, None], mids.shape)))
    feas = fm > 0
    first = np.argmax(feas, axis=1)
    any_ = feas.any(axis=1)
    rows = np.arange(kd.size)
    below = np.maximum(first - 1, 0)
    # the bracket: the last infeasible point and the first feasible one, and their values
    # (NaN: the caller's lo, never simulated)
    lo, f_lo = (np.where(any_ & (first > 0), mids[rows, below], np.where(any_, lo, mids[:, -1])),
                np.where(any_ & (first > 0), fm[rows, below],
                         np.where(any_, np.nan, fm[:, -1])))
    hi, f_hi = np.where(any_, mids[rows, first], hi), np.where(any_, fm[rows, first], f_hi)
    need = np.isnan(f_lo)
    if need.any():
        f_lo[need] = _signed(*evaluate(lo[need], kd[need]))
        # feasible at the caller's lo: the lowest feasible k_p is below the bracket searched
        hi[need & (f_lo > 0)], lo[need & (f_lo > 0)] = lo[need & (f_lo > 0)], np.nan
    known = {"lo": (lo.copy(), f_lo), "hi": (hi.copy(), f_hi)}

    def f(x, i):
        out = np.full(x.shape, np.nan)
        for at, val in known.values():  # the bracket's ends: simulated already
            hit = x == at[i]
            out[hit] = val[i][hit]
        todo = np.isnan(out)
        if todo.any():
            out[todo] = _signed(*evaluate(x[todo], kd[i][todo]))
        return out

    open_ = np.isfinite(lo) & (hi - lo > 1e-12)
    if open_.any():
        i = np.flatnonzero(open_)
        res = find_root(f, (lo[i], hi[i]), args=(i,), tolerances={
            "xatol": 1e-12, "xrtol": 0.0, "fatol": 0.0, "frtol": 0.0})
        (xl, xr), (fl, fr) = res.bracket, res.f_bracket
        lo[i], hi[i] = np.where(fr > 0, xl, xr), np.where(fr > 0, xr, xl)
        bad = i[~(res.success & (np.where(fr > 0, fr, fl) > 0)
                  & (np.where(fr > 0, fl, fr) < 0))]
        lo[bad], hi[bad] = known["lo"][0][bad], known["hi"][0][bad]  # halving, as before
    open_ = np.isfinite(lo) & (hi - lo > 1e-12)
    while open_.any():
        mid = lo[open_] + (hi[open_] - lo[open_]) / 2
        ok = np.isfinite(evaluate(mid, kd[open_])[0])
        hi[open_] = np.where(ok, mid, hi[open_])
        lo[open_] = np.where(ok, lo[open_], mid)
        open_ = hi - lo > 1e-12
    return hi


def _along_boundary(evaluate, best: tuple[float, float, float], h: float, kp_range,
                    kd_range, tol: float, n: int = 21) -> tuple[float, float, float]:
    """Follow a boundary optimum along the stroke limit: zoom in ``k_d`` over the lowest
    feasible ``k_p`` at each ``k_d`` (see the module docstring). ``evaluate(kp, kd)`` gives
    the objective (inf: infeasible) and the stroke margin."""
    moves = 0
    while h > tol:
        cd = np.unique(np.clip(np.linspace(best[1] - h, best[1] + h, n), *kd_range))
        # a feasible upper end per k_d: the incumbent's k_p raised until feasible
        hi, f_hi = np.full(cd.size, np.nan), np.full(cd.size, np.nan)
        for step in (0.0, h, 4 * h, 16 * h, 64 * h):
            idx = np.flatnonzero(np.isnan(hi))  # (only the k_d without one yet)
            if idx.size == 0:
                break
            top = min(best[0] + step, kp_range[1])
            f = _signed(*evaluate(np.full(idx.size, top), cd[idx]))
            hi[idx[f > 0]], f_hi[idx[f > 0]] = top, f[f > 0]
        have = np.isfinite(hi)
        if have.any():
            lo = np.maximum(hi[have] - 4 * max(h, 1e-6), kp_range[0])
            kp_b = _lowest_feasible_kp(evaluate, cd[have], lo, hi[have], f_hi[have])
            J = evaluate(kp_b, cd[have])[0]
            k = int(np.argmin(J))
            if J[k] < best[2]:
                best = (float(kp_b[k]), float(cd[have][k]), float(J[k]))
                at_edge = k in (0, J.size - 1) and cd[have][k] not in kd_range
                if at_edge and moves < 100:  # still descending: move the window, same width
                    moves += 1
                    continue
        h = 2 * h / (n - 1)
    return best


def _grounds_of(ground: Any) -> tuple[Ground, ...]:
    """One ground, or a non-empty list or tuple of grounds, as a tuple (else ParameterError)."""
    if isinstance(ground, Ground):
        return (ground,)
    if isinstance(ground, (str, bytes, Mapping)) or not isinstance(ground, Sequence):
        raise ParameterError("ground", "must be a Ground or a non-empty list or tuple of "
                                       f"Grounds, got {type(ground).__name__} {ground!r:.60}")
    if len(ground) == 0:
        raise ParameterError("ground", "an empty sequence of grounds: give at least one")
    for i, g in enumerate(ground):
        if not isinstance(g, Ground):
            raise ParameterError("ground", f"item {i} of the sequence must be a Ground, got "
                                           f"{type(g).__name__} {g!r:.60}")
    return tuple(ground)


def optimize_impedance(impact: Impact | float, robot: Robot = PAPER_IMPEDANCE_ROBOT,
                       ground: Ground | Sequence[Ground] = LINEAR_GROUND, *,
                       objective: str = "depth", grid: int = 101,
                       kp_range: tuple[float, float] = GAIN_RANGE,
                       kd_range: tuple[float, float] = GAIN_RANGE,
                       tol: float = 1e-8) -> ImpedanceOptimum:
    """Minimise depth (or CoT) over the gains, subject to the stroke limits; with several
    grounds, minimise the worst case over them.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot (its force limit saturates the impedance; the paper's study has none).
    ground : Ground or sequence of Ground
        Ground model, or a non-empty list or tuple of them (the true ground unknown among
        them): then the objective is the largest over the grounds, and gains are feasible
        only if they are on every ground (see the module docstring). One ground in a
        sequence gives the same result as that ground alone.
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
        Bad parameters (an empty sequence of grounds, or an item that is not a Ground), or
        no gains in the box feasible (on every ground).
    """
    impact = Impact.of(impact)
    _check(impact, objective, grid)
    expect("robot", robot, Robot)
    grounds = _grounds_of(ground)
    energy = objective != "depth"

    landings = [0]  # simulated, over all grounds (ImpedanceOptimum.evaluations)

    def one(g: Ground) -> Callable[[Any, Any], tuple[np.ndarray, np.ndarray]]:
        def values(kp, kd) -> tuple[np.ndarray, np.ndarray]:
            b = simulate_batch(robot, impact.v0, kp, kd, g, energy=energy)
            landings[0] += b.depth.size
            return _objective_values(b, objective), b.stroke_margin
        return values

    # the worst case: the affine grounds first (exact kernels, far cheaper than an integrated
    # one), and each further ground only where the gains are still feasible: inf on any
    # ground stays inf, every landing is independent of the others, so the values are those
    # of every ground at every point (the unknown-ground study's two searches: 38 -> 16 s CPU)
    grounds_values = [one(g) for g in sorted(grounds, key=lambda g: not g.is_affine)]

    def evaluate(kp, kd) -> tuple[np.ndarray, np.ndarray]:
        """The objective (inf: infeasible on a ground) and the smallest stroke margin over the
        grounds simulated."""
        kp, kd = np.broadcast_arrays(np.asarray(kp, dtype=float), np.asarray(kd, dtype=float))
        J, M = (np.array(a, dtype=float) for a in grounds_values[0](kp, kd))
        for f in grounds_values[1:]:
            live = np.isfinite(J)
            if live.any():
                Jg, Mg = f(kp[live], kd[live]) if not live.all() else f(kp, kd)
                J[live] = np.maximum(J[live], np.reshape(Jg, J[live].shape))
                M[live] = np.minimum(M[live], np.reshape(Mg, M[live].shape))
        return J, M

    def batch(kp, kd) -> np.ndarray:
        return evaluate(kp, kd)[0]

    kp = np.linspace(*kp_range, grid)
    kd = np.linspace(*kd_range, grid)
    J = batch(kp[:, None], kd[None, :])
    if not np.isfinite(J).any():
        where = "on every ground " if len(grounds) > 1 else ""
        raise ParameterError("k_p", f"no feasible gains {where}in the box: every landing leaves "
                                    "the stroke limits or never comes to rest")
    i, j = np.unravel_index(np.argmin(J), J.shape)
    best = (float(kp[i]), float(kd[j]), float(J[i, j]))
    grid_best = {"k_p": best[0], "k_d": best[1], "value": best[2]}
    best = _zoom(batch, best, (kp[1] - kp[0], kd[1] - kd[0]), kp_range, kd_range, tol)
    best = _onto_boundary(batch, best, tol)
    if np.isinf(batch(np.array([best[0] - 2 * tol]), best[1])[0]):  # k_p at the stroke limit
        best = _along_boundary(evaluate, best, kd[1] - kd[0], kp_range, kd_range, tol)
    return _optimum(objective, robot, impact, grounds, best, grid_best, landings[0])


def _value_of(res: Any, objective: str) -> float:
    if objective == "depth":
        return float(res.depth)
    return float(res.energy.cot if objective == "cot" else res.energy.cot_lossless)


def _optimum(objective: str, robot: Robot, impact: Impact, grounds: tuple[Ground, ...],
             best: tuple[float, float, float], grid_best: dict[str, float],
             evals: int) -> ImpedanceOptimum:
    """Re-simulate the optimum on every ground (never report gains infeasible on any) and
    describe it: the landing on the worst ground, and every ground's figures."""
    kp_s, kd_s, val = best
    results = []
    for g in grounds:
        res = simulate(robot, impact, Impedance(kp_s, kd_s), g)
        if not (res.rest_proven and res.stroke_min >= 0 and res.stroke_max <= robot.s):
            where = f" on ground {g.to_dict()}" if len(grounds) > 1 else ""
            raise RuntimeError(f"refined gains are infeasible on re-simulation{where}; "
                               "please report")
        results.append(res)
    values = tuple(_value_of(r, objective) for r in results)
    top = max(values)
    worst = tuple(i for i, v in enumerate(values) if v >= top - ACTIVE_TOL * max(1.0, abs(top)))
    worst = tuple(sorted(worst, key=lambda i: -values[i]))  # the largest first
    margins = tuple(min(r.stroke_min, robot.s - r.stroke_max) for r in results)
    res = results[worst[0]]
    tight = results[int(np.argmin(margins))]
    on_boundary = min(margins) <= 1e-6
    active = None
    if on_boundary:
        active = ("stroke lower limit x_b - x_f >= 0"
                  if tight.stroke_min <= robot.s - tight.stroke_max
                  else "stroke upper limit x_b - x_f <= s")
    return ImpedanceOptimum(
        objective=objective, robot=robot, impact=impact, ground=grounds[worst[0]], k_p=kp_s,
        k_d=kd_s, value=val, depth=res.depth, steps=res.steps, u_peak=res.u_peak,
        stroke_min=res.stroke_min, stroke_max=res.stroke_max, cot=res.energy.cot,
        cot_lossless=res.energy.cot_lossless, on_stroke_boundary=on_boundary,
        active_constraint=active, grid_best=grid_best, evaluations=evals, grounds=grounds,
        worst=worst, ground_values=values, ground_depths=tuple(r.depth for r in results),
        ground_margins=margins)


__all__ = ["ACTIVE_TOL", "GAIN_RANGE", "ImpedanceOptimum", "OBJECTIVES", "optimize_impedance"]
