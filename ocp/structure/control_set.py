"""The polyhedral control set of coupled controls, and the Hamiltonian's minimiser over it.

Controls tied by linear control-only path constraints (``u1 + u2 <= 1``,
``w1 + w2 + w3 = 1``; see :mod:`ocp.structure.constraint_kinds`) take their values in a
polytope ``P = {u : lo <= u <= hi, clo <= A u <= chi}``, not in a box. For a
control-affine problem the minimum principle asks ``u`` to minimise
``sigma^T u`` over ``P``, a linear programme whose minimum is attained at a
vertex. Polytopes of a few controls are small, so their vertices are
enumerated once (:func:`control_polytope`) and the programme at every sample
is a product with the vertex matrix (:func:`vertex_scores`): the minimiser is
unique where the best vertex beats the second best by a clear margin, and the
programme is degenerate (a singular arc if it lasts) where it does not.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from .constraint_kinds import control_constraints, controls_in

MAX_COMBINATIONS = 200_000
"""Most active sets tried when enumerating the vertices of a polytope."""


@dataclass
class ControlPolytope:
    """The admissible set of a group of coupled controls, by its vertices.

    Attributes
    ----------
    controls : tuple of str
        The group's controls.
    index : tuple of int
        Their positions in the problem's control vector.
    vertices : ndarray (n_vertices, len(controls))
    lower, upper : ndarray
        The controls' own bounds (infinite where the constraints alone bound them).
    """

    controls: tuple[str, ...]
    index: tuple[int, ...]
    vertices: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    @property
    def span(self) -> np.ndarray:
        """Each control's range over the polytope, at least 1 (the scale of its tolerance)."""
        return np.maximum(1.0, np.ptp(self.vertices, axis=0))


def _numeric(pr: OptimalControlProblem, exprs: list[ca.SX], pv: np.ndarray) -> np.ndarray:
    if not exprs:
        return np.zeros(0)
    fn = ca.Function("v", [pr.p, pr.v], [ca.vertcat(*exprs)])
    vv = np.zeros(pr.nv)  # control-only constraints with decision variables: at 0 (rare)
    return np.array(fn(pv, vv), dtype=float).ravel()


def control_polytope(pr: OptimalControlProblem, group: tuple[str, ...],
                     pv: np.ndarray) -> ControlPolytope | None:
    """The polytope of a group of coupled controls
    (:func:`~ocp.structure.constraint_kinds.coupled_groups`) at parameter values ``pv``, with
    its vertices.

    Parameters
    ----------
    pr : OptimalControlProblem
    group : tuple of str
        Control names.
    pv : ndarray
        Parameter values.

    Returns
    -------
    ControlPolytope or None
        None when the set is unbounded, empty, or too large to enumerate.
    """
    idx = tuple(pr.control_names.index(n) for n in group)
    k = len(idx)
    lo = _numeric(pr, [pr.control_bounds[n][0] for n in group], pv)
    hi = _numeric(pr, [pr.control_bounds[n][1] for n in group], pv)
    ug = ca.vertcat(*[pr.u[j] for j in idx])
    eye = np.eye(k)
    rows_G: list[np.ndarray] = [eye[np.isfinite(hi)], -eye[np.isfinite(lo)]]
    rows_h: list[np.ndarray] = [hi[np.isfinite(hi)], -lo[np.isfinite(lo)]]
    for c in control_constraints(pr, linear=True):
        if not set(controls_in(pr, c)) <= set(group):
            continue
        a = _numeric(pr, [ca.jacobian(c.expr, ug).T], pv)
        b = _numeric(pr, [ca.substitute(c.expr, pr.u, ca.DM.zeros(pr.nu))], pv)[0]
        clo, chi = _numeric(pr, [c.lower, c.upper], pv)
        if math.isfinite(chi):
            rows_G.append(a[None, :])
            rows_h.append(np.array([chi - b]))
        if math.isfinite(clo):
            rows_G.append(-a[None, :])
            rows_h.append(np.array([b - clo]))
    G, h = np.vstack(rows_G), np.concatenate(rows_h)
    boxed = bool(np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)))
    if not boxed and not bounded(G):
        return None
    V = polytope_vertices(G, h)
    if V is None or not len(V):
        return None
    return ControlPolytope(tuple(group), idx, V, lo, hi)


def bounded(G: np.ndarray) -> bool:
    """True when ``{u : G u <= h}`` is bounded for every ``h``: no direction ``d != 0`` with
    ``G d <= 0`` (checked by a linear programme per coordinate direction and sign).

    Parameters
    ----------
    G : ndarray (m, k)

    Returns
    -------
    bool
    """
    from scipy.optimize import linprog  # imported on first use: scipy.optimize is slow to load

    m, k = G.shape
    if m <= k:
        return False
    for j in range(k):
        for sign in (1.0, -1.0):
            c = np.zeros(k)
            c[j] = -sign  # maximise sign * d_j over the recession cone, |d| <= 1
            res = linprog(c, A_ub=G, b_ub=np.zeros(m), bounds=[(-1.0, 1.0)] * k,
                          method="highs")
            if res.status != 0 or -res.fun > 1e-9:
                return False
    return True


def polytope_vertices(G: np.ndarray, h: np.ndarray, tol: float = 1e-9) -> np.ndarray | None:
    """Vertices of the bounded polytope ``{u : G u <= h}`` by enumerating active sets.

    Parameters
    ----------
    G : ndarray (m, k)
    h : ndarray (m,)
    tol : float
        Feasibility tolerance (relative to ``max(1, |h|)``) and distance under
        which two vertices are one.

    Returns
    -------
    ndarray (n_vertices, k) or None
        None when there are more than :data:`MAX_COMBINATIONS` active sets.
    """
    m, k = G.shape
    if math.comb(m, k) > MAX_COMBINATIONS:
        return None
    slack = tol * np.maximum(1.0, np.abs(h))
    found: list[np.ndarray] = []
    for rows in itertools.combinations(range(m), k):
        Gs = G[list(rows)]
        if abs(np.linalg.det(Gs)) < 1e-12:
            continue
        v = np.linalg.solve(Gs, h[list(rows)])
        if np.all(G @ v <= h + slack) and not any(np.max(np.abs(v - w)) <= tol for w in found):
            found.append(v)
    return np.array(found).reshape(-1, k)


@dataclass
class VertexScores:
    """The linear programme ``min sigma^T u over P`` at every sample.

    Attributes
    ----------
    best : ndarray of int (m,)
        Index of a minimising vertex.
    value : ndarray (m,)
        The minimum of ``sigma^T u``.
    gap : ndarray (m,)
        Second-best vertex score minus the best (>= 0): the minimiser is unique
        where it is clearly positive.
    signed : ndarray (m,)
        ``gap`` with a sign that flips every time the minimising vertex changes:
        it crosses zero at a switch from one vertex to another, as a switching
        function does.
    """

    best: np.ndarray
    value: np.ndarray
    gap: np.ndarray
    signed: np.ndarray


def vertex_scores(poly: ControlPolytope, sigma: np.ndarray) -> VertexScores:
    """Solve ``min sigma_i^T u over poly`` for every row ``sigma_i`` (m, len(poly.controls)).

    Parameters
    ----------
    poly : ControlPolytope
    sigma : ndarray (m, k)
        The switching functions of the group's controls at each sample.

    Returns
    -------
    VertexScores
    """
    S = np.asarray(sigma, dtype=float) @ poly.vertices.T  # (m, n_vertices)
    order = np.argsort(S, axis=1, kind="stable")
    best = order[:, 0]
    rows = np.arange(len(S))
    value = S[rows, best]
    gap = S[rows, order[:, 1]] - value if S.shape[1] > 1 else np.full(len(S), np.inf)
    flips = np.r_[0, np.cumsum(best[1:] != best[:-1])]
    signed = np.where(flips % 2 == 0, 1.0, -1.0) * gap
    return VertexScores(best, value, gap, signed)


def distance_to_vertices(poly: ControlPolytope, u: np.ndarray) -> np.ndarray:
    """Largest-component distance of each control vector to its nearest vertex, relative
    to each control's range.

    Parameters
    ----------
    poly : ControlPolytope
    u : ndarray (m, len(poly.controls))
        The group's controls at m samples.

    Returns
    -------
    ndarray (m,)
    """
    d = np.abs(np.asarray(u, dtype=float)[:, None, :] - poly.vertices[None, :, :]) / poly.span
    return np.asarray(np.min(np.max(d, axis=2), axis=1))


def vertex_faces(pr: OptimalControlProblem, poly: ControlPolytope, vertex: np.ndarray,
                 pv: np.ndarray, tol: float = 1e-6) -> dict[str, tuple[int, str]]:
    """Which control-only constraint fixes each control of a vertex that is not at a bound.

    At a vertex of the polytope, a control strictly inside its own bounds is set
    by a control-only constraint held at a limit. Controls (in order) are matched
    to distinct active constraints that involve them, so the held constraints
    determine the vertex (one equation per such control).

    Parameters
    ----------
    pr : OptimalControlProblem
    poly : ControlPolytope
    vertex : ndarray (len(poly.controls),)
    pv : ndarray
        Parameter values.
    tol : float
        Distance (relative to ``max(1, |value|)``) at which a bound or a limit is met.

    Returns
    -------
    dict
        Control name -> ``(index of the constraint in pr.structure_path, "lower" or "upper")``;
        the controls at a bound of their own are not in it.
    """
    u = np.zeros(pr.nu)
    u[list(poly.index)] = vertex
    group = set(poly.controls)
    faces: list[tuple[int, str, set[str]]] = []
    linear = {c.name for c in control_constraints(pr, linear=True)}
    for i, c in enumerate(pr.structure_path):
        names = set(controls_in(pr, c))
        if c.name not in linear or not names <= group:
            continue
        fn = ca.Function("f", [pr.u, pr.p, pr.v], [c.expr, c.lower, c.upper])
        val, lo, hi = (float(a) for a in fn(u, pv, np.zeros(pr.nv)))
        room = tol * max(1.0, abs(val))
        for side, limit in (("upper", hi), ("lower", lo)):
            if math.isfinite(limit) and abs(val - limit) <= room:
                faces.append((i, side, names))
                break
    out: dict[str, tuple[int, str]] = {}
    used: set[int] = set()
    for j, name in enumerate(poly.controls):
        room = tol * max(1.0, abs(vertex[j]))
        if abs(vertex[j] - poly.lower[j]) <= room or abs(vertex[j] - poly.upper[j]) <= room:
            continue
        for i, side, names in faces:
            if name in names and i not in used:
                out[name] = (i, side)
                used.add(i)
                break
    return out


def violated_control_constraint(problem: OptimalControlProblem, u: np.ndarray, pv: np.ndarray,
                                tol: float = 1e-9) -> str | None:
    """The first control-only path constraint that the control vector ``u`` violates.

    Parameters
    ----------
    problem : OptimalControlProblem
    u : ndarray (nu,)
        One value per control.
    pv : ndarray
        Parameter values.
    tol : float
        Allowed violation, relative to ``max(1, |value|)``.

    Returns
    -------
    str or None
        Its name; None when ``u`` is in the control set (or there is no such constraint).
    """
    cons = control_constraints(problem)
    if not cons:
        return None
    fn = ca.Function("cc", [problem.x, problem.u, problem.p],
                     [ca.vertcat(*[c.expr for c in cons]), ca.vertcat(*[c.lower for c in cons]),
                      ca.vertcat(*[c.upper for c in cons])])
    # control-only: the state does not enter, any value will do
    v, lo, hi = (np.array(a, dtype=float).ravel()
                 for a in fn(np.zeros(problem.nx), np.asarray(u, dtype=float), pv))
    room = tol * np.maximum(1.0, np.abs(v))
    bad = np.flatnonzero((lo - v > room) | (v - hi > room))
    return cons[int(bad[0])].name if len(bad) else None
