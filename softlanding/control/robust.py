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

The search is SLSQP (``scipy.optimize.minimize``) with finite-difference gradients over a
handful of numbers, on the epigraph form ``min z`` s.t. ``depth_i <= z``; each evaluation is
one exact simulation per ground. Started from the nominal plan, it keeps the best schedule
it evaluated that holds every limit on every ground, so where the nominal plan holds them its
worst depth is never above the nominal one. It is a local search within the nominal plan's
piece structure. SLSQP's quasi-Newton model can degrade where the active grounds switch, so a
run that stops short is restarted from its best point (a fresh model), up to
:data:`RESTARTS` times. Convergence is then checked independently of SLSQP: the KKT
conditions of the epigraph problem at the schedule returned, with central-difference
gradients and the multipliers of the active constraints and bounds by non-negative least
squares (``kkt_residual``, stationarity relative to the objective's gradient; ``converged``
when it is below :data:`KKT_TOL` with every limit held): a local optimum, or the search
says it is not. Every figure reported is an exact replay.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.optimize import minimize

from ocp import SolveError, Trajectory
from softlanding.control.plant import SteppingPlant
from softlanding.control.state_landing import ground_numbers, plan_from_state
from softlanding.errors import InfeasibleLandingError, ParameterError, check, check_count, expect
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.ground import Ground, ground_sequence
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import BangBangLanding, solve_landing
from softlanding.optimal.limits import force_limit
from softlanding.simulation.simulator import LandingResult, joined_trajectory, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted

DEFAULT_BRANCH_TIME = 0.05
"""The tree's branching time in the paper's time unit (five MPC samples; 1.3 ms on the
paper's rig): by then the foot's deceleration has shown the ground."""
MAX_ITERATIONS = 200
"""SLSQP iterations of the search."""
FD_STEP = 1e-7
"""The finite-difference step of the search's gradients (durations and forces)."""
RESTARTS = 4
"""SLSQP runs after the first, each from the best point of the one before, while the KKT
check fails."""
KKT_TOL = 1e-4
"""Largest KKT stationarity residual (relative to the objective's gradient) of a converged
schedule. Measured where SLSQP converged: 2e-5 (v0 = -3, four grounds; the rest is the
finite differences and a flat valley along the long last piece, whose linearised descent
leaves the constraints at second order), 9e-7 and 3e-6 (v0 = -1, -3, the study's 15
grounds); where it stopped at its iteration limit: 0.84 (v0 = -3, four grounds, first run),
0.97 and 0.99 (v0 = -6, -10, 15 grounds, after every restart)."""
KKT_STEP = 1e-6
"""Central-difference step of the KKT check (relative to each variable, at least absolute)."""
ACTIVE_TOL = 1e-6
"""A constraint (scaled to order one) within this of its bound counts as active in the KKT
check."""


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
            "robot": self.robot.to_dict(), "impact": self.impact.to_dict()})


class _Pieces:
    """The schedule family: forces ``u_1..u_{n-1}`` and durations ``d_1..d_n`` free, ``u_n``
    the force that stops the body at the end of piece ``n`` (then the body's weight)."""

    def __init__(self, robot: Robot, impact: Impact, n: int) -> None:
        self.robot, self.impact, self.n = robot, impact, n
        self.gain = (1 + robot.r_m) / robot.r_m  # body acceleration per unit force

    def last_force(self, d: np.ndarray, u: np.ndarray) -> float:
        """The force of the last piece that brings ``v_b`` to zero at its end."""
        v = self.impact.v0 + float(np.sum((-1 + self.gain * u) * d[:-1]))
        return (1 - v / d[-1]) / self.gain

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Durations and forces, projected onto their bounds (the search may step a rounding
        beyond them)."""
        u_max = force_limit(self.robot)
        return (np.maximum(np.asarray(theta[:self.n], float), 1e-9),
                np.clip(np.asarray(theta[self.n:], float), -u_max, u_max))

    def split_longest(self, theta: np.ndarray) -> np.ndarray:
        """One more piece, the same schedule: the longest piece halved."""
        d, u = self.split(theta)
        j = int(np.argmax(d))
        forces = [*u, self.last_force(d, u)]
        d = np.concatenate([d[:j], [d[j] / 2, d[j] / 2], d[j + 1:]])
        forces = forces[:j + 1] + forces[j:]
        self.n += 1
        return np.concatenate([d, forces[:-1]])

    def schedule(self, theta: np.ndarray) -> ForceSchedule:
        d, u = self.split(theta)
        values = [*map(float, u), self.last_force(d, u), self.robot.r_m / (1 + self.robot.r_m)]
        return ForceSchedule(tuple(np.cumsum(d)), tuple(values))


def _nominal_theta(schedule: ForceSchedule | FeedbackSchedule) -> np.ndarray:
    """The durations and forces (but the last) of a nominal plan's constant pieces."""
    if not isinstance(schedule, ForceSchedule):  # well posed, beyond this method
        raise InfeasibleLandingError("the robust landing starts from a bang-bang plan of "
                                     "constant forces; the nominal one holds a stroke limit "
                                     "(a feedback arc), which the search does not vary")
    d = np.diff((0.0,) + schedule.times)
    return np.concatenate([d, np.asarray(schedule.values[:len(d) - 1], float)])


def robust_landing(impact: Impact | float, grounds: Sequence[Ground],
                   robot: Robot = PAPER_ROBOT, *, tree: bool = False,
                   branch_time: float = DEFAULT_BRANCH_TIME,
                   nominal: BangBangLanding | None = None,
                   max_iterations: int = MAX_ITERATIONS,
                   extra_pieces: int = 0) -> RobustLanding:
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
        Pieces added to the nominal plan's (its longest piece halved, repeatedly) before the
        search: a larger family, a slower search.

    Returns
    -------
    RobustLanding

    Raises
    ------
    ParameterError
        Bad arguments (a nominal plan of another landing; with ``tree``, a ground whose law
        is not ``K d + c_d v^2``).
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
    nominal_schedule = nominal.schedule()
    replays = [GroundLanding(g, [(0.0, simulate(robot, impact, nominal_schedule, g,
                                                energy=False))]) for g in grounds]
    theta0 = _nominal_theta(nominal_schedule)
    pieces = _Pieces(robot, impact, (len(theta0) + 1) // 2)
    for _ in range(extra_pieces):
        theta0 = pieces.split_longest(theta0)
    cpu_start = time.process_time()
    found = _search(pieces, grounds, theta0, max_iterations)
    schedule = pieces.schedule(found.theta)
    landings = [GroundLanding(g, [(0.0, simulate(robot, impact, schedule, g, energy=False))])
                for g in grounds]
    out = RobustLanding(
        robot=robot, impact=impact, grounds=grounds, kind="open-loop", schedule=schedule,
        landings=landings, nominal=replays, evaluations=found.evaluations,
        solve_time_s=time.perf_counter() - t_start, message=found.message,
        kkt_residual=found.kkt, iterations=found.iterations,
        cpu_time_s=time.process_time() - cpu_start)
    return two_stage_landing(out, branch_time) if tree else out


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


@dataclass
class _Found:
    theta: np.ndarray
    evaluations: int
    message: str
    kkt: float
    iterations: int


def _search(pieces: _Pieces, grounds: tuple[Ground, ...], theta0: np.ndarray,
            max_iterations: int) -> _Found:
    """``min z`` s.t. ``depth_i <= z`` and every ground's limits, over the pieces; SLSQP,
    restarted from its best point while the KKT check fails."""
    robot, impact = pieces.robot, pieces.impact
    u_max = force_limit(robot)
    s = robot.s
    cache: dict[bytes, np.ndarray] = {}
    holds: dict[bytes, bool] = {}  # every ground's landing feasible (the reported test)
    n = pieces.n
    scale_d = max(1.0, abs(impact.v0))
    nowhere = np.array([math.inf, -s, -s] * len(grounds))

    def measures(theta: np.ndarray) -> np.ndarray:
        """Per ground: depth, stroke margins (inf, -s, -s without a proven rest); then the
        last force's margin."""
        key = np.asarray(theta, float).tobytes()
        if key not in cache:
            holds[key] = False
            if not np.all(np.isfinite(theta)):
                cache[key] = np.r_[nowhere, -u_max]
                return cache[key]
            d, u = pieces.split(theta)
            u_last = pieces.last_force(d, u)
            if not abs(u_last) <= u_max:  # the actuator cannot stop the body in time
                cache[key] = np.r_[nowhere, u_max - abs(u_last)]
                return cache[key]
            if not np.all(np.diff(np.r_[0.0, np.cumsum(d)]) > 0.0):
                # a search step far out: durations of 1e11 (seen) swallow one of 1e-6, so
                # the pieces' times are no schedule; a point nowhere, not a crash
                cache[key] = np.r_[nowhere, u_max - abs(u_last)]
                return cache[key]
            rows = []
            sched = pieces.schedule(theta)
            results = [simulate(robot, impact, sched, g, energy=False) for g in grounds]
            for r in results:
                ok = r.rest_proven and math.isfinite(r.stroke_min)
                rows += [r.depth if ok else math.inf, r.stroke_min if ok else -s,
                         s - r.stroke_max if ok else -s]
            cache[key] = np.array(rows + [u_max - abs(u_last)])
            holds[key] = all(r.stroke_held and r.rest_proven for r in results)
        return cache[key]

    def cons(x: np.ndarray) -> np.ndarray:
        m = measures(x[:-1])
        depth = m[:-1:3]
        big = 10 * scale_d * max(1.0, s)
        depth_margin = np.where(np.isfinite(depth), x[-1] - depth, -big)
        return np.concatenate([depth_margin / scale_d, m[1:-1:3] / s, m[2:-1:3] / s,
                               [m[-1] / u_max]])

    def violation(key: bytes) -> float:
        m = cache[key]
        return float(-min(0.0, np.min(m[1:-1:3]), np.min(m[2:-1:3]), m[-1]))

    def worst(key: bytes) -> float:
        return float(np.max(cache[key][:-1:3]))

    measures(theta0)
    z0 = worst(theta0.tobytes())
    x = np.concatenate([theta0, [z0 if math.isfinite(z0) else 10 * scale_d]])
    lo = np.concatenate([np.full(n, 1e-6), np.full(n - 1, -u_max), [0.0]])
    hi = np.concatenate([np.full(n, np.inf), np.full(n - 1, u_max), [np.inf]])
    grad_f = np.eye(len(x))[-1] / scale_d
    iterations, kkt, messages = 0, math.inf, []
    for _ in range(1 + RESTARTS):
        # SLSQP on finite differences: every measure is smooth while the landing's sequence
        # of events is kept (a stroke extremum is an interior minimum: its derivative is the
        # state's); deterministic, unlike the derivative-free searches tried (COBYQA)
        res = minimize(lambda v: v[-1] / scale_d, x, method="SLSQP", jac=lambda v: grad_f,
                       bounds=list(zip(lo, hi, strict=True)),
                       constraints=[{"type": "ineq", "fun": cons}],
                       options={"maxiter": max_iterations, "ftol": 1e-12, "eps": FD_STEP})
        iterations += int(res.nit)
        messages.append(str(res.message))
        feasible = [k for k in cache if holds[k]]
        if not feasible:
            break
        best = min(feasible, key=worst)
        moved = not np.array_equal(np.frombuffer(best), x[:-1])
        x = np.r_[np.frombuffer(best), worst(best)]
        if moved or not math.isfinite(kkt):
            kkt = kkt_residual(cons, x, lo, hi, grad_f)
        if kkt <= KKT_TOL or not moved:  # converged, or a restart cannot move it
            break
    runs = f"SLSQP: {messages[-1]}" + (f" (run {len(messages)} of restarts from the best "
                                       f"point; before: {', '.join(messages[:-1])})"
                                       if len(messages) > 1 else "")
    feasible = [k for k in cache if holds[k]]
    if feasible:
        verdict = "converged" if kkt <= KKT_TOL else "NOT converged"
        return _Found(x[:-1].copy(), len(cache), f"{runs}; KKT residual {kkt:.2g} "
                      f"({verdict}: tolerance {KKT_TOL:g})", kkt, iterations)
    best = min(cache, key=violation)  # nothing holds: the least violating point
    return _Found(np.frombuffer(best).copy(), len(cache),
                  f"{runs}; none of the {len(cache)} schedules evaluated held every limit on "
                  f"every ground", math.nan, iterations)


def kkt_residual(cons: Any, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                 grad_f: np.ndarray, step: float = KKT_STEP,
                 active_tol: float = ACTIVE_TOL) -> float:
    """The KKT stationarity residual of ``min f`` s.t. ``cons(x) >= 0``, ``lo <= x <= hi``
    at ``x`` (``f`` linear with gradient ``grad_f``): ``|grad_f - J_A^T lam - mu|_inf /
    |grad_f|_inf`` with the multipliers ``lam >= 0`` of the active constraints (within
    ``active_tol``) and ``mu`` of the active bounds (signed by the bound) fitted by
    non-negative least squares; ``J`` by central differences. Infinite when ``x`` violates
    a constraint by more than ``active_tol``.

    Parameters
    ----------
    cons : callable
        ``x -> constraint values`` (feasible where ``>= 0``, scaled to order one).
    x : ndarray
        The point.
    lo, hi : ndarray
        Bounds (infinite: none).
    grad_f : ndarray
        The objective's gradient.
    step : float
        Relative central-difference step.
    active_tol : float
        Activity tolerance.
    """
    from scipy.optimize import nnls

    x = np.asarray(x, float)
    g0 = np.asarray(cons(x), float)
    if not np.all(g0 >= -active_tol):
        return math.inf
    cols = []
    for j in range(len(x)):
        h = step * max(1.0, abs(x[j]))
        up, down = min(x[j] + h, hi[j]), max(x[j] - h, lo[j])  # stay within the bounds
        xp, xm = x.copy(), x.copy()
        xp[j], xm[j] = up, down
        cols.append((np.asarray(cons(xp)) - np.asarray(cons(xm))) / (up - down))
    jac = np.column_stack(cols)
    eye = np.eye(len(x))
    scale = np.maximum(1.0, np.abs(x))
    basis = [jac[g0 <= active_tol].T, eye[:, x <= lo + active_tol * scale],
             -eye[:, x >= hi - active_tol * scale]]
    A = np.hstack(basis)
    if A.shape[1] == 0:
        return float(np.max(np.abs(grad_f)) / np.max(np.abs(grad_f)))
    lam, _ = nnls(A, grad_f)
    return float(np.max(np.abs(grad_f - A @ lam)) / np.max(np.abs(grad_f)))


def _second_stages(robot: Robot, impact: Impact, schedule: ForceSchedule,
                   open_loop: list[GroundLanding],
                   branch_time: float) -> tuple[list[GroundLanding], list[str]]:
    """Each ground's landing: the schedule until ``branch_time``, then the better (feasible
    first, then shallower) of the schedule's remainder and a landing re-planned there."""
    out, stages = [], []
    for kept in open_loop:
        g = kept.ground
        plant = SteppingPlant(robot, impact, g)
        plant.step(schedule, branch_time)
        best, how = kept, "remainder"
        if plant.x[3] < 0:  # the foot still digs: re-plan for the ground now known
            rest = kept.pieces[0][1]
            guess = _shifted_trajectory(rest, branch_time)
            try:
                plant.finish(plan_from_state(robot, g, plant.x, guess))
                replanned = GroundLanding(g, list(plant.history))
                if (replanned.feasible, -replanned.depth) > (kept.feasible, -kept.depth):
                    best, how = replanned, "re-planned"
            except (SolveError, ParameterError):  # no re-plan there: the remainder stays
                raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        out.append(best)
        stages.append(how)
    return out, stages


def _shifted_trajectory(res: LandingResult, t0: float) -> Trajectory | None:
    """The open-loop landing from ``t0`` until the foot's first stop, times from ``t0``."""
    if not res.t_first_stop > t0:
        return None
    return res.trajectory(t_end=res.t_first_stop, n=200).after(t0)


__all__ = ["ACTIVE_TOL", "DEFAULT_BRANCH_TIME", "FD_STEP", "KKT_STEP", "KKT_TOL",
           "MAX_ITERATIONS", "RESTARTS", "GroundLanding", "RobustLanding", "kkt_residual",
           "robust_landing", "two_stage_landing"]
