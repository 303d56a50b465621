"""The robust schedule's search: the epigraph problem over the grounds, its KKT point and its
multipliers.

``min z`` s.t. ``depth_k <= z`` for every ground ``k`` and every ground's limits, over a
:class:`~softlanding.control.robust_family.PieceFamily` (rows made smooth there). SLSQP
(``scipy.optimize.minimize``) with finite-difference gradients over a handful of numbers;
each evaluation is one exact simulation per ground. It keeps the best schedule it evaluated
that holds every limit on every ground, and restarts from it (a fresh quasi-Newton model)
while the KKT check fails, up to :data:`RESTARTS` times.

**Convergence** is checked independently of SLSQP, on the problem the family poses: the KKT
conditions of the epigraph problem at the schedule returned, with central-difference
gradients and the multipliers of the active rows and bounds by non-negative least squares
(:func:`kkt_point`; stationarity relative to the objective's gradient below :data:`KKT_TOL`).
The multipliers of the binding grounds' depth rows sum to 1 at a minimax point (the
``z``-component of stationarity). A pinned family is a restriction (the pinned piece ends at
the foot's stop); its KKT point is also checked off it: the worst depth of the unpinned
schedule must rise (or a limit break) on both sides of the pinned duration
(:func:`off_pin_check`; one direction, not a proof over every direction).

**Starts** (:func:`search`), in order: each given start in its family (a clairvoyant plan
pinned where its foot stops); where a start is not pinned and its first SLSQP run does not
converge, the binding ground's stop is pinned to the nearest switch before it (:func:`pin_at`)
and the search goes on in that family from the best point; only where that does not converge
either do the unpinned restarts run, and the pin is tried again from their best point (on the
study's grounds at v0 = -6 and -10 the pinned search converged to the same schedule, to 1e-11,
in 2,006 and 2,271 evaluations where the unpinned restarts first had taken 11,904 and 9,194).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize, nnls

from softlanding.control.robust_family import Measures, PieceFamily, Pin, Point
from softlanding.simulation.on_grounds import simulate_on_grounds

MAX_ITERATIONS = 200
"""SLSQP iterations of each run."""
FD_STEP = 1e-7
"""The finite-difference step of the search's gradients (durations and forces)."""
RESTARTS = 4
"""SLSQP runs after the first, each from the best point of the one before, while the KKT
check fails."""
KKT_TOL = 1e-4
"""Largest KKT stationarity residual (relative to the objective's gradient) of a converged
schedule. Measured on the smooth rows: 4e-16 (v0 = -10, the study's 15 grounds, pinned), where
the global stroke extrema and the unpinned depth left 0.4 to 0.99 (kinks)."""
KKT_STEP = 1e-6
"""Central-difference step of the KKT check (relative to each variable, at least absolute)."""
ACTIVE_TOL = 1e-6
"""A row (scaled to order one) within this of its bound counts as active in the KKT check."""
OFF_PIN_STEP = 1e-6
"""Relative step of :func:`off_pin_check` along the pinned duration."""


@dataclass(frozen=True)
class KKTPoint:
    """The KKT check of ``min f`` s.t. ``cons(x) >= 0``, ``lo <= x <= hi`` at a point.

    Attributes
    ----------
    residual : float
        ``|grad_f - J_A^T lam - mu|_inf / |grad_f|_inf`` (infinite at an infeasible point).
    rows : ndarray of int
        The active rows.
    multipliers : ndarray
        Their multipliers ``lam >= 0``.
    """

    residual: float
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))


def kkt_point(cons: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lo: np.ndarray,
              hi: np.ndarray, grad_f: np.ndarray, step: float = KKT_STEP,
              active_tol: float = ACTIVE_TOL) -> KKTPoint:
    """The KKT stationarity of ``min f`` s.t. ``cons(x) >= 0``, ``lo <= x <= hi`` at ``x``
    (``f`` linear with gradient ``grad_f``): the multipliers ``lam >= 0`` of the active rows
    (within ``active_tol``) and ``mu`` of the active bounds (signed by the bound) fitted by
    non-negative least squares; ``J`` by central differences (within the bounds).

    Parameters
    ----------
    cons : callable
        ``x -> row values`` (feasible where ``>= 0``, scaled to order one).
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
    x = np.asarray(x, float)
    g0 = np.asarray(cons(x), float)
    if not np.all(g0 >= -active_tol):
        return KKTPoint(math.inf)
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
    rows = np.flatnonzero(g0 <= active_tol)
    A = np.hstack([jac[rows].T, eye[:, x <= lo + active_tol * scale],
                   -eye[:, x >= hi - active_tol * scale]])
    norm = float(np.max(np.abs(grad_f)))
    if A.shape[1] == 0:
        return KKTPoint(1.0, rows, np.zeros(0))
    lam, _ = nnls(A, grad_f)
    return KKTPoint(float(np.max(np.abs(grad_f - A @ lam)) / norm), rows, lam[:len(rows)])


def kkt_residual(cons: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lo: np.ndarray,
                 hi: np.ndarray, grad_f: np.ndarray, step: float = KKT_STEP,
                 active_tol: float = ACTIVE_TOL) -> float:
    """The residual of :func:`kkt_point`.

    Parameters
    ----------
    cons, x, lo, hi, grad_f, step, active_tol
        As :func:`kkt_point`.
    """
    return kkt_point(cons, x, lo, hi, grad_f, step, active_tol).residual


@dataclass
class Run:
    """One family's search.

    Attributes
    ----------
    family : PieceFamily
        The family searched.
    point : Point or None
        The best point holding every limit on every ground (None: none did).
    theta : ndarray
        Its coordinates (or the least violating point's).
    worst : float
        Its worst depth (the rows'; the pinned ground's at its stop).
    kkt : KKTPoint
        The KKT check there (infinite residual without a feasible point).
    names : list of (str, int or None)
        The rows' kinds and grounds.
    iterations, evaluations : int
        SLSQP iterations and points evaluated.
    messages : list of str
        SLSQP's messages, run by run.
    off_pin : str
        :func:`off_pin_check`'s finding ("" without a pin).
    """

    family: PieceFamily
    point: Point | None
    theta: np.ndarray
    worst: float
    kkt: KKTPoint
    names: list[tuple[str, int | None]]
    iterations: int
    evaluations: int
    messages: list[str]
    off_pin: str = ""

    @property
    def converged(self) -> bool:
        """A KKT point of the family's problem holding every limit (and, pinned, off the pin
        the worst depth rises)."""
        return (self.point is not None and self.kkt.residual <= KKT_TOL
                and not self.off_pin.startswith("descent"))

    def ground_multipliers(self) -> dict[int, float]:
        """The multipliers of the active depth rows by ground (they sum to 1 at a KKT point)."""
        out: dict[int, float] = {}
        for row, lam in zip(self.kkt.rows, self.kkt.multipliers, strict=True):
            kind, k = self.names[row]
            if kind == "depth" and k is not None:
                out[k] = out.get(k, 0.0) + float(lam)
        return out

    def limit_multipliers(self) -> list[tuple[str, int | None, float]]:
        """The active limits' rows (kind, ground) and multipliers, the depths left out."""
        return [(*self.names[row], float(lam))
                for row, lam in zip(self.kkt.rows, self.kkt.multipliers, strict=True)
                if self.names[row][0] != "depth"]


def _epigraph(measures: Measures, scale_d: float) -> Callable[[np.ndarray], np.ndarray]:
    """The rows of ``x = [theta, z]`` scaled to order one (feasible where >= 0)."""
    fam = measures.family
    s, g = fam.robot.s, len(fam.grounds)
    per = measures.per_ground
    big = 10 * scale_d * max(1.0, s)

    def cons(x: np.ndarray) -> np.ndarray:
        m = measures(x[:-1])
        ground = m[:per * g].reshape(g, per)
        depth = ground[:, 0]
        margin = np.where(np.isfinite(depth), x[-1] - depth, -big)
        rest = m[per * g + 1:]
        return np.concatenate([np.column_stack([margin / scale_d, ground[:, 1:] / s]).ravel(),
                               [m[per * g] / fam.u_max], rest / scale_d])

    return cons


def run_family(family: PieceFamily, theta0: np.ndarray, max_iterations: int,
               restarts: int = RESTARTS, *, from_start: bool = False) -> Run:
    """SLSQP on the epigraph problem of ``family`` from ``theta0``, restarted from its best
    point while the KKT check fails.

    Parameters
    ----------
    family : PieceFamily
        The family.
    theta0 : ndarray
        The start.
    max_iterations : int
        SLSQP iterations per run.
    restarts : int
        Runs after the first.
    from_start : bool
        Count the runs from SLSQP's first: where ``theta0`` holds every limit, its KKT check
        is not one of them (``restarts=0``: the KKT check there, then one SLSQP run unless
        it converged).
    """
    measures = Measures(family)
    scale_d = max(1.0, abs(family.impact.v0))
    cons = _epigraph(measures, scale_d)
    per, g = measures.per_ground, len(family.grounds)

    def worst(key: bytes) -> float:  # the rows' (smooth) and the replays' (reported)
        return max(float(np.max(measures.cache[key][:per * g:per])), measures.replayed[key])

    theta0 = np.asarray(theta0, float)
    measures(theta0)
    z0 = worst(theta0.tobytes())
    x = np.concatenate([theta0, [z0 if math.isfinite(z0) else 10 * scale_d]])
    lo_t, hi_t = family.bounds()
    lo, hi = np.r_[lo_t, 0.0], np.r_[hi_t, np.inf]
    grad_f = np.eye(len(x))[-1] / scale_d
    iterations, kkt, messages = 0, KKTPoint(math.inf), []
    feasible = [k for k in measures.cache if measures.holds[k]]
    for attempt in range(1 + restarts + (from_start and bool(feasible))):
        if attempt or not feasible:
            # SLSQP on finite differences: every row is smooth while each landing's sequence
            # of events is kept (a stroke extremum is an interior one: its derivative is the
            # state's); deterministic, unlike the derivative-free searches tried (COBYQA)
            res = minimize(lambda v: v[-1] / scale_d, x, method="SLSQP",
                           jac=lambda v: grad_f, bounds=list(zip(lo, hi, strict=True)),
                           constraints=[{"type": "ineq", "fun": cons}],
                           options={"maxiter": max_iterations, "ftol": 1e-14, "eps": FD_STEP})
            iterations += int(res.nit)
            messages.append(str(res.message))
        feasible = [k for k in measures.cache if measures.holds[k]]
        if not feasible:
            break
        best = min(feasible, key=worst)
        moved = not np.array_equal(np.frombuffer(best), x[:-1])
        x = np.r_[np.frombuffer(best), worst(best)]
        if moved or not math.isfinite(kkt.residual):
            kkt = kkt_point(cons, x, lo, hi, grad_f)
        if kkt.residual <= KKT_TOL or (attempt and not moved):
            break  # converged, or a restart cannot move it
    if not feasible:  # nothing holds: the least violating point
        best = min(measures.cache, key=lambda k: _violation(measures, k))
        return Run(family, None, np.frombuffer(best).copy(), math.inf, KKTPoint(math.inf),
                   measures.names(), iterations, len(measures.cache), messages)
    point = family.resolve(x[:-1])
    return Run(family, point, x[:-1].copy(), float(x[-1]), kkt, measures.names(), iterations,
               len(measures.cache), messages)


def _violation(measures: Measures, key: bytes) -> float:
    """How far a point's limits are broken (its rows but the depths, relative to ``s``)."""
    m = measures.cache[key]
    per, g = measures.per_ground, len(measures.family.grounds)
    limits = np.r_[m[:per * g].reshape(g, per)[:, 1:].ravel(), m[per * g:]]
    return -min(0.0, float(np.min(limits))) / measures.family.robot.s


def worst_of(family: PieceFamily, p: Point) -> tuple[float, bool]:
    """The worst depth of a schedule's exact replays and whether every one holds every limit.

    Parameters
    ----------
    family : PieceFamily
        The family (its landing and grounds).
    p : Point
        The schedule's pieces.
    """
    sched = family.schedule(p)
    results = simulate_on_grounds(family.robot, family.impact, sched, family.grounds)
    return max(r.depth for r in results), all(r.feasible for r in results)


def off_pin_check(run: Run) -> str:
    """Off a pinned family's KKT point: the pinned duration moved by a small step either way
    (the other pieces kept), the worst depth of the exact replays must rise or a limit break.

    Returns ``""`` without a pin or a KKT point; ``"rises on both sides (slopes a, b)"``;
    ``"descent ..."`` where it falls on a side holding every limit.

    Parameters
    ----------
    run : Run
        A search run.
    """
    fam, p = run.family, run.point
    if fam.pin is None or p is None or run.kkt.residual > KKT_TOL:
        return ""
    base, _ = worst_of(fam, p)
    j = fam.pin.piece
    h = OFF_PIN_STEP * max(1.0, float(p.d[j]))
    found = []
    for sign in (-1.0, 1.0):
        d = p.d.copy()
        d[j] += sign * h
        unpinned = PieceFamily(fam.robot, fam.impact, fam.grounds, fam.n)
        q = Point(d, p.u, unpinned.last_force(d, p.u), None)
        if not abs(q.u_last) <= fam.u_max:
            found.append("a limit breaks")
            continue
        value, holds = worst_of(unpinned, q)
        slope = (value - base) / h
        if holds and slope < -1e-6 * max(1.0, base):
            return f"descent off the pin ({'shorter' if sign < 0 else 'longer'} piece " \
                   f"{j + 1}: slope {slope:.3g})"
        found.append(f"{slope:.3g}" + ("" if holds else " (a limit breaks)"))
    return f"rises on both sides of the pinned duration (slopes {found[0]}, {found[1]})"


def pin_at(family: PieceFamily, p: Point) -> Pin | None:
    """The pin a converged search would need: the binding ground's first stop tied to the
    switch nearest it (not the last, which is the body's stop); None if its foot stops in the
    first piece or the tie is no schedule.

    Parameters
    ----------
    family : PieceFamily
        The unpinned family.
    p : Point
        The point (the search's best).
    """
    sched = family.schedule(p)
    results = simulate_on_grounds(family.robot, family.impact, sched, family.grounds)
    k = int(np.argmax([r.depth for r in results]))
    t_stop = results[k].t_first_stop
    switches = np.cumsum(p.d)[:-1]
    if not math.isfinite(t_stop) or not len(switches):
        return None
    j = int(np.argmin(np.abs(switches - t_stop)))
    if j == 0 and t_stop < switches[0] * 0.5:
        return None
    pin = Pin(j, k)
    trial = PieceFamily(family.robot, family.impact, family.grounds, family.n, pin)
    return pin if trial.resolve(trial.theta(p.d, p.u)) is not None else None


@dataclass(frozen=True)
class Start:
    """A start of the search.

    Parameters
    ----------
    d : ndarray
        The durations.
    u : ndarray
        The forces but the last.
    pin : Pin, optional
        The pin of its family.
    """

    d: np.ndarray
    u: np.ndarray
    pin: Pin | None = None


def search(family_of: Callable[[int, Pin | None], PieceFamily], starts: Sequence[Start],
           max_iterations: int) -> tuple[Run, list[Run]]:
    """Search from each start in turn until one converges (see the module notes); the chosen
    run (converged first, then the lowest worst depth holding every limit) and every run.

    Parameters
    ----------
    family_of : callable
        ``(n, pin) -> PieceFamily``.
    starts : sequence of Start
        The starts, in order.
    max_iterations : int
        SLSQP iterations per run.
    """
    runs: list[Run] = []
    for st in starts:
        fam = family_of(len(st.d), st.pin)
        if st.pin is not None:
            runs.append(_checked(run_family(fam, fam.theta(st.d, st.u), max_iterations)))
        else:
            runs += _unpinned(family_of, fam, st, max_iterations)
        if any(r.converged for r in runs):
            break
    ranked = sorted(runs, key=lambda r: (not r.converged, r.point is None, r.worst))
    return ranked[0], runs


def _checked(run: Run) -> Run:
    """The run, its pinned optimum checked off the pin."""
    run.off_pin = off_pin_check(run)
    return run


def _unpinned(family_of: Callable[[int, Pin | None], PieceFamily], fam: PieceFamily,
              st: Start, max_iterations: int) -> list[Run]:
    """An unpinned start's runs: one SLSQP run finds the structure (its depths have kinks, so
    restarting it seldom converges: at v0 = -6 and -10 on the study's grounds its four restarts
    were 80 % of the search and the pinned search converged to the same schedule without
    them), then the pinned search at its binding ground's stop; only where that does not
    converge do the unpinned restarts go on from the best point, and the pin is tried again."""
    runs: list[Run] = []
    theta = fam.theta(st.d, st.u)
    for first in (True, False):
        run = _checked(run_family(fam, theta, max_iterations, 0 if first else RESTARTS,
                                  from_start=first))
        runs.append(run)
        if run.converged or run.point is None:
            break
        pin = pin_at(fam, run.point)
        if pin is not None:
            pinned = family_of(len(st.d), pin)
            runs.append(_checked(run_family(pinned, pinned.theta(run.point.d, run.point.u),
                                            max_iterations)))
            if runs[-1].converged:
                break
        theta = run.theta
    return runs


__all__ = ["ACTIVE_TOL", "FD_STEP", "KKT_STEP", "KKT_TOL", "MAX_ITERATIONS", "OFF_PIN_STEP",
           "RESTARTS", "KKTPoint", "Run", "Start", "kkt_point", "kkt_residual", "off_pin_check",
           "pin_at", "run_family", "search", "worst_of"]
