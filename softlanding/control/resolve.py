"""The re-planning MPC's re-solves: the last plan's arc structure re-solved from a measured
state for the believed ground (Newton first, along a path of grounds, on a neighbouring
structure, Ipopt), a fresh transcription last, and the builds before the impact.

A sample the plan explains keeps the plan without a re-solve (:func:`plan_holds`): the
measured state equals the plan's exact prediction on the ground it was planned for, and the
estimate is still that ground (both to ``PLAN_HOLDS_TOL``). For refined (bang-bang) plans
this is the principle of optimality: the rest of an optimal plan is optimal from any state on
its path. A transcribed plan (a creep, not bang-bang) is kept the same way; it is optimal on
its own grid only, and re-solving it every sample changed the study's depths by at most 4e-9.
"""

from __future__ import annotations

import contextlib
import warnings
from functools import lru_cache
from typing import Any

import numpy as np

from ocp import OptimalControlProblem, Solution, SolveError, refine_structure
from ocp.structure.switching import Mode, RefinedSwitching
from softlanding.control.plant import SteppingPlant
from softlanding.control.state_landing import (
    ground_numbers,
    solve_from_state,
    state_parameters,
    state_transcription,
)
from softlanding.errors import RestNotProvenError
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import affine_laws
from softlanding.simulation.simulator import simulate
from softlanding.util.signals import raise_if_interrupted

PLAN_HOLDS_TOL = 1e-8
"""Relative agreement of the measured state with the plan's prediction, and of the estimate
with the plan's ground, under which a sample keeps the plan (no re-solve)."""


def plan_holds(robot: Robot, impact: Impact, schedule: Any, h: float, x_before: np.ndarray,
               x: np.ndarray, planned_for: Ground, believed: Ground) -> bool:
    """Whether the sample went as the plan predicted, on the ground it was planned for, and
    that ground is still what the controller believes.

    Parameters
    ----------
    robot, impact : Robot, Impact
        The landing.
    schedule : ForceSchedule or FeedbackSchedule
        The force over the sample.
    h : float
        The sample's length.
    x_before, x : array of 4
        The state measured before the sample and after it.
    planned_for, believed : Ground
        The ground the plan was made for, and the one now believed.
    """
    k0, c0 = ground_numbers(planned_for)
    k1, c1 = ground_numbers(believed)
    if abs(k1 - k0) > PLAN_HOLDS_TOL * k0 or abs(c1 - c0) > PLAN_HOLDS_TOL * max(1.0, c0):
        return False
    try:
        predicted = simulate(robot, impact, schedule, planned_for, x0=x_before, t_max=h,
                             energy=False).trajectory(t_end=h, n=2).x[-1]
    except RestNotProvenError:  # (the plan's own sample ends off the stroke: it does not hold)
        return False
    scale = max(1.0, float(np.max(np.abs(x))))
    return bool(np.max(np.abs(predicted - x)) <= PLAN_HOLDS_TOL * scale)


def replan_structure(problem: OptimalControlProblem, plan: Any, applied: float, robot: Robot,
                     believed: Ground, x: np.ndarray,
                     planned_for: Ground | None = None) -> tuple[RefinedSwitching, str]:
    """The last plan's structure re-solved from ``x`` for the believed ground, and how.

    Newton on the plan's structure (less the arcs already applied) first; when the estimate
    moved far from the plan's ground, Newton along a path of grounds from that one to the
    believed one (a first drag estimate moves ``c_d`` from 0 to 1 at once); then Newton on
    the structure's neighbours (an arc dropped, e.g. one that collapsed, or one added at the
    end), each about a millisecond; Ipopt on the plan's structure last.

    Parameters
    ----------
    problem : OptimalControlProblem
        :func:`~softlanding.control.state_landing.state_landing_problem`.
    plan : RefinedSwitching
        The last plan.
    applied : float
        How much of it has been applied (its time from its start to where the new plan acts).
    robot : Robot
        The robot.
    believed : Ground
        The ground to plan for.
    x : array of 4
        The state the new plan starts from.
    planned_for : Ground, optional
        The last plan's ground (the continuation's start).

    Raises
    ------
    ocp.SolveError
        No re-solve of the structure or its neighbours converged.
    """
    if isinstance(plan, Solution):
        raise SolveError("transcribed", message="a transcribed plan has no structure to re-solve")
    modes, durs = _remaining(plan, applied)
    params = state_parameters(robot, believed, x)
    try:
        return _checked(refine_structure(problem, modes, durs, x, params, ipopt=False)), "newton"
    except SolveError as err:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        collapsed = err.iterate if err.status == "arc_collapsed" else None
    if planned_for is not None and planned_for != believed:
        try:
            return _continued(problem, modes, durs, x, params,
                              state_parameters(robot, planned_for, x)), "continuation"
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
    for m, d in _neighbours(modes, durs, collapsed):
        try:
            return _checked(refine_structure(problem, m, d, x, params, ipopt=False)), "structure"
        except (SolveError, ValueError):  # (ValueError: a mode outside the control set)
            raise_if_interrupted()
    return _checked(refine_structure(problem, modes, durs, x, params, fast=False)), "ipopt"


CONTINUATION_STEPS = 4
"""Grounds on the path from the plan's ground to the believed one (Newton at each)."""


def _continued(problem: OptimalControlProblem, modes: tuple, durs: np.ndarray, x: np.ndarray,
               params: dict[str, float], start: dict[str, float]) -> RefinedSwitching:
    """Newton along ``K`` and ``c_d`` from ``start``'s values to ``params``', each re-solve
    starting from the last one's durations."""
    r = None
    for lam in np.linspace(0.0, 1.0, CONTINUATION_STEPS + 1)[1:]:
        p = dict(params)
        for name in ("stiffness", "c_d"):
            p[name] = start[name] + lam * (params[name] - start[name])
        r = _checked(refine_structure(problem, modes, durs, x, p, ipopt=False))
        durs = np.asarray(r.durations, float)
    assert r is not None
    return r


def _remaining(plan: RefinedSwitching, applied: float) -> tuple[tuple, np.ndarray]:
    """The plan's modes and durations left after ``applied`` (finished arcs dropped)."""
    durs = np.asarray(plan.durations, float).copy()
    first = 0
    while applied > 0 and first < len(durs):
        if durs[first] > applied:
            durs[first] -= applied
            break
        applied -= durs[first]
        first += 1
    if first == len(durs):
        raise SolveError("no_arcs_left", message="the plan has run out")
    return tuple(plan.modes[first:]), durs[first:]


def _neighbours(modes: tuple, durs: np.ndarray,
                collapsed: RefinedSwitching | None) -> list[tuple[tuple, np.ndarray]]:
    """Structures next to ``modes``: without an arc that collapsed (from the re-solve's
    durations), without the first or the last arc, without any other arc, and with a bang
    arc added at the end (short ones first: an arc that appears starts short)."""
    out: list[tuple[tuple, np.ndarray]] = []
    if collapsed is not None:
        tiny = np.flatnonzero(collapsed.durations <= 1e-9 * collapsed.T)
        out += [_without(modes, np.asarray(collapsed.durations, float), int(i)) for i in tiny]
    k = len(modes)
    order = [0, k - 1, *range(1, k - 1)] if k > 1 else []
    out += [_without(modes, durs, i) for i in dict.fromkeys(order)]
    last = modes[-1][0].kind
    if len(modes[-1]) == 1 and last in _FLIP:
        out.append((modes + ((_FLIP[last],),), np.r_[durs[:-1], 0.99 * durs[-1],
                                                      0.01 * durs[-1]]))
    seen: set[tuple] = set()
    unique = []
    for m, d in out:
        if m and m not in seen:
            seen.add(m)
            unique.append((m, d))
    return unique


_FLIP = {"max": Mode("min"), "min": Mode("max")}


def _without(modes: tuple, durs: np.ndarray, i: int) -> tuple[tuple, np.ndarray]:
    """``modes`` without arc ``i``, its time given to its neighbours (one arc if they then
    repeat a mode)."""
    m, d = list(modes), [float(v) for v in durs]
    gone = d.pop(i)
    m.pop(i)
    if 0 < i < len(m) and m[i - 1] == m[i]:
        d[i - 1] += gone + d.pop(i)
        m.pop(i)
    elif 0 < i < len(m):
        d[i - 1] += 0.5 * gone
        d[i] += 0.5 * gone
    elif m:
        d[min(i, len(m) - 1)] += gone
    return tuple(m), np.asarray(d)


def _checked(r: RefinedSwitching) -> RefinedSwitching:
    """A re-plan that keeps its structure (no arc collapsed) and is finite."""
    if not (np.all(np.isfinite(r.durations)) and np.all(np.isfinite(r.xT))):
        raise SolveError("not_finite", message="the re-plan is not finite")
    if min(r.durations) <= 1e-9 * r.T:
        raise SolveError("arc_collapsed", r, message="an arc of the structure collapsed")
    if not affine_laws(r):  # a stroke held under drag: no exact schedule of this plan
        raise SolveError("law_not_affine", message="a boundary arc's law is not affine")
    return r


def prepare_resolves(problem: OptimalControlProblem, plan: Any, robot: Robot, model: Ground,
                     x: np.ndarray) -> None:
    """Build, before the landing, what a sample may need: the Newton re-solves of the plan's
    structure and of its suffixes (the structures left as its arcs end, each solved once
    from the plan's state where it starts) and the transcription of the last resort.

    Parameters
    ----------
    problem : OptimalControlProblem
        :func:`~softlanding.control.state_landing.state_landing_problem`.
    plan : RefinedSwitching or ocp.Solution
        The first plan.
    robot : Robot
        The robot.
    model : Ground
        The ground it was planned for.
    x : array of 4
        The impact state.
    """
    warm_transcription()
    if isinstance(plan, Solution):
        return
    starts = plan.junctions()[:, :problem.nx]
    for j in range(len(plan.modes)):
        x_j = x if j == 0 else starts[j]
        params = state_parameters(robot, model, x_j)
        modes, durs = tuple(plan.modes[j:]), np.asarray(plan.durations[j:], float)
        for ipopt in (True, False):  # an Ipopt solve for the active set, then its Newton
            with contextlib.suppress(SolveError, ValueError):
                refine_structure(problem, modes, durs, x_j, params, ipopt=ipopt)


@lru_cache(maxsize=1)
def warm_transcription() -> None:
    """Build the transcription and its solvers (cold and warm-started) once per process: the
    first solves cost seconds, which no sample can afford."""
    tr = state_transcription()
    x = SteppingPlant(PAPER_ROBOT, Impact(-3.0), LINEAR_GROUND).x  # the paper's impact
    params = state_parameters(PAPER_ROBOT, LINEAR_GROUND, x)
    with contextlib.suppress(SolveError), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a coarse grid's path warning: only builds count
        tr.solve(params, warm_start=tr.solve(params))


def transcribed_plan(plan: Any, applied: float, robot: Robot, believed: Ground,
                     x: np.ndarray) -> Any:
    """The landing from ``x`` transcribed (from the rest of the last plan) and refined.

    Parameters
    ----------
    plan : RefinedSwitching or ocp.Solution
        The last plan (the guess).
    applied, robot, believed, x
        As for :func:`replan_structure`.

    Raises
    ------
    ocp.SolveError
        The transcription failed, or its refined plan is not usable.
    """
    if isinstance(plan, Solution):
        return solve_from_state(robot, believed, x, warm_start=plan)
    # (a delayed actuation may have run past the plan's end: then no guess from it)
    guess = plan.trajectory(200).after(applied) if applied < 0.99 * plan.T else None
    found = solve_from_state(robot, believed, x, guess=guess)
    return found if isinstance(found, Solution) else _checked(found)


__all__ = ["CONTINUATION_STEPS", "PLAN_HOLDS_TOL", "plan_holds", "prepare_resolves",
           "replan_structure", "transcribed_plan", "warm_transcription"]
