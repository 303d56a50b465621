"""Continuous-time optimal control problem definition (knows nothing of any application).

Example: minimum-time double integrator, rest to rest over a distance ``d``::

    from ocp import OptimalControlProblem, MultipleShooting
    p = OptimalControlProblem()
    x, v = p.state("x"), p.state("v")
    u = p.control("u", lower=-1, upper=1)
    d = p.parameter("d")
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - d, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(lower=0.01, upper=100, guess=2)
    p.minimize_terminal(p.T)
    sol = MultipleShooting(p, nodes=40).solve({"d": 1.0})

Symbols
-------
``p.t`` is time, ``p.t0`` the initial and ``p.T`` the final time; all three
may appear in the dynamics, path constraints and costs. ``p.at_t0(e)`` and
``p.at_tf(e)`` are an expression of the states and controls at ``t0`` and
``T``; ``p.integral(e)`` is ``int_t0^T e dt``. With them,
:meth:`~OptimalControlProblem.boundary_constraint` and
:meth:`~OptimalControlProblem.minimize` take any expression of the end points
(for instance ``p.at_tf(x) - p.at_t0(x)``, or a control at ``T``). The older
calls keep their implicit meaning: in :meth:`terminal_constraint` and
:meth:`minimize_terminal` a state or control symbol stands for its value at
``T``; in :meth:`initial_constraint`, at ``t0``.

Constraint and variable bounds may be numbers or expressions of the parameters
only; they are evaluated at solve time, so changing a parameter never rebuilds
the NLP. Parameters (set at solve time) and decision variables (optimised) are
shared by all phases of a :class:`ocp.MultiPhaseProblem`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np
from numpy import ndarray

from .errors import ProblemDefinitionError
from .normal_form import normal_form
from .symbols import (
    INF,
    Constraint,
    check_bounds,
    constant,
    finite_number,
    require_only,
    to_sx,
)

__all__ = ["INF", "Constraint", "OptimalControlProblem", "ProblemDefinitionError"]

RESERVED = ("t", "t0", "T")
Bound = float | ca.SX


class Shared:
    """Parameters (set at solve time) and decision variables (optimised), shared by phases."""

    def __init__(self) -> None:
        self.param_names: list[str] = []
        self.params: list[ca.SX] = []
        self.var_names: list[str] = []
        self.vars: list[ca.SX] = []
        self.var_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.var_guess: dict[str, ca.SX | None] = {}
        self.var_ref: dict[str, tuple[float, float] | None] = {}
        self.objective_ref: float | None = None  # set by minimize(..., ref=)
        self.phase_names: set[str] = set()  # states and controls of every phase

    @property
    def p(self) -> ca.SX:
        """The parameters, stacked."""
        return ca.vertcat(*self.params) if self.params else ca.SX(0, 1)

    @property
    def v(self) -> ca.SX:
        """The decision variables, stacked."""
        return ca.vertcat(*self.vars) if self.vars else ca.SX(0, 1)

    def taken(self, name: str) -> bool:
        """Whether ``name`` is already a parameter, a variable or reserved.

        Parameters
        ----------
        name : str
            A candidate name.
        """
        return name in self.param_names or name in self.var_names or name in RESERVED

    def bound(self, value: Bound, what: str) -> ca.SX:
        """A bound or guess: a number or an expression of the parameters.

        Parameters
        ----------
        value : float or SX
            A number or an expression of the parameters.
        what : str
            Named in the error if ``value`` is not acceptable.
        """
        b = to_sx(value, what)
        require_only(b, self.params, what, "bounds and guesses may depend on parameters only")
        return b

    def limit(self, value: Bound, what: str) -> ca.SX:
        """A control's bound: a number or an expression of the parameters and the decision
        variables (``u <= peak``: the control set moves with the variable).

        Parameters
        ----------
        value : float or SX
            A number or an expression of the parameters and variables.
        what : str
            Named in the error if ``value`` is not acceptable.
        """
        b = to_sx(value, what)
        require_only(b, [*self.params, *self.vars], what,
                     "a control's bounds may depend on parameters and decision variables only")
        return b


def _guess_value(shared: Shared, guess: Any, what: str) -> Any:
    """None, a number/parameter expression, or a ``(start, end)`` pair of them."""
    if guess is None:
        return None
    if isinstance(guess, tuple | list):
        if len(guess) != 2:
            raise ProblemDefinitionError(f"{what}: give one value or a (start, end) pair")
        return tuple(shared.bound(g, what) for g in guess)
    return shared.bound(guess, what)


def scale_ref(ref: float | None, ref0: float | None, what: str) -> tuple[float, float] | None:
    """``(ref0, ref)`` checked (finite, ``ref > 0``), or None if neither is given.

    As in dymos, the NLP sees ``(value - ref0) / ref``: ``ref0`` maps to 0 and
    ``ref0 + ref`` to 1 (``ref0`` defaults to 0, ``ref`` to 1).

    Parameters
    ----------
    ref, ref0 : float or None
        The reference values.
    what : str
        Named in the error.
    """
    if ref is None and ref0 is None:
        return None
    r = 1.0 if ref is None else finite_number(ref, f"{what}: ref")
    r0 = 0.0 if ref0 is None else finite_number(ref0, f"{what}: ref0")
    if not r > 0:
        raise ProblemDefinitionError(f"{what}: ref must be positive, got {r:g}")
    return r0, r


def objective_ref(ref: float | None) -> float | None:
    """A checked objective reference (finite, positive) or None.

    Parameters
    ----------
    ref : float or None
        The objective's typical magnitude.
    """
    return constraint_ref(ref, "minimize")


def constraint_ref(ref: float | None, what: str) -> float | None:
    """A checked constraint reference (finite, positive) or None.

    Parameters
    ----------
    ref : float or None
        The constraint's typical size.
    what : str
        Named in the error.
    """
    if ref is None:
        return None
    r = finite_number(ref, f"{what}: ref")
    if not r > 0:
        raise ProblemDefinitionError(f"{what}: ref must be positive, got {r:g}")
    return r


class OptimalControlProblem:
    """States, controls, parameters, dynamics, constraints, cost and times (one phase).

    Symbols are CasADi ``SX`` scalars. In terminal constraints and the Mayer
    cost, state and control symbols stand for their final values and ``T`` for
    the final time; in initial constraints, for the initial values; in path
    constraints and the Lagrange integrand, for the values along the trajectory.

    Parameters
    ----------
    name : str
        Used in solver names and messages.
    shared : Shared, optional
        Parameters and decision variables shared with other phases (set by
        :meth:`ocp.MultiPhaseProblem.phase`).
    """

    def __init__(self, name: str = "ocp", *, shared: Shared | None = None) -> None:
        self.name = name
        self._shared = shared if shared is not None else Shared()
        self.state_names: list[str] = []
        self.control_names: list[str] = []
        self._x: list[ca.SX] = []
        self._u: list[ca.SX] = []
        self._x0: list[ca.SX] = []
        self._xT: list[ca.SX] = []
        self._u0: list[ca.SX] = []
        self._uT: list[ca.SX] = []
        # stacked symbol vectors, by key, with the declaration counts they were made at
        # (each SX that CasADi's Python layer returns costs ~30 us; a build reads them often)
        self._stacks: dict[str, tuple[tuple[int, ...], ca.SX]] = {}
        self._end_values: dict[tuple[str, int], tuple[Any, ca.SX]] = {}  # see _at_end
        self._rhs: dict[str, ca.SX] = {}
        # as declared (state/bound_state, control/bound_control); the attributes the rest of
        # ocp reads are their views (ocp.definition.normal_form), set by _normalise
        self.declared_state_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.declared_control_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.state_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.control_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.control_limits: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.structure_path: list[Constraint] = []
        self.bound_names: dict[str, str] = {}
        self.path_written: list[Constraint] = []
        self.state_guess: dict[str, Any] = {}
        self.control_guess: dict[str, Any] = {}
        self.state_ref: dict[str, tuple[float, float] | None] = {}
        self.control_ref: dict[str, tuple[float, float] | None] = {}
        self.path: list[Constraint] = []  # the transcription's rows (see path_written)
        self.initial: list[Constraint] = []
        self.terminal: list[Constraint] = []
        self.boundary: list[Constraint] = []
        self.mayer: ca.SX = ca.SX(0)
        self.lagrange: ca.SX = ca.SX(0)
        self.boundary_cost: ca.SX = ca.SX(0)
        self.integrals: list[tuple[ca.SX, ca.SX]] = []  # (symbol, integrand)
        self.t = ca.SX.sym("t")
        self.t0 = ca.SX.sym("t0")
        self.T = ca.SX.sym("T")
        self.time_free = False
        self.T_bounds: tuple[float, float] = (1.0, 1.0)
        self.T_guess = 1.0
        self._T_set = False  # the default final time 1 gives way to a later initial time
        self.t0_mode = "default"  # "default" (0, or linked to the previous phase), "fixed", "free"
        self.t0_bounds: tuple[float, float] = (0.0, 0.0)
        self.t0_guess = 0.0
        self.duration: tuple[float, float] | None = None
        self.duration_guess: float | None = None

    # ----------------------------------------------------------- declarations
    def state(self, name: str, lower: Bound | None = -INF,
              upper: Bound | None = INF,
              guess: Any = None, *, ref: float | None = None,
              ref0: float | None = None) -> ca.SX:
        """Declare a state; returns its symbol.

        Parameters
        ----------
        name : str
            Unique within the phase (phases may share state names; links use them).
        lower, upper : float, parameter expression or None
            Bounds on the state along the whole trajectory (None: unbounded). A path
            constraint on this state alone is the same bound for structure detection,
            refinement and the certificate (:mod:`ocp.definition.normal_form`).
        guess : float, parameter expression or (start, end) pair, optional
            Initial guess (a pair is interpolated linearly in time). Default:
            the fixed initial/final values where the constraints fix them, else
            the midpoint of finite bounds, else 0 clipped into the bounds.
        ref, ref0 : float, optional
            Scaling, as dymos' ``ref``/``ref0``: the NLP works with
            ``(x - ref0) / ref`` (defect rows are divided by ``ref`` too);
            the solution is reported in the user's units. Default: automatic
            (see :mod:`ocp.definition.scaling`).
        """
        self._check_new(name, phase=True)
        self._checked_bounds(lower, upper, f"state {name!r}")  # before anything is declared
        sref = scale_ref(ref, ref0, f"state {name!r}")
        s = ca.SX.sym(name)
        self.state_names.append(name)
        self._x.append(s)
        self._x0.append(ca.SX.sym(f"{name}(t0)"))
        self._xT.append(ca.SX.sym(f"{name}(tf)"))
        self.bound_state(name, lower, upper)
        self.state_guess[name] = _guess_value(self._shared, guess, f"state {name!r} guess")
        self.state_ref[name] = sref
        return s

    def control(self, name: str, lower: Bound | None = -INF,
                upper: Bound | None = INF,
                guess: Any = None, *, ref: float | None = None,
                ref0: float | None = None) -> ca.SX:
        """Declare a control with optional bounds (numbers or parameter expressions).

        Parameters
        ----------
        name : str
            Unique within the phase.
        lower, upper : float, parameter expression or None
            Control bounds. They may also involve decision variables (``-peak <= u <=
            peak`` with ``peak = p.variable("peak")``: the control set moves with the
            variable; the transcription imposes such a limit as the row ``u - peak <=
            0``, structure detection and the certificate read the control set at the
            variable's value). A path constraint on this control alone is the same bound
            for structure detection (:mod:`ocp.definition.normal_form`).
        guess : float or parameter expression, optional
            Initial guess (default: midpoint of finite bounds, else 0 clipped).
        ref, ref0 : float, optional
            Scaling: the NLP works with ``(u - ref0) / ref`` (see :meth:`state`).
        """
        self._check_new(name, phase=True)
        # before anything is declared
        self._checked_bounds(lower, upper, f"control {name!r}", variables=True)
        sref = scale_ref(ref, ref0, f"control {name!r}")
        s = ca.SX.sym(name)
        self.control_names.append(name)
        self._u.append(s)
        self._u0.append(ca.SX.sym(f"{name}(t0)"))
        self._uT.append(ca.SX.sym(f"{name}(tf)"))
        self.bound_control(name, lower, upper)
        self.control_guess[name] = _guess_value(self._shared, guess, f"control {name!r} guess")
        self.control_ref[name] = sref
        return s

    def parameter(self, name: str) -> ca.SX:
        """Declare a parameter, set at solve time (shared by all phases).

        Parameters
        ----------
        name : str
            Unique among all names of the problem.
        """
        self._check_new(name, phase=False)
        s = ca.SX.sym(name)
        self._shared.param_names.append(name)
        self._shared.params.append(s)
        return s

    def variable(self, name: str, lower: Bound | None = -INF,
                 upper: Bound | None = INF,
                 guess: Bound | None = None, *, ref: float | None = None,
                 ref0: float | None = None) -> ca.SX:
        """Declare a decision parameter: a constant optimised with the trajectory.

        Parameters
        ----------
        name : str
            Unique among parameters and variables (shared by all phases).
        lower, upper : float, parameter expression or None
            Bounds (None: unbounded).
        guess : float or parameter expression, optional
            Initial guess (default: midpoint of finite bounds, else 0 clipped).
        ref, ref0 : float, optional
            Scaling: the NLP works with ``(v - ref0) / ref`` (see :meth:`state`).
        """
        self._check_new(name, phase=False)
        sh = self._shared
        what = f"variable {name!r}"
        lo, hi = self._checked_bounds(lower, upper, what)
        sref = scale_ref(ref, ref0, what)
        s = ca.SX.sym(name)
        sh.var_names.append(name)
        sh.vars.append(s)
        sh.var_bounds[name] = (lo, hi)
        sh.var_guess[name] = None if guess is None else sh.bound(guess, f"{what} guess")
        sh.var_ref[name] = sref
        return s

    def bound_control(self, name: str, lower: Bound | None = -INF,
                      upper: Bound | None = INF) -> None:
        """Set or change a control's bounds.

        Parameters
        ----------
        name : str
            A declared control.
        lower, upper : float, parameter or decision-variable expression, or None
            The bounds (``lower <= upper`` where both are numbers).
        """
        if name not in self.control_names:
            raise ProblemDefinitionError(f"unknown control {name!r}")
        self.declared_control_bounds[name] = self._checked_bounds(
            lower, upper, f"control {name!r}", variables=True)
        self._normalise()

    def bound_state(self, name: str, lower: Bound | None = -INF,
                    upper: Bound | None = INF) -> None:
        """Set or change a state's bounds (imposed along the whole trajectory).

        Parameters
        ----------
        name : str
            A declared state.
        lower, upper : float, parameter expression or None
            The bounds (``lower <= upper`` where both are numbers).
        """
        if name not in self.state_names:
            raise ProblemDefinitionError(f"unknown state {name!r}")
        self.declared_state_bounds[name] = self._checked_bounds(lower, upper, f"state {name!r}")
        self._normalise()

    def _checked_bounds(self, lower: Bound | None, upper: Bound | None,
                        what: str, variables: bool = False) -> tuple[ca.SX, ca.SX]:
        # None is Python's "no value": no bound on that side (as scipy's Bounds reads it)
        lower = -INF if lower is None else lower
        upper = INF if upper is None else upper
        if variables:  # a control's limits may move with decision variables (u <= peak)
            lo, hi = (self._shared.limit(b, f"{what} {s} bound")
                      for b, s in ((lower, "lower"), (upper, "upper")))
        else:
            lo = self._shared.bound(lower, f"{what} lower bound")
            hi = self._shared.bound(upper, f"{what} upper bound")
        check_bounds(lo, hi, what)
        return lo, hi

    def _normalise(self) -> None:
        """Bounds and path constraints in their one form (:mod:`ocp.definition.normal_form`)."""
        nf = normal_form(self.declared_state_bounds, self.declared_control_bounds,
                         self.path_written, self.x, self.state_names, self.u,
                         self.control_names, self._shared.v,
                         ca.vertcat(self.t, self.t0, self.T))
        self.state_bounds, self.control_bounds = nf.state_bounds, nf.control_bounds
        self.control_limits, self.path = nf.control_limits, nf.path
        self.structure_path, self.bound_names = nf.structure_path, nf.bound_names

    def _check_new(self, name: str, phase: bool) -> None:
        if not isinstance(name, str) or not name:
            raise ProblemDefinitionError(f"name must be a non-empty string, got {name!r}")
        here = name in self.state_names or name in self.control_names
        if here or self._shared.taken(name) or (not phase and name in self._shared.phase_names):
            raise ProblemDefinitionError(f"name {name!r} is already used")
        if phase:
            self._shared.phase_names.add(name)

    # --------------------------------------------------------------- dynamics
    def set_dynamics(self, rhs: Any) -> None:
        """Dynamics ``x' = rhs``.

        Parameters
        ----------
        rhs : dict, list, SX or casadi.Function
            A dict state name -> expression, a list or SX vector in state
            order, or a ``casadi.Function`` taking (x, u, p) and returning x'.
            Expressions may use the states, controls, parameters, variables,
            ``t``, ``t0`` and ``T``.
        """
        if isinstance(rhs, ca.Function):
            rhs = rhs(self.x, self.u, self.p)
        if isinstance(rhs, Mapping):
            unknown = sorted(set(rhs) - set(self.state_names))
            if unknown:
                raise ProblemDefinitionError(f"set_dynamics: unknown state(s) {unknown}; "
                                             f"states are {self.state_names}")
            missing = set(self.state_names) - set(rhs)
            if missing:
                raise ProblemDefinitionError(f"no dynamics for state(s) {sorted(missing)}")
            exprs = {k: to_sx(rhs[k], f"dynamics of {k!r}") for k in self.state_names}
        else:
            vec = (ca.vertcat(*[to_sx(r, "dynamics") for r in rhs])
                   if isinstance(rhs, list | tuple) else to_sx(rhs, "dynamics"))
            if vec.numel() != self.nx:
                raise ProblemDefinitionError(
                    f"dynamics has {vec.numel()} rows for {self.nx} states")
            exprs = {k: ca.SX(vec[i]) for i, k in enumerate(self.state_names)}
        for k, e in exprs.items():
            if e.numel() != 1:
                raise ProblemDefinitionError(f"dynamics of {k!r} must be a scalar")
            require_only(e, self.running_symbols(), f"dynamics of {k!r}",
                         "use p.t for time; end-point values belong in boundary terms")
        self._rhs = exprs

    # ------------------------------------------------------------ constraints
    def _constraint(self, store: list[Constraint], expr: Any, lower: Bound,
                    upper: Bound | None, name: str | None, kind: str,
                    ref: float | None = None) -> Constraint:
        if upper is None:
            upper = lower  # one value: an equality
        e = to_sx(expr, f"{kind} constraint")
        label = name or f"{kind}{len(store)}"
        what = f"{kind} constraint {label!r}"
        lo, hi = (self._shared.bound(b, f"{what} {s} bound")
                  for b, s in ((lower, "lower"), (upper, "upper")))
        if lo.numel() not in (1, e.numel()) or hi.numel() not in (1, e.numel()):
            raise ProblemDefinitionError(f"{what}: bounds do not match {e.numel()} rows")
        lo = ca.repmat(lo, e.numel() // lo.numel(), 1)
        hi = ca.repmat(hi, e.numel() // hi.numel(), 1)
        for i in range(e.numel()):
            check_bounds(lo[i], hi[i], what)
        if kind == "path":
            require_only(e, self.running_symbols(), what,
                         "a path constraint is an expression of x, u, t, parameters")
        else:
            require_only(self._to_boundary(e, kind), self.boundary_symbols(), what)
        c = Constraint(e, lo, hi, label, constraint_ref(ref, what))
        store.append(c)
        return c

    def path_constraint(self, expr: Any, lower: Bound = -INF, upper: Bound = INF,
                        name: str | None = None, *,
                        ref: float | None = None) -> Constraint:
        """``lower <= expr(x, u, t, p) <= upper`` along the trajectory.

        Imposed at the shooting nodes (multiple shooting; also at the
        integrator's inner steps with ``inner_constraints=True``) or at the
        collocation points, and checked on a fine grid after every solve.

        A constraint on one state or one control alone (``v <= 0.8``, ``u - peak <=
        0``) is that variable's bound for structure detection, refinement and the
        certificate (:mod:`ocp.definition.normal_form`): the arcs, the refined
        solution and the verdict do not depend on how the bound was written. The
        transcription imposes it as written (rows). ``path_written`` keeps every path
        constraint as given; ``path`` holds the rows a transcription imposes.

        Parameters
        ----------
        expr : SX
            Expression of the states, controls, ``t``, ``t0``, ``T``, parameters and
            variables (a vector gives one constraint per row).
        lower, upper : float or parameter expression
            Bounds (``-inf``/``inf`` for none).
        name : str, optional
            Used in messages and in ``sol.violations``.
        ref : float, optional
            Typical size of ``expr``: its NLP rows are divided by it (default:
            automatic, see :mod:`ocp.definition.scaling`).
        """
        c = self._constraint(self.path_written, expr, lower, upper, name, "path", ref)
        try:
            self._normalise()
        except ProblemDefinitionError:
            self.path_written.pop()  # refused (it was the last added): the problem as it was
            self._normalise()
            raise
        return c

    def initial_constraint(self, expr: Any, lower: Bound, upper: Bound | None = None,
                           name: str | None = None, *,
                           ref: float | None = None) -> Constraint:
        """``lower <= expr <= upper`` at ``t0`` (equality if ``upper`` is omitted).

        States and controls in ``expr`` stand for their values at ``t0``.

        Parameters
        ----------
        expr : SX
            Expression of the states and controls (at ``t0``), end-point symbols,
            times, parameters and variables.
        lower : float or parameter expression
            Lower bound, or the value of an equality.
        upper : float or parameter expression, optional
            Upper bound.
        name : str, optional
            Used in messages.
        ref : float, optional
            Typical size of ``expr``: its NLP rows are divided by it (default:
            automatic, see :mod:`ocp.definition.scaling`).
        """
        return self._constraint(self.initial, expr, lower, upper, name, "initial", ref)

    def terminal_constraint(self, expr: Any, lower: Bound, upper: Bound | None = None,
                            name: str | None = None, *,
                            ref: float | None = None) -> Constraint:
        """``lower <= expr <= upper`` at ``T`` (equality if ``upper`` is omitted).

        States and controls in ``expr`` stand for their values at ``T``.

        Parameters
        ----------
        expr : SX
            Expression of the states and controls (at ``T``), end-point symbols,
            times, parameters and variables.
        lower : float or parameter expression
            Lower bound, or the value of an equality.
        upper : float or parameter expression, optional
            Upper bound.
        name : str, optional
            Used in messages.
        ref : float, optional
            Typical size of ``expr``: its NLP rows are divided by it (default:
            automatic, see :mod:`ocp.definition.scaling`).
        """
        return self._constraint(self.terminal, expr, lower, upper, name, "terminal", ref)

    def boundary_constraint(self, expr: Any, lower: Bound, upper: Bound | None = None,
                            name: str | None = None, *,
                            ref: float | None = None) -> Constraint:
        """``lower <= expr <= upper`` on end-point values (equality if ``upper`` is omitted).

        ``expr`` is built from :meth:`at_t0`, :meth:`at_tf`, :meth:`integral`,
        ``t0``, ``T``, parameters and variables; a bare state is ambiguous here.

        Parameters
        ----------
        expr : SX
            Expression of end-point symbols, times, parameters and variables.
        lower : float or parameter expression
            Lower bound, or the value of an equality.
        upper : float or parameter expression, optional
            Upper bound.
        name : str, optional
            Used in messages.
        ref : float, optional
            Typical size of ``expr``: its NLP rows are divided by it (default:
            automatic, see :mod:`ocp.definition.scaling`).
        """
        e = to_sx(expr, "boundary constraint")
        if ca.depends_on(e, ca.vertcat(self.x, self.u, self.t)):
            raise ProblemDefinitionError(
                "boundary_constraint: a bare state, control or t is ambiguous here; wrap it "
                "in p.at_t0(...) or p.at_tf(...)")
        return self._constraint(self.boundary, e, lower, upper, name, "boundary", ref)

    def integral_constraint(self, integrand: Any, lower: Bound, upper: Bound | None = None,
                            name: str | None = None, *,
                            ref: float | None = None) -> Constraint:
        """``lower <= int_t0^T integrand dt <= upper`` (an isoperimetric constraint).

        Parameters
        ----------
        integrand : SX
            Expression of the states, controls, ``t`` and parameters.
        lower : float or parameter expression
            Lower bound, or the value of an equality.
        upper : float or parameter expression, optional
            Upper bound.
        name : str, optional
            Used in messages.
        ref : float, optional
            Typical size of ``expr``: its NLP rows are divided by it (default:
            automatic, see :mod:`ocp.definition.scaling`).
        """
        return self.boundary_constraint(self.integral(integrand), lower, upper,
                                        name or f"integral{len(self.integrals)}", ref=ref)

    # ------------------------------------------------------- end-point symbols
    def at_t0(self, expr: Any) -> ca.SX:
        """``expr`` evaluated at ``t0`` (states, controls and t at the initial time).

        Parameters
        ----------
        expr : SX
            Expression of the states, controls and ``t``.
        """
        return self._at_end(expr, "at_t0", [*self._x0, *self._u0, self.t0])

    def at_tf(self, expr: Any) -> ca.SX:
        """``expr`` evaluated at ``T`` (states, controls and t at the final time).

        Parameters
        ----------
        expr : SX
            Expression of the states, controls and ``t``.
        """
        return self._at_end(expr, "at_tf", [*self._xT, *self._uT, self.T])

    def _at_end(self, expr: Any, key: str, ends: list[ca.SX]) -> ca.SX:
        """``expr`` with the running symbols replaced by ``ends``; kept by the identity
        of ``expr`` (a build substitutes each boundary constraint several times: guesses,
        scaling sizes, NLP rows). Symbols are only appended, and an expression cannot
        hold one declared after it, so a kept result never goes stale."""
        hit = self._end_values.get((key, id(expr)))
        if hit is not None and hit[0] is expr:
            return hit[1]
        e = to_sx(expr, f"{key}()")
        out = ca.substitute(e, self._stacked("running", [*self._x, *self._u, self.t]),
                            self._stacked(key, ends))
        self._end_values[(key, id(expr))] = (expr, out)  # expr kept: its id stays unique
        return out

    def integral(self, integrand: Any) -> ca.SX:
        """A symbol standing for ``int_t0^T integrand dt`` (use in boundary terms).

        Parameters
        ----------
        integrand : SX
            Scalar expression of the states, controls, ``t`` and parameters.
        """
        e = to_sx(integrand, "integral()")
        if e.numel() != 1:
            raise ProblemDefinitionError("integral(): the integrand must be a scalar")
        require_only(e, self.running_symbols(), "integral() integrand")
        q = ca.SX.sym(f"integral{len(self.integrals)}")
        self.integrals.append((q, e))
        return q

    def _to_boundary(self, expr: ca.SX, kind: str) -> ca.SX:
        if kind == "initial":
            return self.at_t0(expr)
        if kind in ("terminal", "mayer"):
            return self.at_tf(expr)
        return expr

    # ------------------------------------------------------------------- cost
    def minimize_terminal(self, expr: Any, *, ref: float | None = None) -> None:
        """Add a Mayer term ``phi(x(T), u(T), T, p)`` (bare symbols mean values at ``T``).

        Parameters
        ----------
        expr : SX
            Expression of the states and controls (at ``T``), times, parameters
            and variables.
        ref : float, optional
            Typical magnitude of the whole objective: the NLP minimises
            ``J / ref`` (reported unscaled). See :meth:`minimize`.
        """
        self._set_objective_ref(ref)
        e = to_sx(expr, "minimize_terminal")
        require_only(self.at_tf(e), self.boundary_symbols(), "minimize_terminal term")
        self.mayer = self.mayer + e

    def minimize_integral(self, expr: Any, *, ref: float | None = None) -> None:
        """Add a Lagrange term ``int_t0^T L(x, u, t, p) dt``.

        Parameters
        ----------
        expr : SX
            The integrand ``L``.
        ref : float, optional
            Typical magnitude of the whole objective (see :meth:`minimize`).
        """
        self._set_objective_ref(ref)
        e = to_sx(expr, "minimize_integral")
        require_only(e, self.running_symbols(), "minimize_integral integrand")
        self.lagrange = self.lagrange + e

    def minimize(self, expr: Any, *, ref: float | None = None) -> None:
        """Add an end-point cost built from :meth:`at_t0`, :meth:`at_tf`, :meth:`integral`,
        ``t0``, ``T``, parameters and variables (e.g. ``p.at_t0(x)**2``).

        Parameters
        ----------
        expr : SX
            Expression of end-point symbols, times, parameters and variables.
        ref : float, optional
            Typical magnitude of the whole objective (one value per problem,
            the last given wins): the NLP minimises ``J / ref``, so Ipopt's
            tolerances become relative to it; ``sol.objective`` and the
            multipliers stay in the user's units. Default: automatic (see
            :mod:`ocp.definition.scaling`).
        """
        self._set_objective_ref(ref)
        e = to_sx(expr, "minimize")
        if ca.depends_on(e, ca.vertcat(self.x, self.u, self.t)):
            raise ProblemDefinitionError(
                "minimize: a bare state, control or t is ambiguous here; wrap it in "
                "p.at_t0(...) or p.at_tf(...), or use minimize_terminal/minimize_integral")
        require_only(e, self.boundary_symbols(), "minimize term")
        self.boundary_cost = self.boundary_cost + e

    def _set_objective_ref(self, ref: float | None) -> None:
        r = objective_ref(ref)
        if r is not None:
            self._shared.objective_ref = r

    # ------------------------------------------------------------------ times
    def fixed_final_time(self, T: float) -> None:
        """Fix the final time (it must exceed a fixed initial time).

        Parameters
        ----------
        T : float
            The final time.
        """
        Tv = finite_number(T, "fixed_final_time(T)")
        if self.t0_mode != "free" and Tv <= self.t0_bounds[0]:
            raise ProblemDefinitionError(
                f"fixed_final_time(T={Tv:g}): T must exceed the initial time "
                f"{self.t0_bounds[0]:g} (set the initial time first if it is not 0)")
        self._T_set = True
        self.time_free = False
        self.T_bounds = (Tv, Tv)
        self.T_guess = Tv
        self.duration = None

    def free_final_time(self, lower: float = 1e-3, upper: float = 1e3,
                        guess: float | None = None) -> None:
        """Free final time ``lower <= T <= upper`` (absolute times).

        Parameters
        ----------
        lower, upper : float
            Bounds on ``T``.
        guess : float, optional
            Initial guess (default: 1 clipped into the bounds).
        """
        lo = finite_number(lower, "free_final_time(lower)")
        hi = float(upper)
        if not lo < hi:
            raise ProblemDefinitionError(f"free_final_time: need lower < upper, got "
                                         f"{lo:g}, {hi:g}")
        if self.t0_mode != "free" and lo < self.t0_bounds[0]:
            raise ProblemDefinitionError(
                f"free_final_time(lower={lo:g}): below the initial time {self.t0_bounds[0]:g}")
        g = min(max(1.0, lo), hi) if guess is None else finite_number(guess, "guess")
        if not lo <= g <= hi:
            raise ProblemDefinitionError(f"free_final_time(guess={g:g}) outside "
                                         f"[{lo:g}, {hi:g}]")
        self._T_set = True
        self.time_free = True
        self.T_bounds = (lo, hi)
        self.T_guess = g
        self.duration = None

    def fixed_initial_time(self, t0: float) -> None:
        """Fix the initial time (default 0, or the previous phase's end when linked).

        Parameters
        ----------
        t0 : float
            The initial time.
        """
        v = finite_number(t0, "fixed_initial_time(t0)")
        if self._T_set and not self.time_free and v >= self.T_bounds[0]:
            raise ProblemDefinitionError(f"fixed_initial_time(t0={v:g}): not before the fixed "
                                         f"final time {self.T_bounds[0]:g}")
        self.t0_mode = "fixed"
        self.t0_bounds = (v, v)
        self.t0_guess = v

    def free_initial_time(self, lower: float = -INF, upper: float = INF,
                          guess: float | None = None) -> None:
        """Free initial time ``lower <= t0 <= upper``.

        Parameters
        ----------
        lower, upper : float
            Bounds on ``t0``.
        guess : float, optional
            Initial guess (default: 0 clipped into the bounds).
        """
        lo, hi = float(lower), float(upper)
        if not lo <= hi or np.isnan(lo) or np.isnan(hi):
            raise ProblemDefinitionError(f"free_initial_time: need lower <= upper, got "
                                         f"{lo:g}, {hi:g}")
        g = float(np.clip(0.0, lo, hi)) if guess is None else finite_number(guess, "guess")
        if not lo <= g <= hi:
            raise ProblemDefinitionError(f"free_initial_time(guess={g:g}) outside bounds")
        self.t0_mode = "free"
        self.t0_bounds = (lo, hi)
        self.t0_guess = g

    def free_duration(self, lower: float = 0.0, upper: float = INF,
                      guess: float | None = None) -> None:
        """Free final time given by the duration ``lower <= T - t0 <= upper``.

        The natural choice for a phase whose start is linked to the end of the
        previous one.

        Parameters
        ----------
        lower, upper : float
            Bounds on ``T - t0``.
        guess : float, optional
            Initial guess of the duration (default: 1 clipped into the bounds).
        """
        lo = finite_number(lower, "free_duration(lower)")
        hi = float(upper)
        if lo < 0 or not lo < hi:
            raise ProblemDefinitionError(f"free_duration: need 0 <= lower < upper, got "
                                         f"{lo:g}, {hi:g}")
        g = (min(max(1.0, lo), hi) if guess is None
             else finite_number(guess, "free_duration(guess)"))
        if not lo <= g <= hi:
            raise ProblemDefinitionError(f"free_duration(guess={g:g}) outside bounds")
        self._T_set = True
        self.time_free = True
        self.T_bounds = (-INF, INF)
        self.duration = (lo, hi)
        self.duration_guess = g

    def fixed_duration(self, duration: float) -> None:
        """Fix ``T - t0`` (with a free or linked initial time, T moves with it).

        Parameters
        ----------
        duration : float
            ``T - t0``.
        """
        d = finite_number(duration, "fixed_duration(duration)")
        if d <= 0:
            raise ProblemDefinitionError(f"fixed_duration({d:g}): must be positive")
        self._T_set = True
        self.time_free = True
        self.T_bounds = (-INF, INF)
        self.duration = (d, d)
        self.duration_guess = d

    # ---------------------------------------------------------------- access
    def _stacked(self, key: str, syms: list[ca.SX]) -> ca.SX:
        """``vertcat(*syms)``, made again only after a state or control is declared
        (symbols are only ever appended, so the counts tell whether it changed)."""
        counts = (len(self._x), len(self._u))
        hit = self._stacks.get(key)
        if hit is None or hit[0] != counts:
            hit = (counts, ca.vertcat(*syms) if syms else ca.SX(0, 1))
            self._stacks[key] = hit
        return hit[1]

    @property
    def x(self) -> ca.SX:
        """The states, stacked."""
        return self._stacked("x", self._x)

    @property
    def u(self) -> ca.SX:
        """The controls, stacked."""
        return self._stacked("u", self._u)

    @property
    def p(self) -> ca.SX:
        """The parameters (shared by all phases), stacked."""
        return self._shared.p

    @property
    def v(self) -> ca.SX:
        """Decision variables (see :meth:`variable`)."""
        return self._shared.v

    @property
    def shared(self) -> Shared:
        """Parameters and decision variables, shared by all phases (read it; declare through
        :meth:`parameter` and :meth:`variable`)."""
        return self._shared

    @property
    def x0(self) -> ca.SX:
        """The states at ``t0`` (end-point symbols), stacked."""
        return self._stacked("x0", self._x0)

    @property
    def xT(self) -> ca.SX:
        """The states at ``T`` (end-point symbols), stacked."""
        return self._stacked("xT", self._xT)

    @property
    def u0(self) -> ca.SX:
        """The controls at ``t0`` (end-point symbols), stacked."""
        return self._stacked("u0", self._u0)

    @property
    def uT(self) -> ca.SX:
        """The controls at ``T`` (end-point symbols), stacked."""
        return self._stacked("uT", self._uT)

    @property
    def q(self) -> ca.SX:
        """Symbols of the integrals declared by :meth:`integral`."""
        return ca.vertcat(*[s for s, _ in self.integrals]) if self.integrals else ca.SX(0, 1)

    def variable_bounds(self, name: str) -> tuple[ca.SX, ca.SX]:
        """The bounds of decision variable ``name`` (parameter expressions).

        Parameters
        ----------
        name : str
            A declared decision variable.
        """
        if name not in self._shared.var_bounds:
            raise ProblemDefinitionError(f"unknown variable {name!r}")
        return self._shared.var_bounds[name]

    @property
    def param_names(self) -> list[str]:
        """Names of the parameters (shared by all phases)."""
        return self._shared.param_names

    @property
    def var_names(self) -> list[str]:
        """Names of the decision variables (shared by all phases)."""
        return self._shared.var_names

    @property
    def nx(self) -> int:
        """Number of states."""
        return len(self._x)

    @property
    def nu(self) -> int:
        """Number of controls."""
        return len(self._u)

    @property
    def np(self) -> int:
        """Number of parameters."""
        return len(self._shared.params)

    @property
    def nv(self) -> int:
        """Number of decision variables."""
        return len(self._shared.vars)

    @property
    def rhs(self) -> ca.SX:
        """The dynamics ``x'``, in state order."""
        if not self._rhs:
            raise ProblemDefinitionError("set_dynamics() was not called")
        return ca.vertcat(*[self._rhs[k] for k in self.state_names])

    def running_symbols(self) -> list[ca.SX]:
        """What dynamics, path constraints and integrands may depend on."""
        return [*self._x, *self._u, self.t, *self._shared.params, *self._shared.vars,
                self.t0, self.T]

    def boundary_symbols(self) -> list[ca.SX]:
        """What boundary constraints and end-point costs may depend on."""
        return [*self._x0, *self._u0, *self._xT, *self._uT, self.t0, self.T,
                *[s for s, _ in self.integrals], *self._shared.params, *self._shared.vars]

    def is_autonomous(self) -> bool:
        """True if dynamics and running cost use neither t, t0, T nor decision variables."""
        other = ca.vertcat(self.t, self.t0, self.T, self.v)
        return not ca.depends_on(ca.vertcat(self.rhs, self.lagrange), other)

    def _legacy(self, what: str) -> None:
        if not self.is_autonomous():
            raise ProblemDefinitionError(
                f"{what}(x, u, p) cannot represent dynamics or costs that depend on t, t0, T "
                "or decision variables; use ocp.definition.compiled.CompiledPhase(problem).ode")

    def dynamics_function(self) -> ca.Function:
        """``f(x, u, p) -> x'`` (autonomous problems without decision variables)."""
        self._legacy("dynamics_function")
        return ca.Function("f", [self.x, self.u, self.p], [self.rhs], ["x", "u", "p"], ["xdot"])

    def lagrange_function(self) -> ca.Function:
        """``L(x, u, p)`` (autonomous problems without decision variables)."""
        self._legacy("lagrange_function")
        return ca.Function("L", [self.x, self.u, self.p], [self.lagrange])

    def has_running_cost(self) -> bool:
        """True if a Lagrange term was added (and is not identically zero)."""
        return not (isinstance(self.lagrange, ca.SX) and self.lagrange.is_zero())

    def is_control_affine(self) -> bool:
        """True if ``x' = f(x, p) + g(x, p) u`` (needed by the PMP checks)."""
        return not ca.depends_on(ca.jacobian(self.rhs, self.u), self.u)

    def is_affine_in_state(self) -> bool:
        """True if, for fixed u, the dynamics are affine in x (exact arcs by expm)."""
        return not ca.depends_on(ca.jacobian(self.rhs, self.x), self.x)

    def path_stack(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        """All path constraints stacked: ``(expr, lower, upper)`` column vectors."""
        return _stack(self.path)

    def initial_stack(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        """All initial constraints stacked (bare symbols = values at ``t0``)."""
        return _stack(self.initial)

    def terminal_stack(self) -> tuple[ca.SX, ca.SX, ca.SX]:
        """All terminal constraints stacked (bare symbols = values at ``T``)."""
        return _stack(self.terminal)

    def param_vector(self, params: Mapping[str, float]) -> ndarray:
        """The parameter values in declaration order, checked.

        Raises
        ------
        ValueError
            Unknown, missing or non-finite parameters, or a value given for a
            decision variable (those are optimised).

        Parameters
        ----------
        params : mapping
            A value for every declared parameter.
        """
        names = self.param_names
        given_vars = sorted(set(params) & set(self.var_names))
        if given_vars:
            raise ValueError(f"{given_vars} are decision variables (optimised), not "
                             "parameters; set their guess with variable(..., guess=)")
        unknown = set(params) - set(names)
        if unknown:
            raise ValueError(f"unknown parameter(s) {sorted(unknown)}")
        missing = [k for k in names if k not in params]
        if missing:
            raise ValueError(f"missing parameter(s) {missing}")
        pv = np.array([float(params[k]) for k in names])
        if not np.all(np.isfinite(pv)):
            raise ValueError("parameters must be finite")
        return pv

    def validate(self) -> None:
        """Check the definition is complete (dynamics set, times consistent)."""
        _ = self.rhs
        if self.nx == 0:
            raise ProblemDefinitionError("the problem has no state")
        if not self.time_free and self.t0_mode != "free" and self.T_bounds[0] <= self.t0_bounds[0]:
            raise ProblemDefinitionError(
                f"the final time {self.T_bounds[0]:g} must exceed the initial time "
                f"{self.t0_bounds[0]:g}: call fixed_final_time or free_final_time")

    def __repr__(self) -> str:
        return (f"OptimalControlProblem({self.name!r}, states={self.state_names}, "
                f"controls={self.control_names}, parameters={self.param_names})")


def _stack(cs: list[Constraint]) -> tuple[ca.SX, ca.SX, ca.SX]:
    if not cs:
        return ca.SX(0, 1), ca.SX(0, 1), ca.SX(0, 1)
    return (ca.vertcat(*[c.expr for c in cs]), ca.vertcat(*[c.lower for c in cs]),
            ca.vertcat(*[c.upper for c in cs]))


def bound_value(b: ca.SX) -> float | None:
    """A constant bound as float (None if it depends on parameters).

    Parameters
    ----------
    b : SX
        A bound.
    """
    return constant(b)
