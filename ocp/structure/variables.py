"""Decision variables in the switching refinement: each one a state that does not move.

A decision variable ``k`` (``p.variable``) may appear in the dynamics, the costs, the
constraints and a control's limits (``-peak <= u <= peak``, the epigraph form of
``min max |u|``). The refinement's unknowns are the arc durations and the initial
state; :func:`variables_as_states` turns every decision variable into one more state
with ``k' = 0`` whose initial value is free within the variable's bounds, so the
switching times and the variables are refined together by the same NLP, and an arc
at ``u = peak`` is a bang arc of a limit that is a (constant) state. The certificate
then minimises H over the control set at the variable's value (the limits evaluated
along the refined arcs, :func:`ocp.certificate.from_refined.effective_bounds`).

What the derived problem cannot carry is refused: an initial time other than the
default, integrals in boundary terms, and boundary terms on the initial state or on
the end-point controls (the refinement reads the end-point cost and constraints at
``T`` only).

A phase of a multi-phase problem is flowed the same way
(:func:`phase_variables_as_states`: the phase's flows only, when
:func:`moves_with_variables` says it involves a variable); the multi-phase refinement
(:mod:`ocp.structure.phase_refinement`) keeps the variables as unknowns of its own and
imposes the end-point terms on the whole problem.
"""

from __future__ import annotations

import weakref
from typing import Any

import casadi as ca

from ..definition.problem import OptimalControlProblem
from ..definition.symbols import INF, constant
from .derived_times import refuse_shifted_time, same_final_time

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def variables_as_states(pr: OptimalControlProblem) -> OptimalControlProblem:
    """The problem with every decision variable a constant state (built once per problem).

    The states keep their names, then come the variables' (same names); the path
    constraints, bounds and control limits keep their names, so the arc structure of
    a transcribed solution of ``pr`` is one of the derived problem.

    Parameters
    ----------
    pr : OptimalControlProblem
        A single-phase problem with decision variables.

    Returns
    -------
    OptimalControlProblem

    Raises
    ------
    ValueError
        What the refinement cannot represent (see the module docstring).
    """
    return _cached(pr, "problem", _build)


def phase_variables_as_states(ph: OptimalControlProblem) -> OptimalControlProblem:
    """A phase's flows with every decision variable a constant state (built once per phase).

    What the multi-phase refinement (:mod:`ocp.structure.phase_refinement`) reads of a
    phase: states (the phase's, then the variables'), controls, dynamics, running cost,
    path constraints and control limits, by the same names as in ``ph``, and whether
    the phase's final time is free. The end-point terms are not copied: the multi-phase
    refinement imposes them on the whole problem, the variables being its own unknowns.

    Parameters
    ----------
    ph : OptimalControlProblem
        A phase of a :class:`ocp.MultiPhaseProblem` (or a single-phase problem).

    Returns
    -------
    OptimalControlProblem
    """
    return _cached(ph, "phase", _build_phase)


def moves_with_variables(pr: OptimalControlProblem) -> bool:
    """Whether the dynamics, running cost, path constraints or control limits of ``pr``
    involve a decision variable (then it is refined as :func:`phase_variables_as_states`).

    Parameters
    ----------
    pr : OptimalControlProblem
    """
    if not pr.nv:
        return False
    exprs = [pr.rhs, ca.SX(pr.lagrange)]
    exprs += [b for n in pr.control_names for b in pr.control_limits[n]]
    exprs += [e for c in pr.structure_path for e in (c.expr, c.lower, c.upper)]
    return bool(ca.depends_on(ca.vertcat(*[ca.vec(ca.SX(e)) for e in exprs]), pr.v))


def _cached(pr: OptimalControlProblem, kind: str, build: Any) -> OptimalControlProblem:
    per = _CACHE.setdefault(pr, {})
    hit = per.get(kind)
    if hit is not None and hit[0] == _key(pr):
        return hit[1]
    q = build(pr)
    per[kind] = (_key(pr), q)
    return q


def _key(pr: OptimalControlProblem) -> str:
    return str((pr.rhs, pr.lagrange, pr.mayer, pr.boundary_cost, pr.control_limits,
                [(c.expr, c.lower, c.upper) for c in pr.path_written + pr.initial
                 + pr.terminal + pr.boundary], pr.state_bounds, pr.T_bounds, pr.time_free))


def _flows(pr: OptimalControlProblem, name: str) -> tuple[OptimalControlProblem, Any]:
    """The derived problem's symbols, control bounds, dynamics, path constraints and
    running cost; and the substitution of ``pr``'s symbols by its."""
    q = OptimalControlProblem(name)
    P = [q.parameter(n) for n in pr.param_names]
    X = [q.state(n) for n in pr.state_names]
    V = [q.state(n) for n in pr.var_names]
    U = [q.control(n) for n in pr.control_names]
    old = ca.vertcat(pr.p, pr.x, pr.v, pr.u, pr.t, pr.t0, pr.T)
    new = ca.vertcat(*P, *X, *V, *U, q.t, q.t0, q.T)

    def sub(e: ca.SX) -> ca.SX:
        return ca.substitute(ca.SX(e), old, new)

    for n in pr.control_names:
        q.bound_control(n, *(sub(b) for b in pr.control_bounds[n]))
    q.set_dynamics({**{n: sub(e) for n, e in zip(pr.state_names, ca.vertsplit(pr.rhs),
                                                  strict=True)},
                    **{n: ca.SX(0) for n in pr.var_names}})
    # what structure detection sees, by the same names (modes refer to them): the state
    # bounds (declared or written) and the other path constraints
    for c in pr.structure_path:
        q.path_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    if pr.has_running_cost():
        q.minimize_integral(sub(pr.lagrange))
    return q, sub


def _limits(q: OptimalControlProblem, pr: OptimalControlProblem, sub: Any) -> None:
    """The control set moves with the variables: their states now (set last: the API
    re-derives the normal form each time a bound or path constraint is added)."""
    q.control_limits = {n: (sub(lo), sub(hi)) for n, (lo, hi) in pr.control_limits.items()}


def _build(pr: OptimalControlProblem) -> OptimalControlProblem:
    refuse_shifted_time(pr)
    if pr.integrals:
        raise ValueError("refinement with decision variables: integrals in boundary terms are "
                         "not supported (use minimize_integral)")
    q, sub = _flows(pr, f"{pr.name} (variables as constant states)")
    V = q.x[pr.nx:]
    for j, n in enumerate(pr.var_names):  # the variable's bounds hold at the start
        lo, hi = pr.variable_bounds(n)
        if constant(lo) != -INF or constant(hi) != INF:
            q.initial_constraint(V[j], sub(lo), sub(hi), name=f"bounds of variable {n!r}")
    for c in pr.initial:
        q.initial_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    for c in pr.terminal:
        q.terminal_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    for c in pr.boundary:
        q.terminal_constraint(_at_T(pr, c.expr, sub, f"boundary constraint {c.name!r}"),
                              sub(c.lower), sub(c.upper), name=c.name)
    mayer = sub(pr.mayer)
    if not ca.SX(pr.boundary_cost).is_zero():
        mayer = mayer + _at_T(pr, pr.boundary_cost, sub, "the end-point cost")
    q.minimize_terminal(mayer)
    same_final_time(q, pr)
    _limits(q, pr, sub)
    return q


def _build_phase(ph: OptimalControlProblem) -> OptimalControlProblem:
    q, sub = _flows(ph, ph.name)  # (the phase's name: results and reports name phases)
    if ph.time_free:  # (free or fixed is what the certificate reads; the bounds are the
        q.free_duration()  # multi-phase problem's, imposed by the refinement)
    _limits(q, ph, sub)
    return q


def _at_T(pr: OptimalControlProblem, e: ca.SX, sub, what: str) -> ca.SX:
    """An end-point expression read at ``T``: final states stand for the states."""
    e = ca.SX(e)
    if ca.depends_on(e, ca.vertcat(pr.x0, pr.u0, pr.uT)):
        raise ValueError(f"refinement with decision variables: {what} involves initial "
                         "values or end-point controls; write it with final states, "
                         "variables and T")
    return sub(ca.substitute(e, pr.xT, pr.x))


__all__ = ["moves_with_variables", "phase_variables_as_states", "variables_as_states"]
