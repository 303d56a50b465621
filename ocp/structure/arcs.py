"""Arc structure of a transcribed solution: bang, boundary and interior arcs per control.

:func:`detect_arcs` labels each shooting interval of one control by where the
control sits (upper bound ``"max"``, lower bound ``"min"``, or strictly
inside) and merges them into arcs. An interior run of at most
``max_transition`` intervals between two different bang arcs is the switch
(its time is estimated from the interval's average control). A longer
interior run on which a path constraint is active at every node is a
**boundary arc** (``"boundary"``, with the constraint and the limit it sits
at): there the control is whatever keeps the state on the constraint. Only a
control that can hold the constraint rides it (one in the constraint, or in
its first time derivative that involves a control: see
:func:`ocp.structure.constraint_kinds.riding_controls`); a control-only constraint
(``u1 + u2 <= 1``) is a face of the control set, never a boundary arc: the
controls sit at a vertex of that set, each at a bound when the set's vertices
are corners of the box. Any other interior run stays ``"interior"`` (a
singular or free arc: not refinable by switching times).

:func:`detect_structure` does this for every control and merges the switch
events of all controls into one list of intervals (an :class:`ArcStructure`),
which is what the refinement's unknowns are: the durations of the intervals
between consecutive switch events of any control.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, cast

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.gridview import grid_spacing, is_collocation, mesh_level
from ..transcriptions.solution import Solution, along
from .constraint_kinds import (
    CONTROL,
    KINDS,
    control_constraints,
    coupled_groups,
    path_kinds,
    riding_controls,
)
from .control_set import control_polytope, vertex_faces, violated_control_constraint
from .flows import Mode

BANG = ("max", "min")


class TranscribedSolution(Protocol):
    """What this package reads of an :class:`ocp.Solution` (which sets these attributes
    dynamically, so type checkers cannot see them on the class)."""

    problem: OptimalControlProblem
    transcription: Any
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    T: float
    N: int
    params: dict[str, float]
    variables: dict[str, float]
    multipliers: dict[str, np.ndarray]
    objective: float

    def control(self, name: str) -> np.ndarray:
        """The column of control ``name``.

        Parameters
        ----------
        name : str
            Control name.
        """
        ...

    def evaluate(self, expr: ca.SX) -> np.ndarray:
        """An expression of (x, u, p) at every node.

        Parameters
        ----------
        expr : casadi.SX
            An expression of the problem's states, controls and parameters.
        """
        ...


SolutionLike = Solution | TranscribedSolution
"""A transcribed solution, as passed in (``Solution``) or as read (the protocol)."""


def transcribed(sol: SolutionLike) -> TranscribedSolution:
    """``sol`` typed by :class:`TranscribedSolution` (no conversion).

    Parameters
    ----------
    sol : Solution or Trajectory-like
        A solution of a transcription.
    """
    return cast(TranscribedSolution, sol)


@dataclass
class Arc:
    """A maximal interval where one control sits at a bound, on a constraint, or inside.

    Attributes
    ----------
    kind : {"max", "min", "boundary", "vertex", "interior", "singular"}
        ``"singular"`` only where a caller has classified an interior arc as singular
        (:func:`ocp.structure.interior_arcs.refinable_arcs`).
    start, end : float
    active : tuple of str
        State and mixed path constraints active at every node of the arc.
    constraint, side : str or None
        On a boundary arc, the constraint held and its limit (``"lower"``/``"upper"``).
    faces : tuple of str
        Control-only path constraints active at every node of the arc (faces of
        the control set the controls sit on; not state constraints).
    """

    kind: str
    start: float
    end: float
    active: tuple[str, ...] = ()
    constraint: str | None = None
    side: str | None = None
    faces: tuple[str, ...] = ()

    @property
    def duration(self) -> float:
        """``end - start``."""
        return self.end - self.start

    def mode_key(self) -> tuple[str, str | None, str | None]:
        """``(kind, constraint, side)``: arcs with equal keys merge."""
        return (self.kind, self.constraint, self.side)

    @property
    def mode(self) -> Mode:
        """The arc as a refinement :class:`~ocp.structure.flows.Mode` (bang or boundary arcs
        only)."""
        if self.kind == "interior":
            raise ValueError("an interior (singular or free) arc has no refinement mode")
        return Mode(self.kind, self.constraint, self.side)


@dataclass
class SwitchingStructure:
    """Arcs of one control, and whether they are all bang arcs.

    Attributes
    ----------
    control : str
        The control's name.
    arcs : list of Arc
        Its arcs in time order.
    lower, upper : float
        Its bounds.
    """

    control: str
    arcs: list[Arc]
    lower: float
    upper: float

    @property
    def kinds(self) -> list[str]:
        """The arcs' kinds in order."""
        return [a.kind for a in self.arcs]

    @property
    def bang_bang(self) -> bool:
        """Every arc at a bound or at a vertex of the control set (no boundary and no
        interior arc)."""
        return all(a.kind in BANG or a.kind == "vertex" for a in self.arcs)

    @property
    def refinable(self) -> bool:
        """Every arc is a bang or a boundary arc: switching-time refinement applies."""
        return all(a.kind != "interior" for a in self.arcs)

    @property
    def switch_times(self) -> list[float]:
        """Times between consecutive arcs."""
        return [a.end for a in self.arcs[:-1]]

    def without_trailing_constrained(self) -> SwitchingStructure:
        """Drop a final non-bang arc on which a path (state) constraint is active.

        On such an arc the control is whatever keeps the state on its
        constraint, not a bang. Dropping it refines the problem whose final
        time is the end of the last bang arc, which is the right question when
        the terminal conditions already account for the constrained tail (as
        the soft landing's body-arrest condition does).
        """
        last = self.arcs[-1]
        if len(self.arcs) > 1 and last.kind not in BANG and last.active:
            return SwitchingStructure(self.control, self.arcs[:-1], self.lower, self.upper)
        return self


@dataclass
class Interval:
    """An interval between consecutive switch events of any control, with each control's mode.

    Attributes
    ----------
    start, end : float
        The interval's times.
    modes : tuple of Mode
        Each control's mode on it.
    """

    start: float
    end: float
    modes: tuple[Mode, ...]

    @property
    def duration(self) -> float:
        """``end - start``."""
        return self.end - self.start


@dataclass
class ArcStructure:
    """The arc structure of every control, merged into intervals.

    Attributes
    ----------
    controls : tuple of str
    per_control : tuple of SwitchingStructure
        One per control.
    intervals : list of Interval
        Between consecutive switch events of any control; the refinement's unknowns
        are their durations.
    """

    controls: tuple[str, ...]
    per_control: tuple[SwitchingStructure, ...]
    intervals: list[Interval] = field(default_factory=list)

    @property
    def modes(self) -> tuple[tuple[Mode, ...], ...]:
        """Per interval, the mode of every control."""
        return tuple(iv.modes for iv in self.intervals)

    @property
    def kinds(self) -> list[tuple[str, ...]]:
        """Per interval, the kind of every control."""
        return [tuple(m.kind for m in iv.modes) for iv in self.intervals]

    @property
    def durations(self) -> list[float]:
        """Interval lengths."""
        return [iv.duration for iv in self.intervals]

    @property
    def switch_times(self) -> list[float]:
        """Switch events of any control, in order."""
        return [iv.end for iv in self.intervals[:-1]]

    @property
    def bang_bang(self) -> bool:
        """Every control bang-bang."""
        return all(s.bang_bang for s in self.per_control)

    @property
    def refinable(self) -> bool:
        """Every arc of every control is a bang or boundary arc."""
        return all(s.refinable for s in self.per_control)

    @property
    def T(self) -> float:
        """End of the last interval."""
        return self.intervals[-1].end if self.intervals else 0.0

    @classmethod
    def from_controls(cls, structures: list[SwitchingStructure] | tuple[SwitchingStructure, ...],
                      merge_tol: float = 1e-12) -> ArcStructure:
        """Merge per-control arcs into intervals between the switch events of all controls.

        Events of different controls closer than ``merge_tol * T`` are one event.
        When some control has an interior (singular or free) arc there are no
        intervals (``refinable`` is False).
        """
        structures = tuple(structures)
        names = tuple(s.control for s in structures)
        if not all(s.refinable for s in structures):
            return cls(names, structures, [])  # interior arcs: no refinement intervals
        T = max(s.arcs[-1].end for s in structures)
        ev = sorted({t for s in structures for t in s.switch_times})
        events: list[float] = []
        for t in ev:
            if not events or t - events[-1] > merge_tol * max(T, 1.0):
                events.append(t)
        edges = [0.0, *events, T]
        intervals: list[Interval] = []
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            mid = 0.5 * (a + b)
            modes = tuple(_arc_at(s, mid).mode for s in structures)
            if intervals and intervals[-1].modes == modes:
                intervals[-1].end = b
            else:
                intervals.append(Interval(a, b, modes))
        return cls(names, structures, intervals)

    @classmethod
    def from_modes(cls, controls: tuple[str, ...], modes: list[tuple[Mode, ...]],
                   durations: list[float]) -> ArcStructure:
        """A structure given directly by interval modes and durations (a guess)."""
        edges = np.r_[0.0, np.cumsum(durations)]
        intervals = [Interval(float(edges[k]), float(edges[k + 1]), tuple(m))
                     for k, m in enumerate(modes)]
        per = []
        for j, name in enumerate(controls):
            arcs: list[Arc] = []
            for iv in intervals:
                m = iv.modes[j]
                if arcs and arcs[-1].mode == m:
                    arcs[-1].end = iv.end
                else:
                    arcs.append(Arc(m.kind, iv.start, iv.end, (), m.constraint, m.side))
            per.append(SwitchingStructure(name, arcs, np.nan, np.nan))
        return cls(tuple(controls), tuple(per), intervals)


def _arc_at(s: SwitchingStructure, t: float) -> Arc:
    for a in s.arcs:
        if t <= a.end:
            return a
    return s.arcs[-1]


def control_bounds_at(problem: OptimalControlProblem, name: str,
                      params: dict[str, float]) -> tuple[float, float]:
    """Numeric ``(lower, upper)`` bounds of control ``name`` at the values ``params``.

    The control's limits (``problem.control_limits``, :mod:`ocp.definition.normal_form`)
    may involve decision variables (``u <= peak``), and in a problem derived for the
    refinement, the states that stand for them: their values are looked up by name in
    ``params`` too (:func:`known_values` of a solution has them).

    Parameters
    ----------
    problem : OptimalControlProblem
    name : str
        A control's name.
    params : dict
        A value for every parameter of the problem (and for every decision variable
        or state the limits involve).

    Returns
    -------
    (float, float)

    Raises
    ------
    ValueError
        When the limits involve a variable whose value ``params`` does not give.
    """
    lo, hi = problem.control_limits[name]
    both = ca.vertcat(lo, hi)
    if both.is_constant():
        return float(ca.DM(lo)), float(ca.DM(hi))
    syms, vals = [], []
    for names, vec in ((problem.param_names, problem.p), (problem.var_names, problem.v),
                       (problem.state_names, problem.x)):
        for i, n in enumerate(names):
            if ca.depends_on(both, vec[i]):
                if n not in params:
                    raise ValueError(f"the bounds of control {name!r} depend on {n!r}: "
                                     "its value is needed")
                syms.append(vec[i])
                vals.append(float(params[n]))
    f = ca.Function("b", [ca.vertcat(*syms)], [lo, hi])
    a, b = (float(v) for v in f(vals))
    return a, b


def known_values(sol: SolutionLike) -> dict[str, float]:
    """A solution's parameter values and its decision variables' optimised values.

    Parameters
    ----------
    sol : Solution
        A transcribed (or refined) solution.
    """
    return {**transcribed(sol).params, **(getattr(sol, "variables", None) or {})}


def path_activity(sol: SolutionLike, tol: float,
                  kinds: tuple[str, ...] = KINDS) -> tuple[np.ndarray, np.ndarray]:
    """Which path constraints sit at which limit at every node.

    Parameters
    ----------
    sol : Solution
        A transcribed solution.
    tol : float
        Relative distance to a limit that counts as at it.
    kinds : tuple of str
        Which kinds of constraint to report (:func:`ocp.structure.constraint_kinds.constraint_kind`:
        ``"state"``, ``"mixed"``, ``"control"``); the columns of the others are False.

    Returns
    -------
    at_lower, at_upper : bool arrays (N+1, n_path)
        Within ``tol * max(1, |value|)`` of the lower (upper) limit.
    """
    tsol = transcribed(sol)
    pr = tsol.problem
    n = tsol.N + 1
    if not pr.structure_path:
        return np.zeros((n, 0), dtype=bool), np.zeros((n, 0), dtype=bool)
    pv = [tsol.params[k] for k in pr.param_names]
    lows, ups = [], []
    for c, kind in zip(pr.structure_path, path_kinds(pr), strict=True):
        if kind not in kinds:
            lows.append(np.zeros(n, dtype=bool))
            ups.append(np.zeros(n, dtype=bool))
            continue
        vals = tsol.evaluate(c.expr)
        lo, hi = (float(v) for v in ca.Function("b", [pr.p], [c.lower, c.upper])(pv))
        scale = tol * np.maximum(1.0, np.abs(vals))
        lows.append(np.abs(vals - lo) <= scale)
        ups.append(np.abs(vals - hi) <= scale)
    return np.column_stack(lows), np.column_stack(ups)


def active_path_constraints(sol: SolutionLike, tol: float,
                            kinds: tuple[str, ...] = KINDS,
                            crossable: bool = False) -> np.ndarray:
    """Which path constraints are active (at either limit) at every node.

    Parameters
    ----------
    sol : Solution
        A transcribed solution.
    tol : float
        As in :func:`path_activity`.
    kinds : tuple of str
        As in :func:`path_activity`.
    crossable : bool
        Count a state constraint at a limit only where some admissible control could
        cross it (:func:`no_control_crosses`).

    Returns
    -------
    ndarray of bool (N+1, n_path)
    """
    tsol = transcribed(sol)
    lo, up = path_activity(tsol, tol, kinds)
    if crossable:
        _drop_uncrossable(tsol, lo, up)
    return lo | up


def no_control_crosses(pr: OptimalControlProblem, c: Any, side: str, x: np.ndarray,
                       los: np.ndarray, his: np.ndarray, pv: np.ndarray,
                       tol: float = 1e-9) -> np.ndarray:
    """Where no admissible control could push state constraint ``c`` across its ``side``
    limit: ``dc/dt = a(x) + b(x) u`` is on the feasible side for every ``u`` in the box.

    A state at such a limit is not held there by the constraint (``m <= 1`` while
    ``m' = -u/E`` with ``u >= 0``): touching it is no constrained arc, and the costate
    does not jump there. A constraint whose first derivative does not involve the
    controls (relative degree 2 or more), or involves them nonlinearly, can always be
    crossed here (False).

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint
        A state constraint (no control in it).
    side : {"lower", "upper"}
    x : ndarray (m, nx)
        States at the samples.
    los, his : ndarray (m, nu)
        The control set's box at the samples.
    pv : ndarray
        Parameter values.
    tol : float
        Allowed push across, relative to the size of the terms.

    Returns
    -------
    ndarray of bool (m,)
    """
    dc = ca.jtimes(c.expr, pr.x, pr.rhs)
    b = ca.jacobian(dc, pr.u)
    if pr.nu == 0 or ca.depends_on(b, pr.u) or not ca.depends_on(dc, pr.u) \
            or ca.depends_on(dc, ca.vertcat(pr.t, pr.t0, pr.T, pr.v)):
        return np.zeros(len(x), dtype=bool)
    a = ca.substitute(dc, pr.u, ca.DM.zeros(pr.nu))
    av, bv = along(ca.Function("ab", [pr.x, pr.p], [a, b.T]), x, pv)
    av = av.ravel()
    with np.errstate(invalid="ignore"):
        ends = np.stack([bv * los, bv * his])  # (2, m, nu); 0 * inf is nan: no push
    ends = np.where(bv[None] == 0.0, 0.0, ends)
    push = av + (np.sum(np.max(ends, axis=0), axis=1) if side == "upper"
                 else np.sum(np.min(ends, axis=0), axis=1))
    size = np.abs(av) + np.sum(np.abs(np.where(np.isfinite(ends), ends, 0.0)), axis=(0, 2))
    scale = tol * np.maximum(1.0, size)
    ok = push <= scale if side == "upper" else push >= -scale
    return np.isfinite(push) & ok



def _runs(labels: list[str]) -> list[list]:
    runs: list[list] = []  # [label, first interval, last interval]
    for k, lb in enumerate(labels):
        if runs and runs[-1][0] == lb:
            runs[-1][2] = k
        else:
            runs.append([lb, k, k])
    return runs


def _clusters(active: np.ndarray, max_gap: int) -> list[tuple[int, int, int]]:
    """``(first node, last node, active count)`` of groups of active nodes whose
    gaps are at most ``max_gap`` inactive nodes."""
    idx = np.flatnonzero(active)
    out: list[tuple[int, int, int]] = []
    for k in idx.tolist():
        if out and k - out[-1][1] <= max_gap + 1:
            out[-1] = (out[-1][0], k, out[-1][2] + 1)
        else:
            out.append((k, k, 1))
    return out


def _drop_uncrossable(sol: TranscribedSolution, at_lo: np.ndarray, at_up: np.ndarray) -> None:
    """Clear the nodes where a state constraint sits at a limit no admissible control
    could cross there (:func:`no_control_crosses`): not held by the constraint."""
    pr = sol.problem
    if not (at_lo.any() or at_up.any()):
        return
    values = known_values(sol)
    box = [control_bounds_at(pr, n, values) for n in pr.control_names]
    x = np.asarray(sol.x, dtype=float)
    los = np.tile([b[0] for b in box], (len(x), 1))
    his = np.tile([b[1] for b in box], (len(x), 1))
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    for i, c in enumerate(pr.structure_path):
        for side, at in (("lower", at_lo), ("upper", at_up)):
            if at[:, i].any() and not ca.depends_on(c.expr, pr.u):
                at[:, i] &= ~no_control_crosses(pr, c, side, x, los, his, pv)


def _boundary_labels(sol: TranscribedSolution, lab: list[str], tol: float, max_gap: int,
                     min_nodes: int, control: str) -> None:
    """Relabel as ``"boundary:<i>:<side>"`` the intervals between the first and the last
    node of every cluster of at least ``min_nodes`` nodes where path constraint i sits at
    one limit (gaps of ``max_gap`` nodes allowed: a transcription zig-zags along a
    constraint of relative degree two), unless the control sits at one bound throughout.
    Only state and mixed constraints that ``control`` can hold are considered (a
    control-only constraint is a face of the control set, not a boundary arc)."""
    pr = sol.problem
    at_lo, at_up = path_activity(sol, tol, kinds=("state", "mixed"))
    _drop_uncrossable(sol, at_lo, at_up)
    for i in range(at_lo.shape[1]):
        if not (at_lo[:, i].any() or at_up[:, i].any()) or \
                control not in riding_controls(pr, pr.structure_path[i]):
            continue
        for side, act in (("lower", at_lo[:, i]), ("upper", at_up[:, i])):
            for a, b, count in _clusters(act, max_gap):
                span = lab[a:b]
                if count < min_nodes or b - a < 2 or any(x.startswith("boundary") for x in span):
                    continue
                if len(set(span)) == 1 and span[0] in BANG:
                    continue  # a bang arc along the constraint
                lab[a:b] = [f"boundary:{i}:{side}"] * (b - a)


def _vertex_labels(sol: TranscribedSolution, lab: list[str], tol: float, control: str) -> None:
    """Relabel as ``"vertex:<i>:<side>"`` the interior intervals where the group of
    coupled controls sits at a vertex of its polytope at which ``control`` is inside
    its own bounds, fixed by control-only constraint i at its ``side`` limit."""
    pr = sol.problem
    group = next((g for g in coupled_groups(pr, singletons=True) if control in g), None)
    if group is None or "interior" not in lab:
        return
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    poly = control_polytope(pr, group, pv)
    if poly is None:
        return
    U = np.column_stack([sol.control(n) for n in group])
    rng = poly.span
    faces: dict[int, dict[str, tuple[int, str]]] = {}
    for k, label in enumerate(lab):
        if label != "interior" or k >= len(U):
            continue
        dist = np.max(np.abs(U[k] - poly.vertices) / rng, axis=1)
        v = int(np.argmin(dist))
        if dist[v] > tol:
            continue
        if v not in faces:
            faces[v] = vertex_faces(pr, poly, poly.vertices[v], pv)
        if control in faces[v]:
            i, side = faces[v][control]
            lab[k] = f"vertex:{i}:{side}"


def _run_width(t: np.ndarray | None, a: int, b: int) -> float:
    """Length of grid intervals ``a..b`` in mean intervals (their count on an even grid;
    a refined collocation mesh crowds short intervals around a switch)."""
    if t is None or len(t) < 2:
        return float(b - a + 1)
    return float((t[b + 1] - t[a]) / ((t[-1] - t[0]) / (len(t) - 1))) - 1e-9


def _absorb_end_transitions(runs: list[list], max_transition: int,
                            t: np.ndarray | None = None) -> None:
    """A short interior run at either end next to another arc is that arc (the grid
    cannot end the arc exactly on a node); ``t``: the grid times (default even)."""
    for end in (0, -1):
        nb = 1 if end == 0 else -2
        if (len(runs) > 1 and runs[end][0] == "interior" and runs[nb][0] != "interior"
                and _run_width(t, runs[end][1], runs[end][2]) <= max_transition):
            if end == 0:
                runs[1][1] = runs[0][1]
            else:
                runs[-2][2] = runs[-1][2]
            del runs[end]


def _arcs_from_runs(sol: TranscribedSolution, runs: list[list], u: np.ndarray, h: float, lo: float,
                    hi: float, max_transition: int) -> list[Arc]:
    names = [c.name for c in sol.problem.structure_path]
    t = np.asarray(sol.t, dtype=float)
    arcs: list[Arc] = []
    for i, (label, a, b) in enumerate(runs):
        start = a * h if not arcs else arcs[-1].end
        if (label == "interior" and 0 < i < len(runs) - 1
                and _run_width(t, a, b) <= max_transition
                and runs[i - 1][0] != "interior" and runs[i + 1][0] != "interior"
                and runs[i - 1][0] != runs[i + 1][0]):
            # the switch lies inside: split by the average control
            _split_transition(arcs, runs, i, u, h, lo, hi, t)
            continue
        if label.startswith(("boundary", "vertex")):
            kind, ci, side = label.split(":")
            arcs.append(Arc(kind, start, (b + 1) * h, (), names[int(ci)], side))
        else:
            arcs.append(Arc(label, start, (b + 1) * h))
    merged: list[Arc] = []
    for arc in arcs:
        if merged and merged[-1].mode_key() == arc.mode_key():
            merged[-1].end = arc.end
        else:
            merged.append(arc)
    return merged


def _split_transition(arcs: list[Arc], runs: list[list], i: int, u: np.ndarray, h: float,
                      lo: float, hi: float, t: np.ndarray | None = None) -> None:
    """Place the switch inside transition run i (its previous arc is ``arcs[-1]``).

    Between two bang (or vertex) arcs the switch splits the interval by its average
    control.
    Between a boundary and a bang arc, an average outside the range of the
    boundary control (the mean of its two nearest intervals) and the bang value
    means a short arc of the opposite bang lies inside: it is inserted, next
    to the boundary arc, with the length that reproduces the average. Positions are
    in units of ``h`` per grid interval; on an uneven grid ``t`` the average is
    weighted by duration and a fraction of the run is a fraction of its duration.
    """
    prev, nxt = runs[i - 1], runs[i + 1]
    _, a, b = runs[i]
    grid = np.arange(len(u) + 1, dtype=float) if t is None else t
    k = np.arange(len(grid), dtype=float)
    dur = np.diff(grid)[a:b + 1]
    avg = float(np.sum(u[a:b + 1] * dur) / np.sum(dur))

    def at(frac: float) -> float:  # a fraction of the run's duration, in units of h
        return float(np.interp(grid[a] + frac * (grid[b + 1] - grid[a]), grid, k)) * h

    val = {"max": hi, "min": lo}
    for run in (prev, nxt):  # a vertex arc's value is a constant, as a bang's
        if run[0].startswith("vertex"):
            val[run[0]] = float(np.median(u[run[1]:run[2] + 1]))
    if prev[0] in val and nxt[0] in val:
        ua, ub = val[prev[0]], val[nxt[0]]
        theta = float(np.clip((avg - ub) / (ua - ub), 0.0, 1.0))
        arcs[-1].end = at(theta)
        return
    bang, bnd = (nxt, prev) if nxt[0] in BANG else (prev, nxt)
    ub = float(np.mean(u[bnd[2] - 1:bnd[2] + 1] if bnd is prev else u[bnd[1]:bnd[1] + 2]))
    v = val.get(bang[0], ub)
    margin = 0.05 * (hi - lo)
    if bang[0] not in BANG or min(ub, v) - margin <= avg <= max(ub, v) + margin:
        arcs[-1].end = at(0.5)
        return
    other = "min" if bang[0] == "max" else "max"
    theta = float(np.clip((v - avg) / (v - val[other]), 0.05, 0.95))
    if bnd is prev:  # boundary, other, bang
        arcs[-1].end = a * h
        arcs.append(Arc(other, a * h, at(theta)))
    else:  # bang, other, boundary
        arcs[-1].end = at(1 - theta)
        arcs.append(Arc(other, arcs[-1].end, (b + 1) * h))


def _label_active(sol: TranscribedSolution, arcs: list[Arc], h: float, tol: float) -> None:
    """Fill ``active`` (state and mixed path constraints) and ``faces`` (control-only
    ones) active at every node inside each arc."""
    pr = sol.problem
    act = active_path_constraints(sol, tol)
    kinds = path_kinds(pr)
    for arc in arcs:
        k0 = int(round(arc.start / h)) if h > 0 else 0
        k1 = max(k0 + 1, int(round(arc.end / h)))
        nodes = act[k0 + 1:k1] if k1 - k0 > 1 else act[k0:k1]
        held = [i for i in range(len(pr.structure_path)) if nodes.shape[0] and nodes[:, i].all()]
        arc.active = tuple(pr.structure_path[i].name for i in held if kinds[i] != CONTROL)
        arc.faces = tuple(pr.structure_path[i].name for i in held if kinds[i] == CONTROL)
        if arc.constraint is not None and arc.constraint not in arc.active:
            arc.active = (arc.constraint, *arc.active)


def detect_arcs(sol: SolutionLike, control: str | None = None, tol: float = 1e-4,
                max_transition: int = 1, max_gap: int = 1,
                min_boundary_nodes: int = 3) -> SwitchingStructure:
    """Bang, boundary and interior arcs of one control of a transcribed solution.

    Parameters
    ----------
    sol : Solution
    control : str, optional
        Which control (default: the first).
    tol : float
        An interval is at a bound when within ``tol * max(1, |bound|)`` of it;
        a path constraint is active at a node when within ``tol * max(1, |value|)``
        of a limit.
    max_transition : int
        Interior runs of at most this many intervals between two different
        arcs are read as the switch (the control averages both bounds over the
        interval that contains the switching time); such runs at either end of
        the horizon are read as the neighbouring arc. On an uneven grid the run's
        length counts in mean intervals.
    max_gap, min_boundary_nodes : int
        A boundary arc spans a group of at least ``min_boundary_nodes`` nodes at
        which one path constraint sits at one limit, with gaps of at most
        ``max_gap`` nodes (a transcription zig-zags along a constraint of
        relative degree two), unless the control sits at one bound throughout.

    Returns
    -------
    SwitchingStructure

    Notes
    -----
    A collocation solution is read on its mesh (:func:`ocp.transcriptions.gridview.mesh_level`):
    per mesh interval, the quadrature average of the control over its collocation
    points, and the path constraints at the mesh points. Its control polynomials
    spread a switch over the points next to it, so a transition may be one mean
    interval longer than ``max_transition``.
    """
    # a collocation solution is read on its mesh (one average control per interval);
    # arcs are found in units of grid intervals, then placed on the grid's times
    tsol = transcribed(mesh_level(sol))
    pr = tsol.problem
    name = control or pr.control_names[0]
    lo, hi = control_bounds_at(pr, name, known_values(tsol))
    u = tsol.control(name)
    h = 1.0
    at_hi = np.isfinite(hi) & (np.abs(u - hi) <= tol * max(1.0, abs(hi)))
    at_lo = np.isfinite(lo) & (np.abs(u - lo) <= tol * max(1.0, abs(lo)))
    lab = np.where(at_hi, "max", np.where(at_lo, "min", "interior")).tolist()
    _boundary_labels(tsol, lab, tol, max_gap, min_boundary_nodes, name)
    _vertex_labels(tsol, lab, tol, name)
    runs = _runs(lab)
    # a collocation control spreads a switch over the neighbouring points: one more
    # (mean) interval of transition
    width = max_transition + 1 if is_collocation(sol) else max_transition
    _absorb_end_transitions(runs, width, np.asarray(tsol.t, dtype=float))
    arcs = _arcs_from_runs(tsol, runs, u, h, lo, hi, width)
    arcs[-1].end = float(tsol.N)
    _label_active(tsol, arcs, h, tol)
    _place_on_grid(arcs, np.asarray(tsol.t, dtype=float))  # the last ends at t[N] = T
    return SwitchingStructure(name, arcs, lo, hi)


def _place_on_grid(arcs: list[Arc], t: np.ndarray) -> None:
    """Turn arc ends in units of grid intervals (fractions inside one) into times on the
    grid ``t`` (uneven on a refined collocation mesh)."""
    k = np.arange(len(t), dtype=float)
    for arc in arcs:
        arc.start, arc.end = (float(np.interp(v, k, t)) for v in (arc.start, arc.end))


def detect_structure(sol: SolutionLike, tol: float = 1e-4, max_transition: int = 1,
                     max_gap: int = 1, min_boundary_nodes: int = 3,
                     merge_tol: float = 1e-12) -> ArcStructure:
    """Arcs of every control (:func:`detect_arcs`) merged into one :class:`ArcStructure`.

    Parameters
    ----------
    sol : Solution
        A transcribed solution.
    tol : float
        As in :func:`detect_arcs`.
    max_transition : int
        As in :func:`detect_arcs`.
    max_gap : int
        As in :func:`detect_arcs`.
    min_boundary_nodes : int
        As in :func:`detect_arcs`.
    merge_tol : float
        Switch events of different controls closer than ``merge_tol * T`` are one event.

    Returns
    -------
    ArcStructure
        ``intervals`` is empty when some control has an interior (singular or
        free) arc.
    """
    tsol = transcribed(sol)
    per = [detect_arcs(tsol, name, tol, max_transition, max_gap, min_boundary_nodes)
           for name in tsol.problem.control_names]
    st = ArcStructure.from_controls(per, merge_tol)
    return snap_to_control_set(tsol, st, (max_transition + 1) * grid_spacing(tsol), merge_tol)


def outside_control_set(problem: OptimalControlProblem, modes: tuple[Mode, ...],
                        params: dict[str, float], tol: float = 1e-9) -> bool:
    """True when bang ``modes`` (one per control) put the controls outside the control set
    (some control-only path constraint violated: e.g. ``u1 + u2 <= 1`` with both at 1).

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of Mode
    params : dict
        A value for every parameter.
    tol : float
        Allowed violation, relative to ``max(1, |value|)``.

    Returns
    -------
    bool
        False when some mode is not a bang (its value depends on the state).
    """
    if not control_constraints(problem) or any(m.kind not in BANG for m in modes):
        return False
    u = []
    for name, m in zip(problem.control_names, modes, strict=True):
        lo, hi = control_bounds_at(problem, name, params)
        u.append(hi if m.kind == "max" else lo)
    pv = np.array([params[k] for k in problem.param_names], dtype=float)
    return violated_control_constraint(problem, np.array(u), pv, tol) is not None


def snap_to_control_set(sol: SolutionLike, st: ArcStructure, short: float,
                        merge_tol: float = 1e-12) -> ArcStructure:
    """Merge the switch events that bound a short interval outside the control set.

    Coupled controls switch together (``w1 + w2 + w3 = 1``: one mode leaves as
    another enters), but each control's switch time is read off its own
    transcribed values, so their estimates differ slightly and leave a sliver
    where the modes violate a control-only constraint. Such an interval, at most
    ``short`` long, is collapsed: the events at both its ends move to its middle.

    Parameters
    ----------
    sol : Solution
        The transcribed solution (problem and parameters).
    st : ArcStructure
    short : float
        Longest interval collapsed (longer ones are left for the refinement to reject).
    merge_tol : float
        As in :meth:`ArcStructure.from_controls`.

    Returns
    -------
    ArcStructure
    """
    tsol = transcribed(sol)
    pr = tsol.problem
    if not control_constraints(pr):
        return st
    for _ in range(len(st.intervals)):
        bad = [iv for iv in st.intervals[1:-1] if iv.duration <= short
               and outside_control_set(pr, iv.modes, known_values(tsol))]
        if not bad:
            return st
        a, b = bad[0].start, bad[0].end
        mid = 0.5 * (a + b)
        near = 1e-12 * max(st.T, 1.0)
        per = []
        for s in st.per_control:
            arcs = [Arc(x.kind, x.start, x.end, x.active, x.constraint, x.side, x.faces)
                    for x in s.arcs]
            for x, y in zip(arcs[:-1], arcs[1:], strict=True):
                if abs(x.end - a) <= near or abs(x.end - b) <= near:
                    x.end = y.start = mid
            per.append(SwitchingStructure(s.control, arcs, s.lower, s.upper))
        st = ArcStructure.from_controls(per, merge_tol)
    return st
