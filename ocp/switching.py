"""Bang-bang structure detection and switching-time refinement to machine precision.

From a transcribed solution, :func:`detect_arcs` labels each shooting interval
by where its control sits (upper bound, lower bound, or interior) and merges
them into arcs; an interval where the control is between two different bang
arcs is read as the switch, whose time is estimated from the interval average.

:func:`refine_switching` then solves a second, small NLP whose unknowns are
the arc durations (and the initial state), with the control fixed at its bound
on each arc. When the dynamics are affine in the state for fixed control (the
soft-landing model is), each arc is integrated *exactly*: its flow is
``expm(A tau)`` of a constant augmented matrix, written as a CasADi expression
in the duration (Taylor series of degree 18 after scaling, then squaring), so
Ipopt gets exact derivatives of exact arcs. Otherwise each arc is integrated by
CVODES at tolerance 1e-13. Path constraints are imposed at the arc ends and at
``interior_samples`` points inside each arc.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg

from .errors import InfeasibleError, SolveError
from .problem import OptimalControlProblem
from .solution import Solution

REFINE_IPOPT = {"tol": 1e-14, "acceptable_tol": 1e-12, "constr_viol_tol": 1e-13,
                "max_iter": 500, "print_level": 0, "sb": "yes", "bound_relax_factor": 0.0,
                "nlp_scaling_method": "none"}


@dataclass
class Arc:
    """A maximal interval where the control sits at one bound (or strictly inside)."""

    kind: str  # "max", "min" or "interior"
    start: float
    end: float
    active: tuple[str, ...] = ()  # path constraints active at every node of the arc

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass
class SwitchingStructure:
    """Arcs of one control, and whether they are all bang arcs."""

    control: str
    arcs: list[Arc]
    lower: float
    upper: float

    @property
    def kinds(self) -> list[str]:
        return [a.kind for a in self.arcs]

    @property
    def bang_bang(self) -> bool:
        return all(a.kind != "interior" for a in self.arcs)

    @property
    def switch_times(self) -> list[float]:
        return [a.end for a in self.arcs[:-1]]

    def without_trailing_constrained(self) -> SwitchingStructure:
        """Drop a final interior arc on which a path (state) constraint is active.

        On such an arc the control is whatever keeps the state on its
        constraint, not a bang; the bang-bang argument does not apply there.
        Dropping it refines the problem whose final time is the end of the
        last bang arc, which is the right question when the terminal
        conditions already account for the constrained tail (as the soft
        landing's body-arrest condition does).
        """
        if len(self.arcs) > 1 and self.arcs[-1].kind == "interior" and self.arcs[-1].active:
            return SwitchingStructure(self.control, self.arcs[:-1], self.lower, self.upper)
        return self


def _active_path_constraints(sol: Solution, tol: float) -> np.ndarray:
    """Boolean (N+1, n_path): path constraint i active (at a bound) at node k."""
    pr = sol.problem
    if not pr.path:
        return np.zeros((sol.N + 1, 0), dtype=bool)
    pv = [sol.params[k] for k in pr.param_names]
    cols = []
    for c in pr.path:
        vals = sol.evaluate(c.expr)
        lo, hi = (float(v) for v in ca.Function("b", [pr.p], [c.lower, c.upper])(pv))
        scale = tol * np.maximum(1.0, np.abs(vals))
        cols.append((np.abs(vals - lo) <= scale) | (np.abs(vals - hi) <= scale))
    return np.column_stack(cols)


def _bounds_at(problem: OptimalControlProblem, name: str, params: dict) -> tuple[float, float]:
    lo, hi = problem.control_bounds[name]
    f = ca.Function("b", [problem.p], [lo, hi])
    pv = [params[k] for k in problem.param_names]
    return tuple(float(v) for v in f(pv))


def detect_arcs(sol: Solution, control: str | None = None, tol: float = 1e-4,
                max_transition: int = 1) -> SwitchingStructure:
    """Bang and interior arcs of a transcribed solution.

    Parameters
    ----------
    sol : Solution
    control : str, optional
        Which control (default: the only one).
    tol : float
        An interval is at a bound when within ``tol * max(1, |bound|)`` of it.
    max_transition : int
        Interior runs of at most this many intervals between two *different*
        bang arcs are read as the switch (the control averages both bounds
        over the interval that contains the switching time); such runs at
        either end of the horizon, next to a bang arc, are read as that arc
        (the uniform grid cannot end the arc exactly on a node).
    """
    pr = sol.problem
    name = control or pr.control_names[0]
    lo, hi = _bounds_at(pr, name, sol.params)
    u = sol.control(name)
    h = sol.T / sol.N
    lab = np.where(np.abs(u - hi) <= tol * max(1.0, abs(hi)), "max",
                   np.where(np.abs(u - lo) <= tol * max(1.0, abs(lo)), "min", "interior"))
    runs: list[list] = []  # [kind, first interval, last interval]
    for k, lb in enumerate(lab.tolist()):
        if runs and runs[-1][0] == lb:
            runs[-1][2] = k
        else:
            runs.append([lb, k, k])
    # An interior run of at most max_transition intervals at either end, next to
    # a bang arc, is the uniform grid failing to put the end of that arc on a
    # node: absorb it (the refinement then places the end exactly).
    for end in (0, -1):
        nb = 1 if end == 0 else -2
        if (len(runs) > 1 and runs[end][0] == "interior" and runs[nb][0] != "interior"
                and runs[end][2] - runs[end][1] + 1 <= max_transition):
            if end == 0:
                runs[1][1] = runs[0][1]
            else:
                runs[-2][2] = runs[-1][2]
            del runs[end]
    arcs: list[Arc] = []
    i = 0
    while i < len(runs):
        kind, a, b = runs[i]
        start = a * h if not arcs else arcs[-1].end
        if (kind == "interior" and 0 < i < len(runs) - 1 and b - a + 1 <= max_transition
                and runs[i - 1][0] != "interior" and runs[i + 1][0] != "interior"
                and runs[i - 1][0] != runs[i + 1][0]):
            # the switch lies inside: split by the average force
            ua = hi if runs[i - 1][0] == "max" else lo
            ub = hi if runs[i + 1][0] == "max" else lo
            theta = float(np.clip((np.mean(u[a:b + 1]) - ub) / (ua - ub), 0.0, 1.0))
            arcs[-1].end = (a + theta * (b - a + 1)) * h
            i += 1
            continue
        arcs.append(Arc(kind, start, (b + 1) * h))
        i += 1
    # merge neighbours of the same kind (after absorbing transitions)
    merged: list[Arc] = []
    for arc in arcs:
        if merged and merged[-1].kind == arc.kind:
            merged[-1].end = arc.end
        else:
            merged.append(arc)
    merged[-1].end = sol.T
    act = _active_path_constraints(sol, tol)
    for arc in merged:
        k0 = int(round(arc.start / h)) if h > 0 else 0
        k1 = max(k0 + 1, int(round(arc.end / h)))
        nodes = act[k0 + 1:k1] if k1 - k0 > 1 else act[k0:k1]
        arc.active = tuple(c.name for i, c in enumerate(pr.path)
                           if nodes.shape[0] and nodes[:, i].all())
    return SwitchingStructure(name, merged, lo, hi)


# ---------------------------------------------------------------- exact arcs
def _expm_symbolic(M: np.ndarray, tau: ca.SX, tau_max: float, order: int = 18) -> ca.SX:
    """``expm(M tau)`` as an SX expression in the scalar ``tau`` (0 <= tau <= tau_max).

    Scaling and squaring: ``2^-s M tau`` has norm <= 1/2 on the whole range,
    where a degree-18 Taylor polynomial is accurate to 1e-22 relative.
    """
    nrm = float(np.abs(M).sum(axis=1).max()) * max(tau_max, 1e-12)
    s = max(0, math.ceil(math.log2(max(nrm, 1e-300) / 0.5)))
    X = ca.SX(ca.DM(M)) * (tau / 2.0**s)
    n = M.shape[0]
    E = ca.SX.eye(n)
    term = ca.SX.eye(n)
    for k in range(1, order + 1):
        term = ca.mtimes(term, X) / k
        E = E + term
    for _ in range(s):
        E = ca.mtimes(E, E)
    return E


@dataclass
class RefinedSwitching:
    """Switching times and arcs refined to machine precision.

    Attributes
    ----------
    kinds : list of "max"/"min" per arc; ``values`` the control on each arc.
    durations, switch_times : arc lengths and the times between arcs.
    T, objective : final time and refined objective.
    x0, xT : initial and final states.
    exact : True when arcs were integrated by the matrix exponential.
    status, iterations, solve_time : Ipopt's figures.
    transcribed_objective : the objective of the solution it started from.
    """

    problem: OptimalControlProblem
    params: dict
    control: str
    kinds: list[str]
    values: list[float]
    durations: np.ndarray
    T: float
    objective: float
    x0: np.ndarray
    xT: np.ndarray
    exact: bool
    status: str
    iterations: int
    solve_time: float
    transcribed_objective: float
    lam_g: np.ndarray = field(repr=False, default=None)
    blocks: dict = field(repr=False, default_factory=dict)
    end_path_violation: float = 0.0

    @property
    def switch_times(self) -> list[float]:
        return list(np.cumsum(self.durations)[:-1])

    def control_at(self, t: np.ndarray) -> np.ndarray:
        edges = np.cumsum(self.durations)
        idx = np.minimum(np.searchsorted(edges, t, side="right"), len(self.values) - 1)
        return np.asarray(self.values)[idx]

    def sample(self, n: int = 1000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Trajectory on ``n`` points plus the switching instants (exact for affine arcs)."""
        pr = self.problem
        pv = np.array([self.params[k] for k in pr.param_names])
        t = np.union1d(np.linspace(0, self.T, n), np.r_[0.0, np.cumsum(self.durations)])
        xs = np.empty((len(t), pr.nx))
        start = 0.0
        x = self.x0.copy()
        k = 0
        edges = np.cumsum(self.durations)
        flows = [_numeric_flow(pr, v, pv) for v in self.values]
        for i, ti in enumerate(t):
            while k < len(edges) - 1 and ti > edges[k]:
                x = flows[k](x, edges[k] - start)
                start = edges[k]
                k += 1
            xs[i] = flows[k](x, ti - start)
        return t, xs, self.control_at(t)

    def to_dict(self) -> dict[str, Any]:
        return {"arcs": self.kinds, "values": list(map(float, self.values)),
                "durations": self.durations.tolist(), "switch_times": self.switch_times,
                "T": self.T, "objective": self.objective, "x0": self.x0.tolist(),
                "xT": self.xT.tolist(), "exact_arcs": self.exact, "status": self.status,
                "iterations": self.iterations, "solve_time_s": self.solve_time,
                "transcribed_objective": self.transcribed_objective,
                "end_path_violation": self.end_path_violation}


def _affine_parts(pr: OptimalControlProblem, u_value: float, pv: np.ndarray,
                  with_quadrature: bool) -> np.ndarray:
    """Augmented matrix ``[[A, b], [0, 0]]`` of ``x' = A x + b`` at constant control."""
    z = ca.vertcat(pr.x, ca.SX.sym("q")) if with_quadrature else pr.x
    rhs = ca.vertcat(pr.rhs, pr.lagrange) if with_quadrature else pr.rhs
    Jf = ca.Function("J", [z, pr.u, pr.p], [ca.jacobian(rhs, z), rhs])
    n = z.numel()
    A, b = (np.array(v, dtype=float) for v in Jf(np.zeros(n), u_value, pv))
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = b.ravel()
    return M


def _numeric_flow(pr, u_value, pv):
    if pr.is_affine_in_state():
        M = _affine_parts(pr, u_value, pv, False)

        def flow(x, tau):
            z = np.r_[x, 1.0]
            return (scipy.linalg.expm(M * tau) @ z)[:-1]

        return flow
    f = pr.dynamics_function()
    x = ca.SX.sym("x", pr.nx)
    tau = ca.SX.sym("tau")
    integ = ca.integrator("I", "cvodes", {"x": x, "p": tau, "ode": tau * f(x, u_value, pv)}, 0, 1,
                      {"abstol": 1e-13, "reltol": 1e-13})

    def flow(x0, t):
        return np.array(integ(x0=x0, p=t)["xf"]).ravel()

    return flow


def refine_switching(sol: Solution, structure: SwitchingStructure | None = None,
                     extra_arcs: int = 0, interior_samples: int = 16,
                     ipopt_options: dict | None = None) -> RefinedSwitching:
    """Re-solve with the arc durations as unknowns and the control at its bounds.

    Parameters
    ----------
    sol : Solution
        A transcribed solution (parameters, bounds and starting guess).
    structure : SwitchingStructure, optional
        Default: :func:`detect_arcs` of ``sol``. Must be bang-bang.
    extra_arcs : int
        Try this many more bang arcs, to test whether more switches improve
        the objective: pairs are inserted inside the longest arc (which keeps
        the first and last arcs), an odd one is appended at the end.
    interior_samples : int
        Path constraints are checked at this many points inside each arc.

    Raises
    ------
    ValueError
        If the structure has interior (non-bang) arcs.
    SolveError, InfeasibleError
        If Ipopt fails.
    """
    pr = sol.problem
    if pr.nu != 1:
        raise ValueError("switching-time refinement supports problems with one control")
    st = structure or detect_arcs(sol)
    if not st.bang_bang:
        raise ValueError(f"not bang-bang: arcs {st.kinds}; refinement needs bang arcs only")
    kinds = list(st.kinds)
    durs = [a.duration for a in st.arcs]
    for _ in range(extra_arcs // 2):
        # split the longest arc around a short arc of the other bound
        i = int(np.argmax(durs))
        other = "min" if kinds[i] == "max" else "max"
        d = durs[i]
        kinds[i:i + 1] = [kinds[i], other, kinds[i]]
        durs[i:i + 1] = [0.495 * d, 0.01 * d, 0.495 * d]
    if extra_arcs % 2:
        kinds.append("min" if kinds[-1] == "max" else "max")
        cut = 0.01 * durs[-1]
        durs[-1] -= cut
        durs.append(cut)
    values = [st.upper if k == "max" else st.lower for k in kinds]
    K = len(kinds)
    pv = np.array([sol.params[k] for k in pr.param_names])
    nx = pr.nx
    has_L = not (isinstance(pr.lagrange, ca.SX) and pr.lagrange.is_zero())
    exact = pr.is_affine_in_state() and (
        not has_L or not ca.depends_on(ca.jacobian(pr.lagrange, pr.x), pr.x))

    tau = ca.SX.sym("tau", K)
    x0 = ca.SX.sym("x0", nx)
    T_max = pr.T_bounds[1] if pr.time_free else pr.T_bounds[0]
    if exact:
        flows = []
        for v in values:
            M = _affine_parts(pr, v, pv, has_L)
            flows.append(M)

        def propagate(k, z, t):
            E = _expm_symbolic(flows[k], t, T_max)
            return ca.mtimes(E, ca.vertcat(z, 1))[:-1]
    else:
        f = pr.dynamics_function()
        L = pr.lagrange_function()
        Ifs = []
        for v in values:
            xx = ca.SX.sym("x", nx + 1)
            tt = ca.SX.sym("t")
            ode = tt * ca.vertcat(f(xx[:nx], v, pv), L(xx[:nx], v, pv))
            Ifs.append(ca.integrator("I", "cvodes", {"x": xx, "p": tt, "ode": ode}, 0, 1,
                                     {"abstol": 1e-13, "reltol": 1e-13}))

        def propagate(k, z, t):
            return Ifs[k](x0=z, p=t)["xf"]

    # build the chain of arcs (symbolic), with interior samples for path constraints
    H = (ca.Function("H", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in pr.path])])
         if pr.path else None)
    # with a running cost (or an integrator, which always carries one) the state
    # is augmented by the cost's quadrature
    z = ca.vertcat(x0, 0) if (has_L or not exact) else x0
    g, lbg, ubg, blocks = [], [], [], {}
    n = 0

    def add(name, expr, lo, hi):
        nonlocal n
        expr = ca.vec(ca.SX(expr)) if not isinstance(expr, ca.MX) else ca.vec(expr)
        g.append(expr)
        lbg.append(np.ravel(lo))
        ubg.append(np.ravel(hi))
        blocks.setdefault(name, []).append(slice(n, n + expr.numel()))
        n += expr.numel()

    bnd = ca.Function("bnd", [pr.p], [ca.vertcat(*[c.lower for c in pr.path] or [ca.SX(0)]),
                                      ca.vertcat(*[c.upper for c in pr.path] or [ca.SX(0)])])
    plo, phi = (np.array(v, dtype=float).ravel() for v in bnd(pv))
    # Path constraints at the arc junctions and inside the arcs, not at t = 0 and
    # t = T: there the initial and terminal conditions rule, and a path bound
    # that duplicates one of them (v(T) <= 0 beside v(T) = 0) would make the
    # constraint Jacobian rank deficient. End-point values are checked after.
    for k in range(K):
        for j in range(interior_samples + 1):
            if j == 0 and k == 0:
                continue
            zj = z if j == 0 else propagate(k, z, tau[k] * j / (interior_samples + 1))
            if H is not None:
                add("path", H(zj[:nx], values[k], pv), plo, phi)
        z = propagate(k, z, tau[k])
    xT = z[:nx]
    T = ca.sum1(tau)
    if pr.initial:
        G0 = ca.Function("G0", [pr.x, pr.p], [ca.vertcat(*[c.expr for c in pr.initial])])
        b0 = ca.Function("b0", [pr.p], [ca.vertcat(*[c.lower for c in pr.initial]),
                                        ca.vertcat(*[c.upper for c in pr.initial])])
        lo, hi = (np.array(v, dtype=float).ravel() for v in b0(pv))
        add("initial", G0(x0, pv), lo, hi)
    if pr.terminal:
        GT = ca.Function("GT", [pr.x, pr.T, pr.p],
                         [ca.vertcat(*[c.expr for c in pr.terminal])])
        bT = ca.Function("bT", [pr.p], [ca.vertcat(*[c.lower for c in pr.terminal]),
                                        ca.vertcat(*[c.upper for c in pr.terminal])])
        lo, hi = (np.array(v, dtype=float).ravel() for v in bT(pv))
        add("terminal", GT(xT, T, pv), lo, hi)
    if not pr.time_free:
        add("final_time", T, pr.T_bounds[0], pr.T_bounds[0])
    mayer = ca.Function("phi", [pr.x, pr.T, pr.p], [pr.mayer])
    J = mayer(xT, T, pv) + (z[nx] if z.numel() > nx else 0)
    w = ca.vertcat(tau, x0)
    nlp = {"x": w, "f": J, "g": ca.vertcat(*g)}
    opts = {"ipopt": {**REFINE_IPOPT, **(ipopt_options or {})}, "print_time": False,
            "error_on_fail": False}
    solver = ca.nlpsol("refine", "ipopt", nlp, opts)
    lbw = np.r_[np.zeros(K), -np.inf * np.ones(nx)]
    ubw = np.r_[np.full(K, T_max), np.inf * np.ones(nx)]
    w0 = np.r_[np.maximum(durs, 1e-6), sol.x[0]]
    t0 = time.perf_counter()
    res = solver(x0=w0, lbx=lbw, ubx=ubw, lbg=np.concatenate(lbg), ubg=np.concatenate(ubg))
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    wopt = np.array(res["x"]).ravel()
    out_fn = ca.Function("out", [w], [xT, T])
    xT_v, T_v = (np.array(v, dtype=float).ravel() for v in out_fn(wopt))
    end_violation = 0.0
    if H is not None:
        for xe, ue in ((wopt[K:], values[0]), (xT_v, values[-1])):
            hv = np.array(H(xe, ue, pv), dtype=float).ravel()
            end_violation = max(end_violation, float(np.max(np.r_[plo - hv, hv - phi, 0.0])))
    result = RefinedSwitching(
        problem=pr, params=dict(sol.params), control=st.control, kinds=kinds, values=values,
        durations=wopt[:K], T=float(T_v[0]), objective=float(res["f"]), x0=wopt[K:],
        xT=xT_v, exact=exact, status=str(stats["return_status"]),
        iterations=int(stats["iter_count"]), solve_time=elapsed,
        transcribed_objective=sol.objective, lam_g=np.array(res["lam_g"]).ravel(),
        blocks=blocks, end_path_violation=end_violation)
    if not stats["success"]:
        cls = InfeasibleError if "Infeasible" in result.status else SolveError
        raise cls(result.status, result, f"switching-time refinement failed: {result.status}")
    return result
