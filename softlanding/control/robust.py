"""Landings planned for a set of grounds: the robust open-loop schedule and the two-stage tree.

The body's motion does not depend on the ground: ``x_b'' = -1 + (1 + r_m)/r_m u`` involves only
the force. So one open-loop force schedule moves the body identically on every ground, and it
stops the body on all of them at once when it stops it on one. Only the foot differs: on each
ground it digs, stops and sits (or digs again) as the exact simulator says. A robust
schedule is then:

* **robust open-loop**: the pieces of the nominal plan (force ``u_j`` for ``d_j``, the last
  piece's force chosen so that the body stops at its end, then the body's weight), with the
  durations and forces re-chosen to minimise the *worst* depth over the grounds, subject to
  the stroke ``0 <= x_b - x_f <= s`` and a proven rest on *every* ground, evaluated by the
  exact simulator (no relaxation of the foot's static/yielding switch, which a smooth NLP
  sharing a control in physical time across grounds would need);
* **two-stage tree**: that schedule until a branching time ``t_b`` (nobody knows the ground
  yet), then on each ground the better of its remainder and the landing re-solved from the
  state at ``t_b`` for that ground (:func:`~softlanding.control.state_landing.plan_from_state`:
  the ground has revealed itself through the foot's deceleration). Where the robust landing
  holds every limit, the tree's is never deeper, since the remainder stays a choice (a
  re-plan that holds the limits is preferred to a remainder that does not, even if deeper).

The search (:mod:`~softlanding.control.robust_search`) is SLSQP on the epigraph form ``min z``
s.t. ``depth_k <= z`` with finite-difference gradients over a handful of numbers, each
evaluation one exact simulation per ground, on rows made smooth
(:mod:`~softlanding.control.robust_family`: each low local minimum of the stroke a row of its
own; where the binding ground's foot stops at a switch, the piece pinned to end at that stop).
It starts from the clairvoyant optimum of the ground with the deepest one, when the caller
has them (``clairvoyant``), pinned where that foot stops; then from the nominal plan, pinning
the binding ground's stop where the unpinned search does not converge. Convergence is the
KKT conditions of the epigraph problem, checked independently of SLSQP (central-difference
gradients, the multipliers of the active rows by non-negative least squares; those of the
binding grounds' depths sum to 1): a local optimum within the plan's piece structure, or the
result says it is not. A schedule that is a clairvoyant optimum (one ground binding, the
others slack) is reported as that ground's (``clairvoyant_of``): its worst depth is the
largest clairvoyant depth (``lower_bound``), below which no plan for the set lands on that
ground as far as its clairvoyant optimum is the least depth there. Every figure reported is
an exact replay.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ocp import Solution, SolveError, Trajectory
from softlanding.control.plant import SteppingPlant
from softlanding.control.robust_family import PieceFamily, Pin
from softlanding.control.robust_search import (
    ACTIVE_TOL,
    FD_STEP,
    KKT_STEP,
    KKT_TOL,
    MAX_ITERATIONS,
    RESTARTS,
    Run,
    Start,
    kkt_residual,
    search,
)
from softlanding.control.state_landing import ground_numbers, plan_schedule, solve_from_state
from softlanding.errors import InfeasibleLandingError, ParameterError, check, check_count, expect
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.ground import Ground, ground_sequence
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import BangBangLanding, solve_landing, transcribed_schedule
from softlanding.optimal.limits import force_limit
from softlanding.simulation.on_grounds import simulate_on_grounds
from softlanding.simulation.simulator import LandingResult, joined_trajectory
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted

DEFAULT_BRANCH_TIME = 0.05
"""The tree's branching time in the paper's time unit (five MPC samples; 1.3 ms on the
paper's rig): by then the foot's deceleration has shown the ground."""
CLAIRVOYANT_RTOL = 1e-9
"""A robust schedule whose worst depth is within this (relative) of a binding ground's
clairvoyant depth is that ground's clairvoyant optimum."""
RESIDUAL_V = 1e-6
"""A transcribed re-plan whose body ends with ``|v_b|`` below this (Ipopt's accuracy: 1e-8 on
the creeps of the study) ends at rest: its body's weight is held, damped, with no arrest."""


@dataclass(frozen=True)
class GroundLanding:
    """One ground's landing under a robust plan, from the plant's exact simulations.

    Attributes
    ----------
    ground : Ground
        The ground.
    pieces : list of (float, LandingResult)
        The simulations and their start times (one for an open-loop schedule; the first
        stage and the second for a tree); the last one runs to rest.
    """

    ground: Ground
    pieces: list[tuple[float, LandingResult]]

    @property
    def depth(self) -> float:
        """The final depth."""
        return self.pieces[-1][1].depth

    @property
    def stroke_min(self) -> float:
        """The least ``x_b - x_f`` over the landing."""
        return min(r.stroke_min for _, r in self.pieces)

    @property
    def stroke_max(self) -> float:
        """The largest ``x_b - x_f`` over the landing."""
        return max(r.stroke_max for _, r in self.pieces)

    @property
    def feasible(self) -> bool:
        """The stroke held over every piece and rest proven at the end."""
        return all(r.stroke_held for _, r in self.pieces) and self.pieces[-1][1].rest_proven

    def trajectory(self, n: int = 1500) -> Trajectory:
        """The whole landing (``mode``: the ground's mode).

        Parameters
        ----------
        n : int
            About how many samples.
        """
        last = self.pieces[-1]
        starts = [t0 for t0, _ in self.pieces] + [last[0] + 1.2 * max(last[1].T, 1e-9)]
        return joined_trajectory([(r, starts[k], starts[k + 1])
                                  for k, (_, r) in enumerate(self.pieces)], n)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        return {"ground": self.ground.to_dict(), "depth": self.depth,
                "feasible": self.feasible, "stroke_min": self.stroke_min,
                "stroke_max": self.stroke_max, "status": self.pieces[-1][1].status}


@dataclass
class RobustLanding:
    """A landing planned for several grounds.

    Attributes
    ----------
    robot, impact : Robot, Impact
        The landing.
    grounds : tuple of Ground
        The grounds planned for.
    kind : {"open-loop", "tree"}
        One schedule for every ground, or shared until ``branch_time`` only.
    schedule : ForceSchedule
        The robust open-loop schedule (the tree's first stage is its start).
    landings : list of GroundLanding
        The exact landing on each ground.
    nominal : list of GroundLanding
        The nominal plan (solved for the paper's ground, or the one given) replayed on each
        ground.
    branch_time : float or None
        The tree's branching time.
    second_stage : list of str
        For a tree: what each ground's second stage ran (``"re-planned"`` or
        ``"remainder"``).
    evaluations : int
        Points the search evaluated (one exact simulation per ground each, unless the
        point's last force was beyond the actuator).
    solve_time_s : float
        Wall time.
    message : str
        How the search ended.
    kkt_residual : float
        The KKT stationarity residual of the epigraph problem at the open-loop schedule
        (relative; a tree keeps its first stage's).
    iterations : int
        SLSQP iterations, over all its runs.
    cpu_time_s : float
        Process CPU time of the search.
    multipliers : dict of int to float
        The binding grounds (indices) and the multipliers of their depths in the KKT check
        (they sum to 1 at a minimax point).
    limits : list of (str, int or None, float)
        The other active rows of the KKT check: kind, ground index (None: not a ground's) and
        multiplier.
    pin : tuple of (int, int) or None
        ``(piece, ground)``: the schedule's piece (0-based) that ends when that ground's foot
        first stops, in the family the search converged in (None: unpinned).
    off_pin : str
        With a pin: what the worst depth does off it (see
        :func:`~softlanding.control.robust_search.off_pin_check`).
    clairvoyant_depths : list of float or None
        The clairvoyant depth on each ground, when given.
    """

    robot: Robot
    impact: Impact
    grounds: tuple[Ground, ...]
    kind: str
    schedule: ForceSchedule
    landings: list[GroundLanding]
    nominal: list[GroundLanding]
    branch_time: float | None = None
    second_stage: list[str] = field(default_factory=list)
    evaluations: int = 0
    solve_time_s: float = 0.0
    message: str = ""
    kkt_residual: float = math.nan
    iterations: int = 0
    cpu_time_s: float = 0.0
    multipliers: dict[int, float] = field(default_factory=dict)
    limits: list[tuple[str, int | None, float]] = field(default_factory=list)
    pin: tuple[int, int] | None = None
    off_pin: str = ""
    clairvoyant_depths: list[float] | None = None

    @property
    def converged(self) -> bool:
        """The open-loop schedule is a KKT point of the epigraph problem (stationarity within
        :data:`KKT_TOL`) and holds every limit on every ground; a tree is converged when its
        first stage's schedule was."""
        return bool(self.kkt_residual <= KKT_TOL) and self.feasible

    @property
    def depths(self) -> np.ndarray:
        """The depth on each ground."""
        return np.array([g.depth for g in self.landings])

    @property
    def worst(self) -> float:
        """The largest depth over the grounds."""
        return float(np.max(self.depths))

    @property
    def active(self) -> list[int]:
        """The grounds whose depth is the worst (to 1e-9, relative)."""
        return [int(i) for i in np.flatnonzero(self.depths >= self.worst * (1 - 1e-9))]

    @property
    def feasible(self) -> bool:
        """Every ground's landing held the stroke and came to rest."""
        return all(g.feasible for g in self.landings)

    @property
    def lower_bound(self) -> float | None:
        """The largest clairvoyant depth (no plan for the set lands shallower on that ground),
        when the clairvoyant depths were given."""
        return None if self.clairvoyant_depths is None else max(self.clairvoyant_depths)

    @property
    def clairvoyant_of(self) -> int | None:
        """The ground whose clairvoyant optimum the open-loop schedule is: it binds alone and
        its depth is its clairvoyant depth (to :data:`CLAIRVOYANT_RTOL`), the others lie
        below; None otherwise (or without the clairvoyant depths, or for a tree)."""
        if self.clairvoyant_depths is None or self.kind != "open-loop" or not self.feasible:
            return None
        k = int(np.argmax(self.depths))
        c = self.clairvoyant_depths[k]
        return k if abs(self.worst - c) <= CLAIRVOYANT_RTOL * c else None

    @property
    def nominal_worst(self) -> float:
        """The nominal plan's largest depth over the grounds (limits held or not)."""
        return max(g.depth for g in self.nominal)

    @property
    def nominal_feasible(self) -> bool:
        """The nominal plan held every limit and came to rest on every ground."""
        return all(g.feasible for g in self.nominal)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        rows = []
        for i, (g, nom) in enumerate(zip(self.landings, self.nominal, strict=True)):
            row = {**g.to_dict(), "nominal_depth": nom.depth, "nominal_feasible": nom.feasible}
            if self.second_stage:
                row["second_stage"] = self.second_stage[i]
            rows.append(row)
        return json_safe({
            "kind": self.kind, "worst_depth": self.worst, "feasible": self.feasible,
            "active": self.active, "branch_time": self.branch_time,
            "schedule": {"times": list(self.schedule.times),
                         "values": list(self.schedule.values)},
            "grounds": rows, "nominal_worst_depth": self.nominal_worst,
            "nominal_feasible": self.nominal_feasible, "evaluations": self.evaluations,
            "solve_time_s": self.solve_time_s, "cpu_time_s": self.cpu_time_s,
            "message": self.message, "converged": self.converged,
            "kkt_residual": self.kkt_residual, "kkt_tol": KKT_TOL,
            "iterations": self.iterations,
            "multipliers": [{"ground": k, "multiplier": v} for k, v in self.multipliers.items()],
            "limits": [{"kind": kind, "ground": k, "multiplier": v}
                       for kind, k, v in self.limits],
            "pin": None if self.pin is None else {"piece": self.pin[0], "ground": self.pin[1]},
            "off_pin": self.off_pin, "clairvoyant_depths": self.clairvoyant_depths,
            "lower_bound": self.lower_bound, "clairvoyant_of": self.clairvoyant_of,
            "robot": self.robot.to_dict(), "impact": self.impact.to_dict()})


def _pieces(schedule: ForceSchedule | FeedbackSchedule) -> tuple[np.ndarray, np.ndarray]:
    """The durations and forces (but the last) of a plan's constant pieces."""
    if not isinstance(schedule, ForceSchedule):  # well posed, beyond this method
        raise InfeasibleLandingError("the robust landing starts from a bang-bang plan of "
                                     "constant forces; the nominal one holds a stroke limit "
                                     "(a feedback arc), which the search does not vary")
    d = np.diff((0.0,) + schedule.times)
    return d, np.asarray(schedule.values[:len(d) - 1], float)


def _split_longest(fam: PieceFamily, st: Start) -> Start:
    """One more piece, the same schedule: the longest piece halved (a pin kept on its
    piece)."""
    d, u = st.d, st.u
    j = int(np.argmax(d))
    forces = [*u, fam.last_force(d, u)]
    d = np.concatenate([d[:j], [d[j] / 2, d[j] / 2], d[j + 1:]])
    forces = forces[:j + 1] + forces[j:]
    pin = st.pin
    if pin is not None and j <= pin.piece:  # the pinned piece's end moved one piece on
        pin = Pin(pin.piece + 1, pin.ground)
    return Start(d, np.asarray(forces[:-1], float), pin)


def _starts(robot: Robot, impact: Impact, grounds: tuple[Ground, ...], nominal: BangBangLanding,
            clairvoyant: Sequence[BangBangLanding] | None) -> list[Start]:
    """The search's starts: the deepest clairvoyant optimum pinned where its foot stops; the
    nominal plan pinned so where it is the plan of the ground it binds on; the nominal plan."""
    starts = []
    if clairvoyant is not None:
        k = int(np.argmax([c.depth for c in clairvoyant]))
        sched = clairvoyant[k].schedule()
        if isinstance(sched, ForceSchedule) and len(sched.times) >= 2:
            d, u = _pieces(sched)
            starts.append(Start(d, u, Pin(len(d) - 2, k)))
    d, u = _pieces(nominal.schedule())
    if nominal.ground in grounds and len(d) >= 2:
        sched = nominal.schedule()
        depths = [r.depth for r in simulate_on_grounds(robot, impact, sched, grounds)]
        k = grounds.index(nominal.ground)
        if depths[k] >= max(depths):
            starts.append(Start(d, u, Pin(len(d) - 2, k)))
    return [*starts, Start(d, u)]


def robust_landing(impact: Impact | float, grounds: Sequence[Ground],
                   robot: Robot = PAPER_ROBOT, *, tree: bool = False,
                   branch_time: float = DEFAULT_BRANCH_TIME,
                   nominal: BangBangLanding | None = None,
                   max_iterations: int = MAX_ITERATIONS,
                   extra_pieces: int = 0,
                   clairvoyant: Sequence[BangBangLanding] | None = None) -> RobustLanding:
    """The robust open-loop landing (or the two-stage tree) over ``grounds``.

    Parameters
    ----------
    impact : Impact or float
        The impact velocity.
    grounds : sequence of Ground
        The grounds the landing must hold on (at least one).
    robot : Robot
        The robot (with a force limit).
    tree : bool
        Share the schedule only until ``branch_time``, then re-plan for each ground.
    branch_time : float
        The tree's branching time (> 0).
    nominal : BangBangLanding, optional
        The start of the search (default: the landing solved for the paper's ground).
    max_iterations : int
        Bound on the search's iterations.
    extra_pieces : int
        Pieces added to each start's (its longest piece halved, repeatedly) before the
        search: a larger family, a slower search.
    clairvoyant : sequence of BangBangLanding, optional
        The clairvoyant optimum on each ground (``solve_landing(impact, robot, ground)``):
        the deepest one is the first start (pinned where its foot stops), and the result
        says whether its schedule is one of them (``clairvoyant_of``, ``lower_bound``).

    Returns
    -------
    RobustLanding

    Raises
    ------
    ParameterError
        Bad arguments (a nominal plan of another landing, clairvoyant optima of other
        landings or grounds; with ``tree``, a ground whose law is not ``K d + c_d v^2``).
    InfeasibleLandingError
        The nominal plan holds a stroke limit (a feedback arc): not a family of constant
        forces this search varies.
    ocp.SolveError
        The nominal landing cannot be solved.
    """
    t_start = time.perf_counter()
    impact = Impact.of(impact)
    expect("robot", robot, Robot)
    max_iterations = check_count("max_iterations", max_iterations, 1, 100_000)
    extra_pieces = check_count("extra_pieces", extra_pieces, 0, 16)
    grounds = ground_sequence(grounds)  # a ground or 1..MAX_GROUNDS of them
    if tree:
        branch_time = check("branch_time", branch_time, (lambda v: v > 0, "must be > 0"))
        for g in grounds:  # the second stage plans on K d + c_d v^2 grounds only
            try:
                ground_numbers(g)
            except TypeError as err:
                raise ParameterError("grounds", f"with tree=True: {err}") from None
    if nominal is None:
        nominal = solve_landing(impact, robot, replay=False)
    expect("nominal", nominal, BangBangLanding)
    if nominal.impact != impact or nominal.robot != robot:
        raise ParameterError("nominal", f"was solved for {nominal.impact} and {nominal.robot}, "
                                        f"not {impact} and {robot}")
    _check_clairvoyant(clairvoyant, impact, robot, grounds)
    nominal_schedule = nominal.schedule()
    replays = [GroundLanding(g, [(0.0, r)]) for g, r in
               zip(grounds, simulate_on_grounds(robot, impact, nominal_schedule, grounds),
                   strict=True)]
    cpu_start = time.process_time()

    def family(n: int, pin: Pin | None) -> PieceFamily:
        return PieceFamily(robot, impact, grounds, n, pin)

    starts = []
    for st in _starts(robot, impact, grounds, nominal, clairvoyant):
        for _ in range(extra_pieces):
            st = _split_longest(family(len(st.d), None), st)
        starts.append(st)
    chosen, runs = search(family, starts, max_iterations)
    fam = chosen.family
    p = chosen.point if chosen.point is not None else fam.resolve(chosen.theta)
    if p is None:  # the least violating point of a pinned family that never resolved
        p = family(len(starts[-1].d), None).resolve(fam.theta(starts[-1].d, starts[-1].u))
    assert p is not None  # (an unpinned family resolves every theta)
    schedule = fam.schedule(p)
    landings = [GroundLanding(g, [(0.0, r)]) for g, r in
                zip(grounds, simulate_on_grounds(robot, impact, schedule, grounds), strict=True)]
    out = RobustLanding(
        robot=robot, impact=impact, grounds=grounds, kind="open-loop", schedule=schedule,
        landings=landings, nominal=replays, evaluations=sum(r.evaluations for r in runs),
        solve_time_s=time.perf_counter() - t_start, message=_message(chosen, runs),
        kkt_residual=chosen.kkt.residual if chosen.point is not None else math.nan,
        iterations=sum(r.iterations for r in runs), cpu_time_s=time.process_time() - cpu_start,
        multipliers=chosen.ground_multipliers(), limits=chosen.limit_multipliers(),
        pin=None if fam.pin is None else (fam.pin.piece, fam.pin.ground),
        off_pin=chosen.off_pin,
        clairvoyant_depths=None if clairvoyant is None else [c.depth for c in clairvoyant])
    return two_stage_landing(out, branch_time) if tree else out


def _check_clairvoyant(clairvoyant: Sequence[BangBangLanding] | None, impact: Impact,
                      robot: Robot, grounds: tuple[Ground, ...]) -> None:
    """Refuse clairvoyant optima that are not one per ground of this landing."""
    if clairvoyant is None:
        return
    if isinstance(clairvoyant, BangBangLanding) or len(clairvoyant) != len(grounds):
        raise ParameterError("clairvoyant", f"must be one landing per ground ({len(grounds)})")
    for c, g in zip(clairvoyant, grounds, strict=True):
        expect("clairvoyant", c, BangBangLanding)
        if c.impact != impact or c.robot != robot or c.ground != g:
            raise ParameterError("clairvoyant", f"was solved for {c.impact}, {c.robot} and "
                                                f"{c.ground}, not {impact}, {robot} and {g}")


def _run_line(run: Run) -> str:
    """One search run: its family, SLSQP's last word and the KKT check."""
    fam = run.family
    where = ("unpinned" if fam.pin is None
             else f"piece {fam.pin.piece + 1} ends at ground {fam.pin.ground}'s foot stop")
    slsqp = (f"SLSQP: {run.messages[-1]}" + (f" ({len(run.messages)} runs)"
                                               if len(run.messages) > 1 else "")
             if run.messages else "SLSQP not needed")
    if run.point is None:
        return f"{where}: {slsqp}; none of the {run.evaluations} schedules evaluated held " \
               f"every limit on every ground"
    verdict = "converged" if run.converged else "NOT converged"
    tail = f"; off the pin the worst depth {run.off_pin}" if run.off_pin else ""
    return f"{where}: {slsqp}; KKT residual {run.kkt.residual:.2g} ({verdict}: tolerance " \
           f"{KKT_TOL:g}){tail}"


def _message(chosen: Run, runs: list[Run]) -> str:
    """How the search ended: the chosen run first, then the others tried."""
    others = [_run_line(r) for r in runs if r is not chosen]
    return _run_line(chosen) + (f" [also tried: {'; '.join(others)}]" if others else "")


def two_stage_landing(robust: RobustLanding,
                      branch_time: float = DEFAULT_BRANCH_TIME) -> RobustLanding:
    """The two-stage tree on a robust open-loop landing's grounds: its schedule until
    ``branch_time``, then on each ground the better (limits held first, then shallower) of
    the schedule's remainder and the landing re-planned from there for that ground
    (:func:`~softlanding.control.state_landing.plan_from_state`).

    Since the remainder stays a choice, no ground whose robust landing holds the limits lands
    deeper than under ``robust``: where ``robust`` holds them on every ground, the tree's
    worst depth is at most the robust one (where it does not, a re-plan that holds them wins
    even if deeper). The first stage is the robust schedule's start, not re-optimised for the
    tree: a joint optimum of both stages can only be lower.

    Parameters
    ----------
    robust : RobustLanding
        An open-loop robust landing (:func:`robust_landing`).
    branch_time : float
        When the ground is known (> 0).

    Raises
    ------
    ParameterError
        ``robust`` is already a tree, or a bad branching time.
    """
    expect("robust", robust, RobustLanding)
    if robust.kind != "open-loop":
        raise ParameterError("robust", "is already a two-stage tree")
    branch_time = check("branch_time", branch_time, (lambda v: v > 0, "must be > 0"))
    t_start = time.perf_counter()
    landings, stages = _second_stages(robust.robot, robust.impact, robust.schedule,
                                      robust.landings, branch_time)
    return replace(robust, kind="tree", landings=landings, branch_time=branch_time,
                   second_stage=stages,
                   solve_time_s=robust.solve_time_s + time.perf_counter() - t_start)


def _second_stages(robot: Robot, impact: Impact, schedule: ForceSchedule,
                   open_loop: list[GroundLanding],
                   branch_time: float) -> tuple[list[GroundLanding], list[str]]:
    """Each ground's landing: the schedule until ``branch_time``, then the better (feasible
    first, then shallower) of the schedule's remainder and a landing re-planned there (from
    the remainder's path as a guess; where that one breaks a limit, also from Ipopt's default
    start: on a creep the guess's NLP has a second local optimum, at ``v0 = -1`` on
    ``K = 0.5``, ``c_d = 1`` a creep of 4.7 time units whose replay breaks the stroke, which
    a change of 1e-14 in the state picks)."""
    out, stages = [], []
    for kept in open_loop:
        g = kept.ground
        best, how = kept, "remainder"
        for guessed in (True, False):
            plant = SteppingPlant(robot, impact, g)
            plant.step(schedule, branch_time)
            if not plant.x[3] < 0:  # the foot has stopped: the remainder is the landing
                break
            guess = _shifted_trajectory(kept.pieces[0][1], branch_time) if guessed else None
            try:
                plant.finish(_replanned(robot, g, plant.x, guess))
            except (SolveError, ParameterError):  # no re-plan there: the remainder stays
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
                continue
            replanned = GroundLanding(g, list(plant.history))
            if (replanned.feasible, -replanned.depth) > (best.feasible, -best.depth):
                best, how = replanned, "re-planned"
            if replanned.feasible:
                break
        out.append(best)
        stages.append(how)
    return out, stages


def _replanned(robot: Robot, ground: Ground, x: np.ndarray,
               guess: Trajectory | None) -> ForceSchedule | FeedbackSchedule:
    """The landing re-planned from state ``x`` on ``ground``, as a schedule: that of
    :func:`~softlanding.control.state_landing.plan_schedule`, but a transcription (a creep)
    whose body ends within :data:`RESIDUAL_V` of rest is held there, damped.

    (``plan_schedule`` arrests a body ending at ``v_b = -1e-8``, the transcription's error,
    over ``2 stroke / |v_b|`` ~ 1e9 time units, which no replay proves at rest, and holds
    one ending at ``+1e-8`` damped: which one a creep got followed the sign of its rounding,
    and the tree's worst depth at ``v0 = -1`` on the study's grounds with it, 2.238 (the
    remainder kept on ``K = 0.5``, ``c_d = 1``) or 2.137.)
    """
    plan = solve_from_state(robot, ground, x, guess=guess)
    if isinstance(plan, Solution) and abs(float(plan.x[-1][1])) <= RESIDUAL_V:
        held = copy.copy(plan)  # the body at rest to the transcription's accuracy
        held.x = np.array(plan.x, float)
        held.x[-1, 1] = 0.0
        return transcribed_schedule(held, robot.r_m, force_limit(robot), damped=True)
    return plan_schedule(plan, robot)


def _shifted_trajectory(res: LandingResult, t0: float) -> Trajectory | None:
    """The open-loop landing from ``t0`` until the foot's first stop, times from ``t0``."""
    if not res.t_first_stop > t0:
        return None
    return res.trajectory(t_end=res.t_first_stop, n=200).after(t0)


__all__ = ["ACTIVE_TOL", "CLAIRVOYANT_RTOL", "DEFAULT_BRANCH_TIME", "FD_STEP", "KKT_STEP",
           "KKT_TOL", "MAX_ITERATIONS", "RESIDUAL_V", "RESTARTS", "GroundLanding", "RobustLanding",
           "kkt_residual", "robust_landing", "two_stage_landing"]
