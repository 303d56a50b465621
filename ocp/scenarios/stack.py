"""How a :class:`ocp.scenarios.scenario.ScenarioProblem` is stacked into one multi-phase problem.

Scenario ``i`` of a one-phase problem gets its own copy of every state
(``"x[i]"``) and of every scenario parameter (``"b[i]"``); the common
parameters and the decision variables are shared. The stacked problem runs in
normalised time ``tau`` in ``[0, 1]``: the dynamics of scenario ``i`` are
multiplied by ``T_i - t0`` and its time is ``t = t0 + tau (T_i - t0)``, where
``T_i`` is the fixed final time or the decision variable ``"T[i]"``. Controls
are shared (same names) in the phase before the branching and per scenario
(``"u[i]"``) after it. The running cost and the declared integrals of each
scenario are carried by states that start at 0 (``"running_cost[i]"``,
``"integral0[i]"``; one per distinct integrand), so every scenario's cost and
boundary constraints are expressions of end-point values. A constraint whose copies do not differ
between scenarios (one on the shared control only) is posted once: its
copies would be the same row ``S`` times, which Ipopt cannot tell apart.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from ..definition.errors import ProblemDefinitionError
from ..definition.multiphase import MultiPhaseProblem
from ..definition.problem import INF, OptimalControlProblem
from ..definition.symbols import Constraint
from .result import ScenarioMaps

__all__ = ["EPIGRAPH", "stack"]

EPIGRAPH = "worst_case"
"""Name of the epigraph variable ``z`` of the worst-case objective (``J_i <= z``)."""


def stack(problem: OptimalControlProblem, names: list[str], n_scenarios: int,
          objective: str, branching: float) -> tuple[MultiPhaseProblem, ScenarioMaps]:
    """The stacked problem of ``n_scenarios`` copies of ``problem``, and its maps.

    Parameters
    ----------
    problem : OptimalControlProblem
        The one-phase problem (fixed initial time).
    names : list of str
        The scenario parameters (one copy per scenario); the others are common.
    n_scenarios : int
        Number of scenarios.
    objective : {"worst", "expected"}
        Epigraph of the largest cost, or the sum weighted by the parameters
        ``"weight[i]"``.
    branching : float
        Fraction of the horizon until which the control is shared (1: all of it).
    """
    return _Stacker(problem, names, n_scenarios, objective, branching).build()


class _Stacker:
    """Builds the stacked problem and its maps (see :func:`stack`)."""

    def __init__(self, problem: OptimalControlProblem, names: list[str], n_scenarios: int,
                 objective: str, branching: float) -> None:
        pr = problem
        self.pr = pr
        self.names = list(names)
        self.common_names = [n for n in pr.param_names if n not in names]
        self.objective = objective
        self.branching = branching
        self.S = n_scenarios
        self.mp = MultiPhaseProblem(f"{pr.name}_scenarios")
        self.t0c = float(pr.t0_bounds[0]) if pr.t0_mode == "fixed" else 0.0
        # one accumulator state per distinct integrand: the running cost, then the
        # declared integrals (an integral constraint and a cost term on the same
        # integrand share one; two identical states make Ipopt's KKT systems hard)
        self.acc: list[str] = []
        self.acc_rhs: list[ca.SX] = []
        named = ([("running_cost", pr.lagrange)] if pr.has_running_cost() else []) + \
            [(str(q.name()), e) for q, e in pr.integrals]
        where = [self._accumulator(k, e) for k, e in named]
        self.running_state = where[0] if pr.has_running_cost() else None
        self.integral_states = where[1:] if pr.has_running_cost() else where
        self._spec0: ca.SX | None = None  # scenario 0's own symbols, once the phases exist

    def _accumulator(self, name: str, integrand: ca.SX) -> str:
        """The accumulator state of ``integrand`` (a new one unless it repeats one)."""
        for k, e in zip(self.acc, self.acc_rhs, strict=True):
            if ca.is_equal(e, integrand, 64):
                return k
        self.acc.append(name)
        self.acc_rhs.append(integrand)
        return name

    # ------------------------------------------------------------ symbols
    def _declare_symbols(self) -> None:
        pr, mp, S = self.pr, self.mp, self.S
        sh = pr.shared
        self.common = {n: mp.parameter(n) for n in self.common_names}
        self.scen = [{n: mp.parameter(f"{n}[{i}]") for n in self.names} for i in range(S)]
        self.weight = ([mp.parameter(f"weight[{i}]") for i in range(S)]
                       if self.objective == "expected" else [])
        self.vars: list[ca.SX] = []
        for n in pr.var_names:
            lo, hi = (self._common_only(b, f"variable {n!r} bound") for b in sh.var_bounds[n])
            g = sh.var_guess.get(n)
            g = None if g is None else self._common_only(g, f"variable {n!r} guess")
            r = sh.var_ref.get(n)
            self.vars.append(mp.variable(n, lo, hi, g, ref=None if r is None else r[1],
                                         ref0=None if r is None else r[0]))
        self.Ts: list[ca.SX] = [self._final_time(i) for i in range(S)]

    def _final_time(self, i: int) -> ca.SX:
        pr, t0 = self.pr, self.t0c
        if pr.duration is not None:
            lo, hi = t0 + pr.duration[0], t0 + pr.duration[1]
            guess = t0 + (pr.duration_guess or 1.0)
        else:
            lo, hi = pr.T_bounds
            guess = pr.T_guess
        if not pr.time_free or lo == hi:
            return ca.SX(lo)
        return self.mp.variable(f"T[{i}]", lo, hi, guess)

    def _param_subs(self, i: int | None) -> tuple[list[ca.SX], list[ca.SX]]:
        """Original parameters and variables -> stacked ones (scenario i; None: common)."""
        old, new = [], []
        for n, s in zip(self.pr.param_names, ca.vertsplit(self.pr.p), strict=True):
            old.append(s)
            if n in self.common:
                new.append(self.common[n])
            elif i is not None:
                new.append(self.scen[i][n])
            else:
                new.append(ca.SX.nan())
        old += ca.vertsplit(self.pr.v)[:len(self.vars)]  # all, once they are declared
        new += self.vars
        return old, new

    def _sub(self, expr: Any, old: list[ca.SX], new: list[ca.SX]) -> ca.SX:
        e = ca.SX(expr)
        if not old:
            return e
        return ca.substitute(e, ca.vertcat(*old), ca.vertcat(*new))

    def _common_only(self, b: Any, what: str) -> ca.SX:
        e = ca.SX(b)
        unc = [self.pr.p[self.pr.param_names.index(n)] for n in self.names]
        if unc and ca.depends_on(e, ca.vertcat(*unc)):
            raise ProblemDefinitionError(
                f"{what} depends on a scenario parameter {self.names}: it is shared by "
                "all scenarios")
        return self._sub(e, *self._param_subs(None))

    # ------------------------------------------------------------- phases
    def _phase(self, name: str, start: float, end: float, shared: bool) -> OptimalControlProblem:
        pr, S = self.pr, self.S
        ph = self.mp.phase(name)
        for i in range(S):
            old, new = self._param_subs(i)
            for k in pr.state_names:
                lo, hi = (self._sub(b, old, new) for b in pr.state_bounds[k])
                g = pr.state_guess.get(k)
                if isinstance(g, tuple):
                    a, b = (self._sub(v, old, new) for v in g)
                    g = (a + (b - a) * start, a + (b - a) * end)
                elif g is not None:
                    g = self._sub(g, old, new)
                r = pr.state_ref.get(k)
                ph.state(f"{k}[{i}]", lo, hi, g, ref=None if r is None else r[1],
                         ref0=None if r is None else r[0])
            for k in self.acc:
                ph.state(f"{k}[{i}]")
        for k in pr.control_names:
            r = pr.control_ref.get(k)
            ref = {"ref": None if r is None else r[1], "ref0": None if r is None else r[0]}
            if shared:
                lo, hi = (self._common_only(b, f"control {k!r} bound")
                          for b in pr.control_bounds[k])
                g = pr.control_guess.get(k)
                g = None if g is None else self._common_only(g, f"control {k!r} guess")
                ph.control(k, lo, hi, g, **ref)
            else:
                for i in range(S):
                    old, new = self._param_subs(i)
                    lo, hi = (self._sub(b, old, new) for b in pr.control_bounds[k])
                    g = pr.control_guess.get(k)
                    ph.control(f"{k}[{i}]", lo, hi, None if g is None else
                               self._sub(g, old, new), **ref)
        ph.fixed_final_time(end)  # a later phase's start is linked to the previous end
        return ph

    def _state(self, ph: OptimalControlProblem, name: str) -> ca.SX:
        return ph.x[ph.state_names.index(name)]

    def _control(self, ph: OptimalControlProblem, name: str, i: int) -> ca.SX:
        k = name if name in ph.control_names else f"{name}[{i}]"
        return ph.u[ph.control_names.index(k)]

    def _running(self, ph: OptimalControlProblem, i: int) -> tuple[list[ca.SX], list[ca.SX]]:
        """Original running symbols -> scenario i's in phase ``ph``."""
        pr = self.pr
        old = [*ca.vertsplit(pr.x), *ca.vertsplit(pr.u), pr.t, pr.t0, pr.T]
        new = [*[self._state(ph, f"{k}[{i}]") for k in pr.state_names],
               *[self._control(ph, k, i) for k in pr.control_names],
               self.t0c + ph.t * (self.Ts[i] - self.t0c), ca.SX(self.t0c), self.Ts[i]]
        po, pn = self._param_subs(i)
        return old + po, new + pn

    def _boundary(self, i: int) -> tuple[list[ca.SX], list[ca.SX]]:
        """Original end-point symbols -> scenario i's in the stacked problem."""
        pr, first, last = self.pr, self.phases[0], self.phases[-1]
        old = [*ca.vertsplit(pr.x0), *ca.vertsplit(pr.u0), *ca.vertsplit(pr.xT),
               *ca.vertsplit(pr.uT), pr.t0, pr.T, *ca.vertsplit(pr.q)]
        new = [*[first.at_t0(self._state(first, f"{k}[{i}]")) for k in pr.state_names],
               *[first.at_t0(self._control(first, k, i)) for k in pr.control_names],
               *[last.at_tf(self._state(last, f"{k}[{i}]")) for k in pr.state_names],
               *[last.at_tf(self._control(last, k, i)) for k in pr.control_names],
               ca.SX(self.t0c), self.Ts[i],
               *[last.at_tf(self._state(last, f"{k}[{i}]")) for k in self.integral_states]]
        po, pn = self._param_subs(i)
        return old + po, new + pn

    def _specific(self, i: int) -> ca.SX:
        """Every symbol of the stacked problem that belongs to scenario i alone."""
        out: list[ca.SX] = [self.scen[i][n] for n in self.names]
        if self.Ts[i].is_symbolic():
            out.append(self.Ts[i])
        for ph in self.phases:
            for k, s in zip(ph.state_names, ca.vertsplit(ph.x), strict=True):
                if k.endswith(f"[{i}]"):
                    out += [s, ph.at_t0(s), ph.at_tf(s)]
            for k, s in zip(ph.control_names, ca.vertsplit(ph.u), strict=True):
                if k.endswith(f"[{i}]"):
                    out += [s, ph.at_t0(s), ph.at_tf(s)]
        return ca.vertcat(*out)

    def _owners(self, exprs: list[ca.SX]) -> list[int] | None:
        """The scenarios a family of per-scenario rows belongs to (None: identical rows).

        ``exprs`` are scenario 0's copies (expression and bounds): if none involves a
        symbol of scenario 0 alone, every scenario's copy is the same row.
        """
        if self._spec0 is None:
            self._spec0 = self._specific(0)
        if self.S > 1 and not any(ca.depends_on(e, self._spec0) for e in exprs):
            return None
        return list(range(self.S))

    # --------------------------------------------------------------- build
    def build(self) -> tuple[MultiPhaseProblem, ScenarioMaps]:
        pr, mp, S, f = self.pr, self.mp, self.S, self.branching
        self._declare_symbols()
        if f in (0.0, 1.0):
            self.phases = [self._phase(pr.name, 0.0, 1.0, f == 1.0)]
        else:
            self.phases = [self._phase("shared", 0.0, f, True),
                           self._phase("branched", f, 1.0, False)]
            mp.link(self.phases[0], self.phases[1])
        self.path_owner: dict[str, int | None] = {}
        for ph in self.phases:
            self._dynamics_and_path(ph)
        checks = self._boundary_constraints()
        costs = []
        for i in range(S):
            old, new = self._boundary(i)
            J = self._sub(pr.at_tf(pr.mayer) + pr.boundary_cost, old, new)
            if self.running_state is not None:
                J = J + self.phases[-1].at_tf(self._state(self.phases[-1],
                                                          f"{self.running_state}[{i}]"))
            costs.append(J)
        ref = pr.shared.objective_ref
        if self.objective == "worst":
            z = mp.variable(EPIGRAPH)
            for i, J in enumerate(costs):
                mp.link_constraint(J - z, -INF, 0.0, name=f"cost[{i}] <= {EPIGRAPH}")
            mp.minimize(z, ref=ref)
        else:
            mp.minimize(sum((w * J for w, J in zip(self.weight, costs, strict=True)),
                            ca.SX(0)), ref=ref)
        return mp, self._maps(costs, checks)

    def _dynamics_and_path(self, ph: OptimalControlProblem) -> None:
        pr, S = self.pr, self.S
        rhs: dict[str, ca.SX] = {}
        for i in range(S):
            old, new = self._running(ph, i)
            scale = self.Ts[i] - self.t0c
            for k, e in zip(pr.state_names, ca.vertsplit(pr.rhs), strict=True):
                rhs[f"{k}[{i}]"] = scale * self._sub(e, old, new)
            for k, e in zip(self.acc, self.acc_rhs, strict=True):
                rhs[f"{k}[{i}]"] = scale * self._sub(e, old, new)
        ph.set_dynamics(rhs)
        for c in pr.path:
            rows = [(self._sub(c.expr, *self._running(ph, i)),
                     self._sub(c.lower, *self._running(ph, i)),
                     self._sub(c.upper, *self._running(ph, i))) for i in range(S)]
            owners = self._owners(list(rows[0]))
            if owners is None:
                e, lo, hi = rows[0]
                ph.path_constraint(e, lo, hi, name=c.name, ref=c.ref)
                self.path_owner[c.name] = None
                continue
            for i in owners:
                e, lo, hi = rows[i]
                ph.path_constraint(e, lo, hi, name=f"{c.name}[{i}]", ref=c.ref)
                self.path_owner[f"{c.name}[{i}]"] = i

    def _boundary_constraints(self) -> list[tuple[int | None, str, Constraint]]:
        """Post every end-point constraint of every scenario; return them for the checks.

        A constraint on the first phase's start only becomes an initial constraint and
        one on the last phase's end only a terminal one (so that the default guess sees
        the fixed values); anything else is a link constraint.
        """
        pr, first, last = self.pr, self.phases[0], self.phases[-1]
        out: list[tuple[int | None, str, Constraint]] = []
        for i in range(self.S):
            for k in self.acc:  # every accumulated integral starts at 0
                first.initial_constraint(self._state(first, f"{k}[{i}]"), 0.0,
                                         name=f"{k}[{i}](t0)")
        family = [(pr.at_t0(c.expr), c) for c in pr.initial] + \
            [(pr.at_tf(c.expr), c) for c in pr.terminal] + [(c.expr, c) for c in pr.boundary]
        groups: list[tuple[str, ca.SX]] = []
        for j, ph in enumerate(self.phases):
            groups += [(f"{j}x0", ph.x0), (f"{j}u0", ph.u0), (f"{j}xT", ph.xT),
                       (f"{j}uT", ph.uT), (f"{j}q", ph.q)]
        n = len(self.phases) - 1
        start, end = {"0x0", "0u0"}, {f"{n}xT", f"{n}uT"}
        for e0, c in family:
            rows = []
            for i in range(self.S):
                old, new = self._boundary(i)
                rows.append(tuple(self._sub(v, old, new) for v in (e0, c.lower, c.upper)))
            owners = self._owners(list(rows[0]))
            for i in ([0] if owners is None else owners):
                e, lo, hi = rows[i]
                name = c.name if owners is None else f"{c.name}[{i}]"
                used = {k for k, v in groups if v.numel() and ca.depends_on(e, v)}
                if used and used <= end:
                    last.terminal_constraint(_bare_T(last, e), lo, hi, name=name, ref=c.ref)
                elif used <= start:
                    first.initial_constraint(_bare_0(first, e), lo, hi, name=name, ref=c.ref)
                else:
                    self.mp.link_constraint(e, lo, hi, name=name, ref=c.ref)
                out.append((None if owners is None else i, name, Constraint(e, lo, hi, name)))
        return out

    def _maps(self, costs: list[ca.SX],
              checks: list[tuple[int | None, str, Constraint]]) -> ScenarioMaps:
        pr, mp, first, last = self.pr, self.mp, self.phases[0], self.phases[-1]
        ends = ca.vertcat(first.x0, first.u0, last.xT, last.uT)
        g = ca.vertcat(*[c.expr for _, _, c in checks]) if checks else ca.SX(0, 1)
        lo = ca.vertcat(*[c.lower for _, _, c in checks]) if checks else ca.SX(0, 1)
        hi = ca.vertcat(*[c.upper for _, _, c in checks]) if checks else ca.SX(0, 1)
        fn = ca.Function("scenario_ends", [ends, mp.p, mp.v], [ca.vertcat(*costs), g, lo, hi])
        state_owner: dict[str, int] = {}
        for ph in self.phases:
            for k in ph.state_names:
                state_owner[k] = int(k.rsplit("[", 1)[1][:-1])
        final = [self.Ts[i] if not self.Ts[i].is_symbolic() else str(self.Ts[i].name())
                 for i in range(self.S)]
        return ScenarioMaps(
            names=list(self.names), n_scenarios=self.S, objective=self.objective,
            state_names=list(pr.state_names), control_names=list(pr.control_names),
            t0=self.t0c, final_times=[float(v) if isinstance(v, ca.SX) else v for v in final],
            ends=fn, checks=[(owner, name) for owner, name, _ in checks],
            path_owner=dict(self.path_owner), state_owner=state_owner,
            phase_names=[ph.name for ph in self.phases], branching=self.branching)


def _bare_0(ph: OptimalControlProblem, e: ca.SX) -> ca.SX:
    return ca.substitute(e, ca.vertcat(ph.x0, ph.u0), ca.vertcat(ph.x, ph.u))


def _bare_T(ph: OptimalControlProblem, e: ca.SX) -> ca.SX:
    return ca.substitute(e, ca.vertcat(ph.xT, ph.uT), ca.vertcat(ph.x, ph.u))

