"""One form for bounds, however the user wrote them.

A bound on one state may be given as ``p.state("v", upper=0.8)``, set later by
``p.bound_state("v", upper=0.8)``, or written as a path constraint on that state
alone (``p.path_constraint(v, upper=0.8)``, or ``2 * v - 1 <= 0.6``); a control
bound likewise (``p.control("u", -1, 1)`` or ``p.path_constraint(u, -1, 1)``). They
are one constraint. :func:`normal_form` (run by the problem each time a bound or a
path constraint is added) gives every part of ``ocp`` its view of them:

* **transcriptions** impose what was written: declared bounds as bounds of the NLP's
  variables (``problem.state_bounds``, ``problem.control_bounds``), path constraints as
  rows (``problem.path``). Both impose the bound at the same nodes, so the feasible
  node values are the same; the NLPs differ only in how Ipopt treats a bound and a
  row (their optima agree to Ipopt's tolerance). A control limit that depends on a
  decision variable (``-peak <= u <= peak``, ``peak = p.variable(...)``) cannot be a
  variable bound of the NLP: it is the row ``u - peak <= 0`` (and its side of
  ``control_bounds`` is infinite);
* **structure detection, refinement and the certificate** see one form:
  ``problem.structure_path`` (the path constraints that are no bound, then one state
  constraint ``lower <= x_i <= upper`` per bounded state, the tightest of its declared
  bounds and its path constraints, named after the path constraints it came from or
  ``"bounds of state 'x'"``) and ``problem.control_limits`` (each control's tightest
  bounds, which may depend on decision variables: the control set at the variables'
  values). So the arcs, the refined solution and the verdict do not depend on how a
  bound was written.

A path constraint counts as a bound when it is one row ``a * s + b`` with ``s`` one
state or control, ``a`` a nonzero number and ``b`` a parameter expression (also of
decision variables for a control); anything else (two states, a time, a control and
a state) stays a path constraint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca

from .errors import ProblemDefinitionError
from .symbols import INF, Constraint, check_bounds, constant

Bounds = dict[str, tuple[ca.SX, ca.SX]]


@dataclass
class NormalForm:
    """The bounds and path constraints of one phase in the form every part of ocp reads.

    Attributes
    ----------
    path : list of Constraint
        The rows a transcription imposes: the path constraints as written, then the
        rows of declared control limits that depend on decision variables.
    state_bounds, control_bounds : dict
        Name -> ``(lower, upper)``, parameter expressions: the declared bounds, the NLP's
        variable bounds.
    control_limits : dict
        Name -> ``(lower, upper)``, expressions of parameters and decision variables:
        the control set.
    structure_path : list of Constraint
        What structure detection, refinement and the certificate see: the path
        constraints that are no bound, then one ``lower <= x_i <= upper`` per bounded
        state.
    bound_names : dict
        State or control name -> the name its bound is reported under.
    """

    path: list[Constraint] = field(default_factory=list)
    state_bounds: Bounds = field(default_factory=dict)
    control_bounds: Bounds = field(default_factory=dict)
    control_limits: Bounds = field(default_factory=dict)
    structure_path: list[Constraint] = field(default_factory=list)
    bound_names: dict[str, str] = field(default_factory=dict)


def single_variable_bound(c: Constraint, syms: ca.SX, rest: ca.SX
                          ) -> tuple[int, ca.SX, ca.SX] | None:
    """``(i, lower, upper)`` when ``c`` is ``lower <= syms[i] <= upper`` in disguise.

    Parameters
    ----------
    c : Constraint
        A path constraint.
    syms : SX
        The candidate symbols (states, or controls).
    rest : SX
        Every other running symbol ``c`` must not involve (the other kind of
        variable, time, and for states the decision variables).

    Returns
    -------
    (int, SX, SX) or None
    """
    e = c.expr
    if e.numel() != 1 or e.is_constant() or ca.depends_on(e, rest):
        return None
    hits = [i for i in range(syms.numel()) if ca.depends_on(e, syms[i])]
    if len(hits) != 1:
        return None
    s = syms[hits[0]]
    a = ca.jacobian(e, s)
    av = constant(ca.SX(a))
    if av is None or av == 0.0 or not math.isfinite(av):
        return None  # nonlinear in s, or a coefficient of the parameters
    b = ca.substitute(e, s, ca.SX(0))
    if constant(b) == 0.0 and av == 1.0:
        return hits[0], c.lower, c.upper  # the bound itself, not an expression of it
    def solved(v: ca.SX) -> ca.SX:  # (v - b) / a, an infinite limit staying infinite
        k = constant(v)
        if k is not None and math.isinf(k):
            return ca.SX(math.copysign(INF, k * av))
        return (v - b) / av

    lo, hi = solved(c.lower), solved(c.upper)
    return (hits[0], lo, hi) if av > 0 else (hits[0], hi, lo)


def _tighter(a: ca.SX, b: ca.SX, upper: bool) -> ca.SX:
    """The tighter of two bounds (one side), numbers folded."""
    none = INF if upper else -INF
    ca_, cb = constant(a), constant(b)
    if ca_ == none:
        return b
    if cb == none:
        return a
    if ca_ is not None and cb is not None:
        return ca.SX(min(ca_, cb) if upper else max(ca_, cb))
    return ca.fmin(a, b) if upper else ca.fmax(a, b)


def normal_form(declared_states: Bounds, declared_controls: Bounds, written: list[Constraint],
                x: ca.SX, state_names: list[str], u: ca.SX, control_names: list[str],
                variables: ca.SX, times: ca.SX) -> NormalForm:
    """The :class:`NormalForm` of a phase (see the module docstring).

    Parameters
    ----------
    declared_states, declared_controls : dict
        Bounds given by ``state``/``bound_state`` and ``control``/``bound_control``
        (control bounds may involve decision variables).
    written : list of Constraint
        The path constraints as written.
    x, u : SX
        States and controls, stacked.
    state_names, control_names : list of str
    variables : SX
        The decision variables, stacked.
    times : SX
        ``t``, ``t0``, ``T``.

    Raises
    ------
    ProblemDefinitionError
        When the bounds of a state or control leave no value.
    """
    out = NormalForm()
    sb = dict(declared_states)
    limits = dict(declared_controls)
    names: dict[str, list[str]] = {}
    general = []
    for c in written:
        hit = single_variable_bound(c, x, ca.vertcat(u, times, variables))
        store, labels = sb, state_names
        if hit is None:
            hit = single_variable_bound(c, u, ca.vertcat(x, times))
            store, labels = limits, control_names
        if hit is None:
            general.append(c)
            continue
        i, lo, hi = hit
        k = labels[i]
        old = store[k]
        store[k] = (_tighter(old[0], lo, False), _tighter(old[1], hi, True))
        check_bounds(*store[k], f"{'state' if store is sb else 'control'} {k!r} "
                                f"(with path constraint {c.name!r})")
        names.setdefault(k, []).append(c.name)
    out.bound_names = {k: " & ".join(v) for k, v in names.items()}
    # the transcriptions impose what was written: declared bounds as bounds of the NLP's
    # variables, path constraints as rows (a bound written either way is one set of
    # feasible node values; moving rows to variable bounds changes Ipopt's path to it)
    out.state_bounds = dict(declared_states)
    out.control_limits = limits
    out.path = list(written)
    for j, k in enumerate(control_names):
        sides = []
        for side, b in enumerate(declared_controls[k]):
            if ca.depends_on(b, variables):
                # a limit that moves with a decision variable is a row, u - b on one side of 0
                label = f"bounds of control {k!r} ({'lower' if side == 0 else 'upper'})"
                row = Constraint(u[j] - b, ca.SX(0 if side == 0 else -INF),
                                 ca.SX(INF if side == 0 else 0), label)
                out.path.append(row)
                b = ca.SX(-INF if side == 0 else INF)
            sides.append(b)
        out.control_bounds[k] = (sides[0], sides[1])
    out.structure_path = list(general)
    for i, k in enumerate(state_names):
        lo, hi = sb[k]
        if constant(lo) == -INF and constant(hi) == INF:
            continue
        out.structure_path.append(
            Constraint(x[i], lo, hi, out.bound_names.get(k) or f"bounds of state {k!r}"))
    for k in control_names:
        out.bound_names.setdefault(k, f"bounds of control {k!r}")
    for k in state_names:
        out.bound_names.setdefault(k, f"bounds of state {k!r}")
    return out


def require_no_variable(bound: ca.SX, variables: ca.SX, what: str) -> None:
    """Refuse a decision variable in a state bound (the NLP imposes those as bounds).

    Parameters
    ----------
    bound : SX
    variables : SX
        The decision variables, stacked.
    what : str
        Named in the error.
    """
    if variables.numel() and ca.depends_on(bound, variables):
        raise ProblemDefinitionError(f"{what} may not depend on a decision variable; write "
                                     "it as a path constraint (e.g. x - k <= 0)")
