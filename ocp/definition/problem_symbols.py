"""A phase's symbols (:class:`ProblemSymbols`, the base of
:class:`~ocp.definition.problem.OptimalControlProblem`): states, controls, parameters and
decision variables with their bounds, guesses and scaling references, the dynamics, and the
stacked views and checks the rest of ``ocp`` reads. Constraints, costs and times are declared
on :class:`~ocp.definition.problem.OptimalControlProblem`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np
from numpy import ndarray

from .errors import ProblemDefinitionError
from .normal_form import normal_form
from .references import scale_ref
from .shared import Bound, Shared, guess_value
from .symbols import INF, Constraint, check_bounds, constant, require_only, to_sx

__all__ = ["ProblemSymbols", "bound_value"]


class ProblemSymbols:
    """A phase's symbols, bounds and dynamics (see the module); every attribute of a phase
    is set here, the declarations of constraints, costs and times are the subclass's.

    Parameters
    ----------
    name : str
        Used in solver names and messages.
    shared : Shared, optional
        Parameters and decision variables shared with other phases.
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
        self.state_guess[name] = guess_value(self._shared, guess, f"state {name!r} guess")
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
        self.control_guess[name] = guess_value(self._shared, guess, f"control {name!r} guess")
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
