"""What kind of path constraint: on the state, mixed, or on the controls only.

The one place that classifies a path constraint ``lo <= c(x, u, t, p) <= hi``
(:func:`constraint_kind`), used by structure detection, refinement and the
certificate alike:

* ``"state"``   -- no control in ``c``: held on a *boundary arc*, where the
  control is whatever keeps the state on it (found through the constraint's
  time derivatives), and the costate may jump at its ends;
* ``"mixed"``   -- a control and the state (or the time) in ``c``: held, it
  bounds the control as a function of the state;
* ``"control"`` -- controls only (and parameters or decision variables): it
  shapes the admissible control set itself, e.g. ``u1 + u2 <= 1``. The
  controls then sit at a vertex of the set ``{u : bounds, control-only
  constraints}`` (a polytope when they are linear), and the minimum principle
  minimises the Hamiltonian over that set: such a constraint never makes a
  boundary arc.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

import casadi as ca

from ..definition.problem import Constraint, OptimalControlProblem

STATE, MIXED, CONTROL = "state", "mixed", "control"
KINDS = (STATE, MIXED, CONTROL)

# per problem, per constraint object: what was found (the symbolic checks cost ~1 ms each,
# and structure detection asks for every control and constraint)
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _cached(pr: OptimalControlProblem, what: str, con: Constraint,
            compute: Callable[[], Any]) -> Any:
    store = _CACHE.setdefault(pr, {})
    key = (what, id(con))
    hit = store.get(key)
    if hit is None or hit[0] is not con:
        hit = store[key] = (con, compute())
    return hit[1]

MAX_RELATIVE_DEGREE = 3
"""Highest time derivative of a state constraint searched for a control."""


def _constraint(pr: OptimalControlProblem, c: Constraint | str) -> Constraint:
    if not isinstance(c, str):
        return c
    for con in pr.structure_path:
        if con.name == c:
            return con
    raise ValueError(f"no path constraint named {c!r}; have {[k.name for k in pr.structure_path]}")


def constraint_kind(pr: OptimalControlProblem, c: Constraint | str) -> str:
    """``"state"``, ``"mixed"`` or ``"control"``: what path constraint ``c`` involves.

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint or str
        A path constraint of ``pr`` (or its name).

    Returns
    -------
    str
        ``"control"`` when ``c`` involves a control and neither a state nor the
        time (``t``, ``t0``, ``T``); ``"mixed"`` when it involves a control and a
        state or the time; ``"state"`` when it involves no control.
    """
    con = _constraint(pr, c)

    def compute() -> str:
        if pr.nu == 0 or not ca.depends_on(con.expr, pr.u):
            return STATE
        other = ca.vertcat(pr.x, pr.t, pr.t0, pr.T)
        return MIXED if ca.depends_on(con.expr, other) else CONTROL

    return str(_cached(pr, "kind", con, compute))


def is_control_only(pr: OptimalControlProblem, c: Constraint | str | None) -> bool:
    """True when path constraint ``c`` is a control constraint (:func:`constraint_kind`
    is ``"control"``).

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint, str or None
        A path constraint of ``pr``, its name, or None (False).
    """
    return c is not None and constraint_kind(pr, c) == CONTROL


def path_kinds(pr: OptimalControlProblem) -> list[str]:
    """:func:`constraint_kind` of every path constraint, in ``pr.structure_path`` order.

    Parameters
    ----------
    pr : OptimalControlProblem
        The problem.
    """
    return [constraint_kind(pr, c) for c in pr.structure_path]


def control_constraints(pr: OptimalControlProblem, linear: bool = False) -> list[Constraint]:
    """The control-only path constraints of ``pr`` (with ``linear``: only those affine in u).

    Parameters
    ----------
    pr : OptimalControlProblem
    linear : bool
        Keep only the constraints affine in the controls (the faces of a polytope).

    Returns
    -------
    list of Constraint
    """
    out = [c for c in pr.structure_path if constraint_kind(pr, c) == CONTROL]
    if linear and out:
        u = pr.u

        def affine(c: Constraint) -> bool:
            return bool(_cached(pr, "linear", c,
                                lambda: not ca.depends_on(ca.jacobian(c.expr, u), u)))

        out = [c for c in out if affine(c)]
    return out


def controls_in(pr: OptimalControlProblem, c: Constraint | str) -> tuple[str, ...]:
    """Names of the controls that appear in path constraint ``c`` itself.

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint or str

    Returns
    -------
    tuple of str
    """
    con = _constraint(pr, c)

    def compute() -> tuple[str, ...]:
        u = pr.u
        return tuple(n for j, n in enumerate(pr.control_names) if ca.depends_on(con.expr, u[j]))

    return tuple(_cached(pr, "controls", con, compute))


def riding_controls(pr: OptimalControlProblem, c: Constraint | str) -> tuple[str, ...]:
    """The controls that can keep path constraint ``c`` at a limit (on a boundary arc).

    Those that appear in the first time derivative of ``c`` along the dynamics
    that involves any control (its relative degree, at most
    :data:`MAX_RELATIVE_DEGREE`); the controls in ``c`` itself for a mixed
    constraint. A control-only constraint has none: it is a face of the control
    set, not a boundary arc.

    Parameters
    ----------
    pr : OptimalControlProblem
    c : Constraint or str

    Returns
    -------
    tuple of str
    """
    con = _constraint(pr, c)
    kind = constraint_kind(pr, con)
    if kind == CONTROL:
        return ()
    if kind == MIXED:
        return controls_in(pr, con)

    def compute() -> tuple[str, ...]:
        d, x, u, rhs = con.expr, pr.x, pr.u, pr.rhs
        for _ in range(MAX_RELATIVE_DEGREE):
            d = ca.jtimes(d, x, rhs)
            if ca.depends_on(d, u):
                return tuple(n for j, n in enumerate(pr.control_names)
                             if ca.depends_on(d, u[j]))
        return ()

    return tuple(_cached(pr, "riding", con, compute))


def coupled_groups(pr: OptimalControlProblem, singletons: bool = False) -> list[tuple[str, ...]]:
    """Sets of controls coupled by linear control-only constraints in several controls.

    Two controls are in one group when some linear control-only constraint
    involves both (transitively). Controls in no such constraint are in no group.

    Parameters
    ----------
    pr : OptimalControlProblem
    singletons : bool
        Also return, as a group of one, each control in a linear control-only
        constraint of its own (``u1 <= 0.5``: its set is an interval).

    Returns
    -------
    list of tuple of str
        In ``pr.control_names`` order within each group.
    """
    parent = {n: n for n in pr.control_names}

    def root(n: str) -> str:
        while parent[n] != n:
            n = parent[n]
        return n

    linked: set[str] = set()
    for c in control_constraints(pr, linear=True):
        names = controls_in(pr, c)
        if len(names) < 2 and not singletons:
            continue
        linked.update(names)
        for n in names[1:]:
            parent[root(n)] = root(names[0])
    groups: dict[str, list[str]] = {}
    for n in pr.control_names:
        if n in linked:
            groups.setdefault(root(n), []).append(n)
    return [tuple(g) for g in groups.values()]
