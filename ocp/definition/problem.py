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

from typing import Any

import casadi as ca
import numpy as np

from .errors import ProblemDefinitionError
from .problem_symbols import ProblemSymbols

# (the "X as X" imports re-export names that were defined here before the module was split)
from .problem_symbols import bound_value as bound_value
from .references import constraint_ref, objective_ref
from .references import scale_ref as scale_ref
from .shared import RESERVED as RESERVED
from .shared import Bound
from .shared import Shared as Shared
from .symbols import (
    INF,
    Constraint,
    check_bounds,
    finite_number,
    require_only,
    to_sx,
)

__all__ = ["INF", "Constraint", "OptimalControlProblem", "ProblemDefinitionError"]


class OptimalControlProblem(ProblemSymbols):
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
        if self.t0_mode == "free" and Tv <= self.t0_bounds[0]:
            raise ProblemDefinitionError(
                f"fixed_final_time(T={Tv:g}): T must exceed the free initial time's lower "
                f"bound {self.t0_bounds[0]:g}")
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
        if self.t0_mode == "free" and hi <= self.t0_bounds[0]:
            raise ProblemDefinitionError(
                f"free_final_time(upper={hi:g}): not after the free initial time's lower "
                f"bound {self.t0_bounds[0]:g}")
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
        if self._T_set and self.time_free and self.duration is None and v >= self.T_bounds[1]:
            raise ProblemDefinitionError(f"fixed_initial_time(t0={v:g}): not before the final "
                                         f"time's upper bound {self.T_bounds[1]:g}")
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
        if self._T_set and self.duration is None and lo >= self.T_bounds[1]:
            # (a final time set first: the reverse order is refused by the final time's setter)
            raise ProblemDefinitionError(
                f"free_initial_time(lower={lo:g}): not before the final time's upper bound "
                f"{self.T_bounds[1]:g}")
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
