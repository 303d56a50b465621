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

import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.gridview import grid_spacing, is_collocation, mesh_level
from .activity import (
    active_path_constraints,
    control_bounds_at,
    drop_uncrossable,
    known_values,
    no_control_crosses,
    path_activity,
)
from .arc_structure import (
    BANG,
    Arc,
    ArcStructure,
    Interval,
    SolutionLike,
    SwitchingStructure,
    TranscribedSolution,
    transcribed,
)
from .constraint_kinds import (
    CONTROL,
    control_constraints,
    coupled_groups,
    path_kinds,
    riding_controls,
)
from .control_set import control_polytope, vertex_faces, violated_control_constraint
from .flows import Mode

# the types and the activity checks, importable from here as before the split
__all__ = ["BANG", "Arc", "ArcStructure", "Interval", "SolutionLike", "SwitchingStructure",
           "TranscribedSolution", "active_path_constraints", "control_bounds_at",
           "detect_arcs", "detect_structure", "known_values", "no_control_crosses",
           "outside_control_set", "path_activity", "snap_to_control_set", "transcribed"]


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
    drop_uncrossable(sol, at_lo, at_up)
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
