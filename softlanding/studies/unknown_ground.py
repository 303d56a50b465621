"""How close a controller that does not know the ground comes to one that does.

For every true ground (stiffness factor ``K``, drag number ``c_d``) and impact velocity: the
clairvoyant optimum (the landing OCP solved for the true ground), the nominal open-loop
bang-bang plan (solved for the paper's ground) replayed on the true ground, the robust
open-loop schedule and the two-stage tree planned for the whole set of grounds
(:func:`softlanding.control.robust_landing`), the best fixed impedance tuned for the paper's
ground and the one tuned for the worst case over the set, and model-predictive control with
on-line ground estimation (:func:`softlanding.control.mpc_landing`). Depths are divided by
the clairvoyant depth; a controller that breaks a limit (stroke, force) or whose rest is not
proven is flagged, not hidden.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from softlanding.control.loop_replay import replay
from softlanding.control.mpc import DEFAULT_PERIOD, mpc_landing
from softlanding.control.robust import (
    DEFAULT_BRANCH_TIME,
    GroundLanding,
    RobustLanding,
    robust_landing,
    two_stage_landing,
)
from softlanding.errors import ParameterError, expect
from softlanding.model.controllers import Impedance
from softlanding.model.ground import Ground, linear_or_drag
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.model.terrain import paper_rig_units
from softlanding.optimal.landing import solve_landing
from softlanding.simulation.simulator import simulate
from softlanding.studies.impedance import optimize_impedance
from softlanding.util.progress import progress as show_progress

STUDY_STIFFNESS = (0.5, 0.75, 1.0, 1.5, 2.0)
"""The true grounds' stiffness factors of the study."""
STUDY_DRAG = (0.0, 0.2, 1.0)
"""The true grounds' drag numbers of the study."""
STUDY_V0 = (-1.0, -3.0, -6.0, -10.0)
"""The study's impact velocities."""


def true_ground(stiffness: float, c_d: float) -> Ground:
    """A true ground of the study: ``f = K d + c_d v^2`` (linear when ``c_d = 0``,
    :func:`~softlanding.model.ground.linear_or_drag`).

    Parameters
    ----------
    stiffness, c_d : float
        ``K`` and the drag number.
    """
    return linear_or_drag(stiffness, c_d)


def _replayed(res: Any) -> dict[str, Any]:
    return {"depth": res.depth, "feasible": bool(res.feasible), "status": res.status,
            "u_peak": res.u_peak, "stroke_min": res.stroke_min, "stroke_max": res.stroke_max}


def _planned(landing: GroundLanding) -> dict[str, Any]:
    return {"depth": landing.depth, "feasible": landing.feasible,
            "stroke_min": landing.stroke_min, "stroke_max": landing.stroke_max}


def unknown_ground_case(v0: float, ground: Ground, robot: Robot = PAPER_ROBOT, *,
                        period: float = DEFAULT_PERIOD, nominal: Any = None,
                        gains: Impedance | None = None,
                        worst_gains: Impedance | None = None,
                        robust: GroundLanding | None = None,
                        tree: GroundLanding | None = None) -> dict[str, Any]:
    """One true ground and impact velocity: every controller's landing.

    Parameters
    ----------
    v0 : float
        Impact velocity.
    ground : Ground
        The true ground.
    robot : Robot
        The robot (with a force limit; the impedance is saturated by it).
    period : float
        The MPC's sample period.
    nominal : BangBangLanding, optional
        The nominal plan (solved for the paper's ground if not given).
    gains : Impedance, optional
        The impedance tuned for the paper's ground (optimised if not given).
    worst_gains : Impedance, optional
        The impedance tuned for the worst case over a set of grounds (row
        ``"impedance_worst"``; none if not given).
    robust, tree : GroundLanding, optional
        This ground's landing under the robust open-loop schedule and the two-stage tree of
        a set of grounds (rows ``"robust"`` and ``"tree"``; none if not given).
    """
    impact = Impact(v0)
    clair = solve_landing(impact, robot, ground)
    nominal = nominal if nominal is not None else solve_landing(impact, robot)
    if gains is None:
        o = optimize_impedance(impact, robot)
        gains = Impedance(o.k_p, o.k_d)
    m = mpc_landing(impact, robot, ground, period=period, controller="replan")
    row: dict[str, Any] = {
        "v0": v0, "ground": ground.to_dict(), "clairvoyant_depth": clair.depth,
        "clairvoyant_verified": not clair.unverified_reasons(),
        "open_loop": _replayed(simulate(robot, impact, nominal.schedule(), ground)),
        "impedance_nominal": _replayed(simulate(robot, impact, gains, ground)),
        "mpc": {**m.to_dict(), "depth": m.depth, "step_times_ms": list(m.step_times_ms),
                "step_cpu_ms": list(m.step_cpu_ms)}}
    for key, planned in (("robust", robust), ("tree", tree)):
        if planned is not None:
            row[key] = _planned(planned)
    if worst_gains is not None:
        row["impedance_worst"] = _replayed(simulate(robot, impact, worst_gains, ground))
    for key in ("open_loop", "robust", "tree", "impedance_nominal", "impedance_worst", "mpc"):
        if key in row:
            row[key]["ratio"] = row[key]["depth"] / clair.depth
    return row


def unknown_ground_study(v0_values: Sequence[float] = STUDY_V0,
                         stiffness: Sequence[float] = STUDY_STIFFNESS,
                         drag: Sequence[float] = STUDY_DRAG, robot: Robot = PAPER_ROBOT, *,
                         period: float = DEFAULT_PERIOD, impedance_grid: int = 41,
                         plans: Sequence[RobustLanding] | RobustLanding = (),
                         progress: bool | None = None) -> list[dict[str, Any]]:
    """Every case of the study (see :func:`unknown_ground_case`), velocity-major.

    Parameters
    ----------
    v0_values, stiffness, drag : sequences of float
        The grid.
    robot : Robot
        The robot.
    period : float
        The MPC's sample period.
    impedance_grid : int
        The starting grid per axis of the impedance tuned for the worst case over the grounds
        (every grid point is one landing per ground).
    plans : sequence of RobustLanding, or one
        Robust plans already made over the study's grounds (:func:`robust_landing`, and
        :func:`two_stage_landing` for a tree; a notebook's, say): each is used for its
        impact velocity instead of planning again, its landing on each ground read by
        ground. A tree needs its open-loop plan given with it (and the study's branching
        time); a velocity given an open-loop plan alone gets its tree from it, one given
        nothing is planned here.
    progress : bool, optional
        A progress bar.

    Raises
    ------
    ParameterError
        A plan of another robot, of other grounds, of a velocity outside the study, of a
        kind other than ``"open-loop"`` or ``"tree"``, two plans of one kind for one
        velocity, or a tree without its open-loop plan or at another branching time
        (checked before anything is solved).
    """
    grounds = [true_ground(k, c) for k, c in itertools.product(stiffness, drag)]
    given = _given_plans(plans, v0_values, grounds, robot)
    nominal = {v: solve_landing(v, robot) for v in v0_values}
    tuned, worst, robust, trees = {}, {}, {}, {}
    for v in v0_values:
        o = optimize_impedance(v, robot)
        tuned[v] = Impedance(o.k_p, o.k_d)
        w = optimize_impedance(v, robot, grounds, grid=impedance_grid)
        worst[v] = Impedance(w.k_p, w.k_d)
        r = given.get((v, "open-loop"))
        robust[v] = r if r is not None else robust_landing(v, grounds, robot, nominal=nominal[v])
        t = given.get((v, "tree"))
        trees[v] = t if t is not None else two_stage_landing(robust[v])
    cases = [(v, g) for v in v0_values for g in grounds]
    return [unknown_ground_case(v, g, robot, period=period, nominal=nominal[v],
                                gains=tuned[v], worst_gains=worst[v],
                                robust=_landing_on(robust[v], g), tree=_landing_on(trees[v], g))
            for v, g in show_progress(cases, progress, desc="unknown ground", unit="case")]


def _given_plans(plans: Sequence[RobustLanding] | RobustLanding, v0_values: Sequence[float],
                 grounds: Sequence[Ground], robot: Robot
                 ) -> dict[tuple[float, str], RobustLanding]:
    """The plans given to :func:`unknown_ground_study`, by (velocity, kind), checked (one
    plan alone is taken as a sequence of one)."""
    if isinstance(plans, RobustLanding):
        plans = (plans,)
    if not isinstance(plans, Sequence):
        raise ParameterError("plans", "must be a sequence of RobustLanding")
    given: dict[tuple[float, str], RobustLanding] = {}
    for p in plans:
        expect("plans", p, RobustLanding)
        v = p.impact.v0
        if v not in v0_values:
            raise ParameterError("plans", f"a plan for v0 = {v:g}, not one of the study's "
                                          "velocities")
        if p.robot != robot:
            raise ParameterError("plans", f"the plan for v0 = {v:g} is another robot's")
        if set(p.grounds) != set(grounds) or len(p.grounds) != len(grounds):
            raise ParameterError("plans", f"the plan for v0 = {v:g} is over other grounds "
                                          "than the study's")
        if p.kind not in ("open-loop", "tree"):
            raise ParameterError("plans", f"the plan for v0 = {v:g} is of kind {p.kind!r}, "
                                          "not 'open-loop' or 'tree'")
        if (v, p.kind) in given:
            raise ParameterError("plans", f"two {p.kind} plans for v0 = {v:g}")
        given[(v, p.kind)] = p
    for (v, kind), t in given.items():
        # the study's tree is its open-loop plan's, at the study's branching time: a tree
        # alone (or another plan's) would pair rows of two plans
        if kind != "tree":
            continue
        r = given.get((v, "open-loop"))
        if r is None or t.schedule != r.schedule:
            raise ParameterError("plans", f"the tree for v0 = {v:g} needs the open-loop plan "
                                          "it was made from, given with it")
        if t.branch_time != DEFAULT_BRANCH_TIME:
            raise ParameterError("plans", f"the tree for v0 = {v:g} branches at "
                                          f"{t.branch_time:g}, not at the study's "
                                          f"{DEFAULT_BRANCH_TIME:g}")
    return given


def _landing_on(plan: RobustLanding, ground: Ground) -> GroundLanding:
    """The plan's landing on ``ground`` (one of its grounds)."""
    return plan.landings[plan.grounds.index(ground)]


#: The realistic sensing of the controller study (issue 33), in the paper's units on its
#: rig (x_s = 6.7 mm, tau_s = 26 ms, m_t g = 29 N): a standard deviation of 1e-3 is 7 um of
#: foot position, 0.26 mm/s of velocity, 1e-3 g of acceleration and 0.03 N of force; one
#: sample (0.26 ms) between a measurement and its actuation.
REALISTIC_NOISE, REALISTIC_DELAY = 1e-3, 1


def controller_case(v0: float, ground: Ground, robot: Robot = PAPER_ROBOT, *,
                    period: float = DEFAULT_PERIOD, noise: float = REALISTIC_NOISE,
                    delay: int = REALISTIC_DELAY, margins: Sequence[float] = (0.0, 2.0),
                    seed: int = 0, bang_bang: bool | None = None,
                    estimator: str = "filtered",
                    before_landing: Callable[[], None] | None = None
                    ) -> dict[str, Any] | None:
    """One case of the controller study: the clairvoyant optimum, the compiled bang-bang
    controller with exact measurements, and with noisy, delayed ones for each margin. Each
    landing's compiled samples are timed twice: in the landing (``compiled_times_ms``,
    ``compiled_cpu_ms``: the plant's simulation between them), and replayed as a control
    loop, one per period of the paper's rig (``loop_times_ms``, ``loop_cpu_ms``:
    :func:`~softlanding.control.loop_replay.replay`, checked identical to the last bit; a
    replay that is not raises :class:`~softlanding.control.loop_replay.ReplayMismatch` and
    ends the study: its times would be another computation's).

    Parameters
    ----------
    v0, ground, robot, period
        As for :func:`unknown_ground_case` (``period``: the controller's sample period).
    noise, delay, seed : float, int, int
        The noisy sensing (:func:`~softlanding.control.mpc_landing`).
    margins : sequence of float
        The noisy landings' margins (one landing each, key ``"noisy_m<margin>"``).
    bang_bang : bool, optional
        Only a case whose clairvoyant optimum is bang-bang (True) or a creep (False): else
        None, without the landings.
    estimator : str
        The noisy landings' ground estimator (:func:`~softlanding.control.mpc_landing`).
    before_landing : callable, optional
        Called before each landing and each replay (``benchmarks.realtime.rest``: a
        real-time benchmark sleeps there, so that the kernel's real-time throttling never
        falls in a sample).
    """
    clair = solve_landing(v0, robot, ground)
    if bang_bang is not None and (clair.refined is not None) != bang_bang:
        return None
    row: dict[str, Any] = {"v0": v0, "ground": ground.to_dict(),
                           "clairvoyant_depth": clair.depth,
                           "clairvoyant_verified": not clair.unverified_reasons(),
                           "clairvoyant_bang_bang": clair.refined is not None}
    runs: dict[str, dict[str, Any]] = {"exact": {}}
    runs.update({f"noisy_m{m:g}": {"noise": noise, "delay": delay, "seed": seed, "margin": m,
                                   "estimator": estimator} for m in margins})
    for key, kw in runs.items():
        if before_landing is not None:
            before_landing()
        m = mpc_landing(v0, robot, ground, period=period, controller="bangbang", **kw)
        own = [i for i, p in enumerate(m.step_paths) if p.startswith("bangbang")]
        loop: tuple[list[float], list[float]] = ([], [])
        if m.compiled is not None and m.compiled.samples:
            # the same samples as a control loop, one per period of the paper's rig
            if before_landing is not None:
                before_landing()
            loop = replay(m.compiled, pace_s=period * paper_rig_units().time)
        row[key] = {**m.to_dict(), "ratio": m.depth / clair.depth,
                    "step_times_ms": list(m.step_times_ms), "step_cpu_ms": list(m.step_cpu_ms),
                    "paths": sorted(set(m.step_paths)),
                    # (the compiled controller's own samples, without its fallbacks)
                    "compiled_times_ms": [m.step_times_ms[i] for i in own],
                    "compiled_cpu_ms": [m.step_cpu_ms[i] for i in own],
                    "loop_times_ms": loop[0], "loop_cpu_ms": loop[1]}
    return row


def controller_study(v0_values: Sequence[float] = STUDY_V0,
                     stiffness: Sequence[float] = STUDY_STIFFNESS,
                     drag: Sequence[float] = STUDY_DRAG, robot: Robot = PAPER_ROBOT, *,
                     progress: bool | None = None, **kw: Any) -> list[dict[str, Any]]:
    """:func:`controller_case` on every case of the grid, velocity-major.

    Parameters
    ----------
    v0_values, stiffness, drag, robot, progress
        As for :func:`unknown_ground_study` (the grid, the robot, a progress bar).
    **kw
        To :func:`controller_case` (``bang_bang``: only those cases).
    """
    cases = [(v, true_ground(k, c)) for v in v0_values for k, c in
             itertools.product(stiffness, drag)]
    rows = [controller_case(v, g, robot, **kw)
            for v, g in show_progress(cases, progress, desc="controller", unit="case")]
    return [r for r in rows if r is not None]


def study_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The study's goals checked: MPC within 2 % of the clairvoyant depth and never below it,
    every limit held; the step times' median and 99th percentile over every step of every
    case (and the largest of the cases' own 99th percentiles); per impact velocity, the
    worst depth over the grounds of the nominal plan, the robust open-loop schedule, the
    tree and the clairvoyant optima (robust <= nominal and tree <= robust are goals).

    Parameters
    ----------
    rows : list of dict
        From :func:`unknown_ground_study`.
    """
    ratios = np.array([r["mpc"]["ratio"] for r in rows])
    steps, cpu = (np.concatenate([np.asarray(r["mpc"].get(key, []), float) for r in rows]
                                 + [np.zeros(0)]) for key in ("step_times_ms", "step_cpu_ms"))
    verified = np.array([r["clairvoyant_verified"] for r in rows])
    return {
        "cases": len(rows), "clairvoyant_verified": int(verified.sum()),
        "mpc_max_ratio": float(ratios.max()), "mpc_min_ratio": float(ratios.min()),
        "mpc_within_2_percent": int((ratios <= 1.02).sum()),
        "mpc_feasible": int(sum(r["mpc"]["feasible"] for r in rows)),
        "open_loop_feasible": int(sum(r["open_loop"]["feasible"] for r in rows)),
        "impedance_feasible": int(sum(r["impedance_nominal"]["feasible"] for r in rows)),
        **{f"{key}_feasible": int(sum(r[key]["feasible"] for r in rows))
           for key in ("robust", "tree", "impedance_worst") if all(key in r for r in rows)},
        # over every step of every case (the goals), and the worst case's own percentile
        "step_time_median_ms": float(np.median(steps)) if steps.size else math.nan,
        "step_time_p99_ms": float(np.percentile(steps, 99)) if steps.size else math.nan,
        "step_time_p99_worst_case_ms": float(np.max([r["mpc"]["step_time_p99_ms"]
                                                     for r in rows])),
        "step_cpu_median_ms": float(np.median(cpu)) if cpu.size else math.nan,
        "step_cpu_p99_ms": float(np.percentile(cpu, 99)) if cpu.size else math.nan,
        "steps": int(steps.size),
        "worst_case": _worst_cases(rows)}


def _worst_cases(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per impact velocity: each controller's worst depth over the grounds and whether it held
    every limit on all of them."""
    out: dict[str, dict[str, Any]] = {}
    for v in dict.fromkeys(r["v0"] for r in rows):
        mine = [r for r in rows if r["v0"] == v]
        d: dict[str, Any] = {"clairvoyant": max(r["clairvoyant_depth"] for r in mine)}
        for key in ("open_loop", "robust", "tree", "impedance_nominal", "impedance_worst",
                    "mpc"):
            if all(key in r for r in mine):
                d[key] = max(r[key]["depth"] for r in mine)
                d[key + "_feasible"] = all(r[key]["feasible"] for r in mine)
        # the goals: robust holds every limit and is no deeper than the nominal plan where
        # that holds them too; the tree no deeper than robust (to rounding: the robust
        # schedule re-derives its last force, 1e-15 off the nominal's)
        if "robust" in d and "open_loop" in d:
            d["robust_le_nominal"] = d["robust_feasible"] and (
                not d["open_loop_feasible"] or d["robust"] <= d["open_loop"] * (1 + 1e-9))
        if "robust" in d and "tree" in d:
            d["tree_le_robust"] = d["tree_feasible"] and (
                not d["robust_feasible"] or d["tree"] <= d["robust"] * (1 + 1e-9))
        out[f"{v:g}"] = d
    return out


__all__ = ["REALISTIC_DELAY", "REALISTIC_NOISE", "STUDY_DRAG", "controller_case",
           "controller_study", "STUDY_STIFFNESS", "STUDY_V0", "study_summary", "true_ground",
           "unknown_ground_case", "unknown_ground_study"]
