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

Constraint bounds may be numbers or expressions of the parameters only; they
are evaluated at solve time, so changing a parameter never rebuilds the NLP.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

INF = float("inf")


class ProblemDefinitionError(ValueError):
    """The problem is incompletely or inconsistently defined."""


@dataclass
class Constraint:
    """``lower <= expr <= upper`` (bounds: numbers or parameter expressions)."""

    expr: ca.SX
    lower: ca.SX
    upper: ca.SX
    name: str


class OptimalControlProblem:
    """States, controls, parameters, dynamics, constraints, cost and final time.

    Symbols are CasADi ``SX`` scalars. In terminal constraints and the Mayer
    cost, state symbols stand for the final state and ``T`` for the final time;
    in initial constraints they stand for the initial state; in path
    constraints and the Lagrange integrand, for the state along the trajectory.
    """

    def __init__(self, name: str = "ocp") -> None:
        self.name = name
        self.state_names: list[str] = []
        self.control_names: list[str] = []
        self.param_names: list[str] = []
        self._x: list[ca.SX] = []
        self._u: list[ca.SX] = []
        self._p: list[ca.SX] = []
        self._rhs: dict[str, ca.SX] = {}
        self.control_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.path: list[Constraint] = []
        self.initial: list[Constraint] = []
        self.terminal: list[Constraint] = []
        self.mayer: ca.SX = ca.SX(0)
        self.lagrange: ca.SX = ca.SX(0)
        self.T = ca.SX.sym("T")
        self.time_free = False
        self.T_bounds: tuple[float, float] = (1.0, 1.0)
        self.T_guess = 1.0

    # ----------------------------------------------------------- declarations
    def state(self, name: str) -> ca.SX:
        """Declare a state; returns its symbol."""
        self._check_new(name)
        s = ca.SX.sym(name)
        self.state_names.append(name)
        self._x.append(s)
        return s

    def control(self, name: str, lower=-INF, upper=INF) -> ca.SX:
        """Declare a control with optional bounds (numbers or parameter expressions)."""
        self._check_new(name)
        s = ca.SX.sym(name)
        self.control_names.append(name)
        self._u.append(s)
        self.control_bounds[name] = (ca.SX(lower), ca.SX(upper))
        return s

    def parameter(self, name: str) -> ca.SX:
        """Declare a parameter, set at solve time."""
        self._check_new(name)
        s = ca.SX.sym(name)
        self.param_names.append(name)
        self._p.append(s)
        return s

    def bound_control(self, name: str, lower=-INF, upper=INF) -> None:
        """Set or change a control's bounds."""
        if name not in self.control_names:
            raise ProblemDefinitionError(f"unknown control {name!r}")
        self.control_bounds[name] = (ca.SX(lower), ca.SX(upper))

    def _check_new(self, name: str) -> None:
        if name in self.state_names + self.control_names + self.param_names + ["T"]:
            raise ProblemDefinitionError(f"name {name!r} is already used")

    # --------------------------------------------------------------- dynamics
    def set_dynamics(self, rhs) -> None:
        """Dynamics ``x' = rhs``.

        Parameters
        ----------
        rhs : dict name -> expression, a list or SX vector in state order, or a
            ``casadi.Function`` taking (x, u, p) and returning x'.
        """
        if isinstance(rhs, ca.Function):
            rhs = rhs(self.x, self.u, self.p)
        if isinstance(rhs, dict):
            missing = set(self.state_names) - set(rhs)
            if missing:
                raise ProblemDefinitionError(f"no dynamics for state(s) {sorted(missing)}")
            self._rhs = {k: ca.SX(rhs[k]) for k in self.state_names}
            return
        rhs = ca.vertcat(*rhs) if isinstance(rhs, list | tuple) else ca.SX(rhs)
        if rhs.numel() != self.nx:
            raise ProblemDefinitionError(f"dynamics has {rhs.numel()} rows for {self.nx} states")
        self._rhs = {k: rhs[i] for i, k in enumerate(self.state_names)}

    # ------------------------------------------------------------ constraints
    def _constraint(self, store, expr, lower, upper, name):
        if upper is None:
            upper = lower  # one value: an equality
        c = Constraint(ca.SX(expr), ca.SX(lower), ca.SX(upper), name or f"c{len(store)}")
        for b in (c.lower, c.upper):
            if ca.depends_on(b, ca.vertcat(*self._x, *self._u)):
                raise ProblemDefinitionError("constraint bounds may depend on parameters only")
        store.append(c)
        return c

    def path_constraint(self, expr, lower=-INF, upper=INF, name: str | None = None):
        """``lower <= expr(x, u, p) <= upper`` at every shooting node."""
        return self._constraint(self.path, expr, lower, upper, name)

    def initial_constraint(self, expr, lower, upper=None, name: str | None = None):
        """``lower <= expr(x(0), p) <= upper`` (equality if ``upper`` is omitted)."""
        return self._constraint(self.initial, expr, lower, upper, name)

    def terminal_constraint(self, expr, lower, upper=None, name: str | None = None):
        """``lower <= expr(x(T), T, p) <= upper`` (equality if ``upper`` is omitted)."""
        return self._constraint(self.terminal, expr, lower, upper, name)

    # --------------------------------------------------------------- cost, T
    def minimize_terminal(self, expr) -> None:
        """Add a Mayer term ``phi(x(T), T, p)``."""
        self.mayer = self.mayer + ca.SX(expr)

    def minimize_integral(self, expr) -> None:
        """Add a Lagrange term ``int_0^T L(x, u, p) dt``."""
        self.lagrange = self.lagrange + ca.SX(expr)

    def fixed_final_time(self, T: float) -> None:
        self.time_free = False
        self.T_bounds = (float(T), float(T))
        self.T_guess = float(T)

    def free_final_time(self, lower: float = 1e-3, upper: float = 1e3,
                        guess: float | None = None) -> None:
        if not 0 <= lower < upper:
            raise ProblemDefinitionError("need 0 <= lower < upper for the final time")
        self.time_free = True
        self.T_bounds = (float(lower), float(upper))
        self.T_guess = float(guess if guess is not None else min(max(1.0, lower), upper))

    # ---------------------------------------------------------------- access
    @property
    def x(self) -> ca.SX:
        return ca.vertcat(*self._x)

    @property
    def u(self) -> ca.SX:
        return ca.vertcat(*self._u)

    @property
    def p(self) -> ca.SX:
        return ca.vertcat(*self._p)

    @property
    def nx(self) -> int:
        return len(self._x)

    @property
    def nu(self) -> int:
        return len(self._u)

    @property
    def np(self) -> int:
        return len(self._p)

    @property
    def rhs(self) -> ca.SX:
        if not self._rhs:
            raise ProblemDefinitionError("set_dynamics() was not called")
        return ca.vertcat(*[self._rhs[k] for k in self.state_names])

    def dynamics_function(self) -> ca.Function:
        """``f(x, u, p) -> x'``."""
        return ca.Function("f", [self.x, self.u, self.p], [self.rhs], ["x", "u", "p"], ["xdot"])

    def lagrange_function(self) -> ca.Function:
        return ca.Function("L", [self.x, self.u, self.p], [self.lagrange])

    def is_control_affine(self) -> bool:
        """True if ``x' = f(x, p) + g(x, p) u`` (needed by the PMP checks)."""
        return not ca.depends_on(ca.jacobian(self.rhs, self.u), self.u)

    def is_affine_in_state(self) -> bool:
        """True if, for fixed u, the dynamics are affine in x (exact arcs by expm)."""
        return not ca.depends_on(ca.jacobian(self.rhs, self.x), self.x)

    def validate(self) -> None:
        _ = self.rhs
        if self.nu == 0:
            raise ProblemDefinitionError("the problem has no control")
