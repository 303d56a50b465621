"""Multi-phase problems: phases in sequence, each with its own states, controls,
dynamics and constraints, joined by linkage constraints, sharing parameters and
decision variables.

Example (a hybrid sequence: a phase with drag, then a free-flight phase)::

    mp = MultiPhaseProblem("two_phase")
    g = mp.parameter("g")
    a, b = mp.phase("drag"), mp.phase("free")
    for ph in (a, b):
        y, v = ph.state("y"), ph.state("v")
        u = ph.control("u", -1, 1)
    a.set_dynamics({"y": a.x[1], "v": a.u[0] - g - 0.1 * a.x[1]})
    b.set_dynamics({"y": b.x[1], "v": b.u[0] - g})
    a.free_final_time(0.1, 10)
    b.free_duration(0.1, 10)
    mp.link(a, b)                     # b starts where and when a ends
    mp.minimize(b.T)

A :class:`ocp.OptimalControlProblem` on its own is a one-phase problem; every
transcription accepts either.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy import ndarray

from .errors import ProblemDefinitionError
from .problem import (
    INF,
    Bound,
    OptimalControlProblem,
    Shared,
    constraint_ref,
    objective_ref,
)
from .symbols import Constraint, check_bounds, require_only, to_sx

PhaseRef = OptimalControlProblem | int


@dataclass
class PhaseTimes:
    """How a phase's initial and final times enter the NLP (resolved over the sequence).

    Attributes
    ----------
    t0_free, T_free : bool
        The initial / final time is a decision.
    t0_bounds, T_bounds : (float, float)
        Their bounds.
    t0_guess, T_guess : float
        Their guesses.
    span : (float, float) or None
        Bounds on ``T - t0`` imposed as a constraint.
    """

    t0_free: bool
    t0_bounds: tuple[float, float]
    t0_guess: float
    T_free: bool
    T_bounds: tuple[float, float]
    T_guess: float
    span: tuple[float, float] | None  # bounds on T - t0 imposed as a constraint


class MultiPhaseProblem:
    """A sequence of phases with linkage constraints and a common objective.

    Parameters
    ----------
    name : str
        Used in solver names.
    """

    def __init__(self, name: str = "multiphase") -> None:
        self.name = name
        self._shared = Shared()
        self._anchor = OptimalControlProblem(name, shared=self._shared)
        self.phases: list[OptimalControlProblem] = []
        self.links: list[Constraint] = []
        self.time_links: list[tuple[int, int]] = []
        self.boundary_cost: ca.SX = ca.SX(0)

    @classmethod
    def single(cls, problem: OptimalControlProblem) -> MultiPhaseProblem:
        """A one-phase view of ``problem`` (shares its parameters and variables).

        Parameters
        ----------
        problem : OptimalControlProblem
            The only phase.
        """
        mp = cls(problem.name)
        mp._shared = problem.shared
        mp._anchor = problem
        mp.phases = [problem]
        return mp

    # ------------------------------------------------------------ declarations
    def phase(self, name: str | None = None) -> OptimalControlProblem:
        """Add a phase (after the existing ones) and return it for definition.

        Parameters
        ----------
        name : str, optional
            Used in messages and solver names (default ``phase<i>``).
        """
        ph = OptimalControlProblem(name or f"phase{len(self.phases)}", shared=self._shared)
        self.phases.append(ph)
        return ph

    def parameter(self, name: str) -> ca.SX:
        """A parameter set at solve time, shared by all phases.

        Parameters
        ----------
        name : str
            Unique among all names of the problem.
        """
        return self._anchor.parameter(name)

    def variable(self, name: str, lower: Bound = -INF, upper: Bound = INF,
                 guess: Bound | None = None, *, ref: float | None = None,
                 ref0: float | None = None) -> ca.SX:
        """A decision parameter shared by all phases (see
        :meth:`OptimalControlProblem.variable`).

        Parameters
        ----------
        name : str
            Unique among all names of the problem.
        lower, upper : float or parameter expression
            Bounds.
        guess : float or parameter expression, optional
            Initial guess.
        ref, ref0 : float, optional
            Scaling (see :meth:`OptimalControlProblem.state`).
        """
        return self._anchor.variable(name, lower, upper, guess, ref=ref, ref0=ref0)

    def _index(self, ph: PhaseRef) -> int:
        if isinstance(ph, int):
            if not 0 <= ph < len(self.phases):
                raise ProblemDefinitionError(f"no phase {ph}; have {len(self.phases)}")
            return ph
        for i, q in enumerate(self.phases):
            if q is ph:
                return i
        raise ProblemDefinitionError("that phase does not belong to this problem")

    def link(self, a: PhaseRef, b: PhaseRef, states: Sequence[str] | None = None,
             time: bool = True) -> None:
        """Continuity from the end of phase ``a`` to the start of phase ``b``.

        Parameters
        ----------
        a, b : OptimalControlProblem or int
            The phases (``b`` usually follows ``a``).
        states : sequence of str, optional
            States equal across the junction (default: every state name the two
            phases share; refused when they share none, so that a typo cannot leave
            the phases unlinked; ``()`` links the time only). Use
            :meth:`link_constraint` for anything else (jumps, resets, inequalities).
        time : bool
            Also ``t0 of b = T of a``.
        """
        ia, ib = self._index(a), self._index(b)
        pa, pb = self.phases[ia], self.phases[ib]
        names = [n for n in pa.state_names if n in pb.state_names] if states is None \
            else list(states)
        if states is None and not names and pa.nx and pb.nx:
            # a link that silently joins nothing would solve as two unrelated phases
            raise ProblemDefinitionError(
                f"link: phases {pa.name!r} and {pb.name!r} share no state name; name the "
                "states (states=[...]), pass states=() to link time only, or use "
                "link_constraint")
        for n in names:
            if n not in pa.state_names or n not in pb.state_names:
                raise ProblemDefinitionError(f"link: state {n!r} is not in both phases")
            ea = pa.xT[pa.state_names.index(n)]
            eb = pb.x0[pb.state_names.index(n)]
            self.link_constraint(eb - ea, 0.0, name=f"{n}: {pa.name} -> {pb.name}")
        if time:
            self.link_constraint(pb.t0 - pa.T, 0.0, name=f"time: {pa.name} -> {pb.name}")
            self.time_links.append((ia, ib))

    def link_constraint(self, expr: Any, lower: Bound, upper: Bound | None = None,
                        name: str | None = None, *, ref: float | None = None) -> Constraint:
        """``lower <= expr <= upper`` on end-point values of any phases.

        ``expr`` uses ``phase.at_t0(...)``, ``phase.at_tf(...)``,
        ``phase.integral(...)``, ``phase.t0``, ``phase.T``, parameters and variables.

        Parameters
        ----------
        expr : SX
            Expression of end-point symbols of any phases, parameters and variables.
        lower : float or parameter expression
            Lower bound, or the value of an equality.
        upper : float or parameter expression, optional
            Upper bound.
        name : str, optional
            Used in messages.
        ref : float, optional
            Typical size of ``expr`` (see :meth:`OptimalControlProblem.path_constraint`).
        """
        e = to_sx(expr, "link constraint")
        label = name or f"link{len(self.links)}"
        require_only(e, self.boundary_symbols(), f"link constraint {label!r}",
                     "use phase.at_t0(...) / phase.at_tf(...)")
        upper = lower if upper is None else upper
        lo = ca.repmat(self._shared.bound(lower, f"{label} lower bound"), e.numel(), 1)
        hi = ca.repmat(self._shared.bound(upper, f"{label} upper bound"), e.numel(), 1)
        for i in range(e.numel()):
            check_bounds(lo[i], hi[i], f"link constraint {label!r}")
        c = Constraint(e, lo, hi, label, constraint_ref(ref, f"link constraint {label!r}"))
        self.links.append(c)
        return c

    def minimize(self, expr: Any, *, ref: float | None = None) -> None:
        """Add an end-point cost over any phases (``phase.at_tf(...)``, ``phase.T``, ...).

        Parameters
        ----------
        expr : SX
            Expression of end-point symbols of any phases, parameters and variables.
        ref : float, optional
            Typical magnitude of the objective (see
            :meth:`OptimalControlProblem.minimize`).
        """
        r = objective_ref(ref)
        if r is not None:
            self._shared.objective_ref = r
        e = to_sx(expr, "minimize")
        require_only(e, self.boundary_symbols(), "minimize term",
                     "use phase.at_t0(...) / phase.at_tf(...)")
        self.boundary_cost = self.boundary_cost + e

    # ------------------------------------------------------------------ access
    @property
    def param_names(self) -> list[str]:
        """Names of the parameters."""
        return self._shared.param_names

    @property
    def var_names(self) -> list[str]:
        """Names of the decision variables."""
        return self._shared.var_names

    @property
    def np(self) -> int:
        """Number of parameters."""
        return len(self._shared.params)

    @property
    def nv(self) -> int:
        """Number of decision variables."""
        return len(self._shared.vars)

    @property
    def p(self) -> ca.SX:
        """The parameters, stacked."""
        return self._shared.p

    @property
    def v(self) -> ca.SX:
        """The decision variables, stacked."""
        return self._shared.v

    @property
    def shared(self) -> Shared:
        """Parameters and decision variables, shared by all phases (read it; declare through
        :meth:`parameter` and :meth:`variable`)."""
        return self._shared

    def param_vector(self, params: Mapping[str, float]) -> ndarray:
        """Parameter values in declaration order, checked (see
        :meth:`OptimalControlProblem.param_vector`).

        Parameters
        ----------
        params : mapping
            A value for every declared parameter.
        """
        return self._anchor.param_vector(params)

    def boundary_symbols(self) -> list[ca.SX]:
        """What link constraints and the objective may depend on."""
        out: list[ca.SX] = []
        for ph in self.phases:
            out += ph.boundary_symbols()[:-(self.np + self.nv) or None]
        return out + list(self._shared.params) + list(self._shared.vars)

    def validate(self) -> None:
        """Check every phase, and that something is left to optimise."""
        if not self.phases:
            raise ProblemDefinitionError("the problem has no phase")
        for ph in self.phases:
            ph.validate()

    # -------------------------------------------------------- resolved pieces
    def times(self) -> list[PhaseTimes]:
        """Each phase's time handling, resolved along the sequence (links, guesses)."""
        linked = {b: a for a, b in self.time_links}
        out: list[PhaseTimes] = []
        for i, ph in enumerate(self.phases):
            out.append(_phase_times(ph, out[linked[i]] if i in linked and linked[i] < i
                                    else None, i in linked))
        return out

    def boundary_blocks(self, times: list[PhaseTimes]) -> list[tuple[int, str, Constraint]]:
        """Every end-point constraint, as ``(phase index or -1, block name, constraint)``.

        Parameters
        ----------
        times : list of PhaseTimes
            Each phase's time handling, as given by the method ``times``.
        """
        out: list[tuple[int, str, Constraint]] = []
        for i, (ph, tm) in enumerate(zip(self.phases, times, strict=True)):
            for kind, store in (("initial", ph.initial), ("terminal", ph.terminal)):
                for c in store:
                    e = ph.at_t0(c.expr) if kind == "initial" else ph.at_tf(c.expr)
                    out.append((i, kind, Constraint(e, c.lower, c.upper, c.name, c.ref)))
            out += [(i, "boundary", c) for c in ph.boundary]
            if tm.span is not None:
                out.append((i, "time", Constraint(ph.T - ph.t0, ca.SX(tm.span[0]),
                                                  ca.SX(tm.span[1]), "duration")))
        return out + [(-1, "link", c) for c in self.links]

    def objective(self) -> ca.SX:
        """The end-point part of the objective (Mayer terms of all phases and ours)."""
        J = self.boundary_cost
        for ph in self.phases:
            J = J + ph.at_tf(ph.mayer) + ph.boundary_cost
        return J


def _phase_times(ph: OptimalControlProblem, prev: PhaseTimes | None,
                 linked: bool) -> PhaseTimes:
    if ph.t0_mode == "free" or (ph.t0_mode == "default" and linked):
        t0_free, t0_b = True, ph.t0_bounds if ph.t0_mode == "free" else (-INF, INF)
        t0_g = prev.T_guess if prev is not None and ph.t0_mode == "default" else ph.t0_guess
    else:
        t0_free, t0_b, t0_g = False, ph.t0_bounds, ph.t0_bounds[0]
    span: tuple[float, float] | None = None
    if ph.duration is not None:
        T_free, T_b, T_g = True, (-INF, INF), t0_g + (ph.duration_guess or 1.0)
        span = ph.duration
    elif ph.time_free:
        T_free, T_b, T_g = True, ph.T_bounds, ph.T_guess
        if T_g <= t0_g:
            T_g = float(np.clip(t0_g + 1.0, *T_b))
        if t0_free:
            span = (0.0, INF)
    else:
        T_free, T_b, T_g = False, ph.T_bounds, ph.T_bounds[0]
        if t0_free:
            span = (0.0, INF)
    return PhaseTimes(t0_free, t0_b, t0_g, T_free, T_b, T_g, span)


def as_multiphase(problem: OptimalControlProblem | MultiPhaseProblem) -> MultiPhaseProblem:
    """``problem`` as a :class:`MultiPhaseProblem` (a one-phase view if needed).

    Parameters
    ----------
    problem : OptimalControlProblem or MultiPhaseProblem
        The problem.
    """
    if isinstance(problem, MultiPhaseProblem):
        return problem
    if isinstance(problem, OptimalControlProblem):
        return MultiPhaseProblem.single(problem)
    raise ProblemDefinitionError(f"expected an OptimalControlProblem or MultiPhaseProblem, "
                                 f"got {type(problem).__name__}")


__all__ = ["MultiPhaseProblem", "PhaseTimes", "as_multiphase"]
