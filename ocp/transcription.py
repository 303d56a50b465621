"""Multiple-shooting transcription into a parametric NLP, built once, solved by Ipopt.

The NLP takes the problem's parameters as CasADi NLP parameters ``p`` and its
constraint bounds as functions of ``p`` evaluated at solve time, so a new
parameter value (or a continuation step) re-solves the same NLP object:
nothing is rebuilt. Ipopt gets exact sparse first and second derivatives from
CasADi's algorithmic differentiation; with the RK4 integrator the graph is
expanded to SX (scalar expressions), which is faster to evaluate.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .errors import InfeasibleError, SolveError
from .problem import OptimalControlProblem
from .solution import Solution

DEFAULT_IPOPT = {"tol": 1e-10, "max_iter": 3000, "print_level": 0, "sb": "yes",
                 "mu_strategy": "adaptive"}
INFEASIBLE_STATUSES = {"Infeasible_Problem_Detected", "Restoration_Failed"}


def rk4_function(f: ca.Function, L: ca.Function, nx: int, nu: int, np_: int,
                 substeps: int) -> ca.Function:
    """One shooting interval of length ``h`` by ``substeps`` RK4 steps; also integrates L."""
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", nu)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", np_)
    dt = h / substeps
    xk, q = x, ca.SX(0)
    for _ in range(substeps):
        k1, l1 = f(xk, u, p), L(xk, u, p)
        k2, l2 = f(xk + dt / 2 * k1, u, p), L(xk + dt / 2 * k1, u, p)
        k3, l3 = f(xk + dt / 2 * k2, u, p), L(xk + dt / 2 * k2, u, p)
        k4, l4 = f(xk + dt * k3, u, p), L(xk + dt * k3, u, p)
        xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q = q + dt / 6 * (l1 + 2 * l2 + 2 * l3 + l4)
    return ca.Function("F", [x, u, h, p], [xk, q], ["x", "u", "h", "p"], ["xf", "qf"])


def cvodes_function(f: ca.Function, L: ca.Function, nx: int, nu: int, np_: int,
                    tol: float = 1e-10) -> ca.Function:
    """One shooting interval by CVODES (BDF, for stiff variants), time scaled to [0, 1]."""
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", nu)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", np_)
    dae = {"x": x, "p": ca.vertcat(u, h, p), "ode": h * f(x, u, p), "quad": h * L(x, u, p)}
    integ = ca.integrator("I", "cvodes", dae, 0.0, 1.0, {"abstol": tol, "reltol": tol})
    xm, um, hm, pm = (ca.MX.sym(n, k) for n, k in (("x", nx), ("u", nu), ("h", 1), ("p", np_)))
    r = integ(x0=xm, p=ca.vertcat(um, hm, pm))
    return ca.Function("F", [xm, um, hm, pm], [r["xf"], r["qf"]],
                       ["x", "u", "h", "p"], ["xf", "qf"])


@dataclass
class _Layout:
    """Where things live in the decision vector w and the constraint vector g."""

    iT: int | None
    iX: slice
    iU: slice
    blocks: dict[str, slice]


class MultipleShooting:
    """Multiple-shooting transcription of an :class:`OptimalControlProblem`.

    Parameters
    ----------
    problem : OptimalControlProblem
    nodes : int
        Number of shooting intervals N (piecewise-constant control on each).
    integrator : {"rk4", "cvodes"}
        RK4 with ``substeps`` steps per interval, or CVODES (stiff problems).
    substeps : int
        RK4 steps per interval.
    ipopt_options : dict, optional
        Overrides of :data:`DEFAULT_IPOPT`.
    expand : bool
        Expand the NLP to SX scalar graphs (RK4 only): building takes longer
        (0.4 s instead of 0.02 s for the soft landing at N = 100) but every
        evaluation is ~5x faster, so re-solves are ~2x faster. Worth it for
        sweeps and continuation.

    Attributes
    ----------
    n_builds : int
        How many times the NLP was built (stays 1: re-solves never rebuild).
    """

    def __init__(self, problem: OptimalControlProblem, nodes: int = 50, integrator: str = "rk4",
                 substeps: int = 4, ipopt_options: dict | None = None,
                 expand: bool = False) -> None:
        problem.validate()
        if nodes < 1:
            raise ValueError("nodes must be >= 1")
        if integrator not in ("rk4", "cvodes"):
            raise ValueError("integrator must be 'rk4' or 'cvodes'")
        self.problem = problem
        self.N = int(nodes)
        self.integrator = integrator
        self.substeps = int(substeps)
        self.ipopt_options = {**DEFAULT_IPOPT, **(ipopt_options or {})}
        self.expand = bool(expand) and integrator == "rk4"
        self.n_builds = 0
        self._solvers: dict[bool, Any] = {}
        self._build()

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        pr, N = self.problem, self.N
        nx, nu, np_ = pr.nx, pr.nu, pr.np
        f, L = pr.dynamics_function(), pr.lagrange_function()
        if self.integrator == "rk4":
            self.F = rk4_function(f, L, nx, nu, np_, self.substeps)
        else:
            self.F = cvodes_function(f, L, nx, nu, np_)
        nT = 1 if pr.time_free else 0
        nw = nT + nx * (N + 1) + nu * N
        # An MX graph that maps the per-interval function (SX inside for RK4) over
        # the N intervals: derivatives of a map are maps of the small function's
        # derivatives, so building the Hessian stays cheap.
        Sym = ca.MX
        w = Sym.sym("w", nw)
        P = Sym.sym("p", np_)
        T = w[0] if pr.time_free else Sym(pr.T_bounds[0])
        X = ca.reshape(w[nT:nT + nx * (N + 1)], nx, N + 1)
        U = ca.reshape(w[nT + nx * (N + 1):], nu, N)
        h = T / N
        Xn, Q = self.F.map(N)(X[:, :N], U, ca.repmat(h, 1, N), ca.repmat(P, 1, N))

        xs, us, ps, Ts = pr.x, pr.u, pr.p, pr.T
        g, lbg, ubg, blocks = [], [], [], {}
        n = 0

        def add(name, expr, lo, hi):
            nonlocal n
            expr = ca.vec(expr)
            k = expr.numel()
            g.append(expr)
            lbg.append(lo)
            ubg.append(hi)
            blocks[name] = slice(n, n + k)
            n += k

        zeros = ca.SX.zeros(nx * N)
        # F(X_k, U_k) - X_{k+1} = 0; see ocp.pmp for what its multipliers mean
        add("continuity", Xn - X[:, 1:], zeros, zeros)
        if pr.path:
            H = ca.Function("H", [xs, us, ps], [ca.vertcat(*[c.expr for c in pr.path])])
            Ucl = ca.horzcat(U, U[:, N - 1])  # the last node sees the last control
            add("path", H.map(N + 1)(X, Ucl, ca.repmat(P, 1, N + 1)),
                ca.repmat(ca.vertcat(*[c.lower for c in pr.path]), N + 1, 1),
                ca.repmat(ca.vertcat(*[c.upper for c in pr.path]), N + 1, 1))
        if pr.initial:
            G0 = ca.Function("G0", [xs, ps], [ca.vertcat(*[c.expr for c in pr.initial])])
            add("initial", G0(X[:, 0], P), ca.vertcat(*[c.lower for c in pr.initial]),
                ca.vertcat(*[c.upper for c in pr.initial]))
        if pr.terminal:
            GT = ca.Function("GT", [xs, Ts, ps], [ca.vertcat(*[c.expr for c in pr.terminal])])
            add("terminal", GT(X[:, N], T, P), ca.vertcat(*[c.lower for c in pr.terminal]),
                ca.vertcat(*[c.upper for c in pr.terminal]))
        mayer = ca.Function("phi", [xs, Ts, ps], [pr.mayer])
        J = mayer(X[:, N], T, P) + ca.sum2(Q)

        # bounds on w as functions of the parameters
        lbu = ca.vertcat(*[pr.control_bounds[k][0] for k in pr.control_names])
        ubu = ca.vertcat(*[pr.control_bounds[k][1] for k in pr.control_names])
        inf = ca.SX.inf(nx * (N + 1))
        lbw = [ca.SX(pr.T_bounds[0])] if nT else []
        ubw = [ca.SX(pr.T_bounds[1])] if nT else []
        lbw += [-inf, ca.repmat(lbu, N, 1)]
        ubw += [inf, ca.repmat(ubu, N, 1)]
        self._bounds = ca.Function("bounds", [ps], [ca.vertcat(*lbw), ca.vertcat(*ubw),
                                                    ca.vertcat(*lbg), ca.vertcat(*ubg)])
        self._nlp = {"x": w, "p": P, "f": J, "g": ca.vertcat(*g)}
        self.layout = _Layout(0 if nT else None, slice(nT, nT + nx * (N + 1)),
                              slice(nT + nx * (N + 1), nw), blocks)
        self.n_w, self.n_g = nw, n
        self._mayer = mayer
        self.n_builds += 1

    def _solver(self, warm: bool):
        if warm not in self._solvers:
            ipopt = dict(self.ipopt_options)
            if warm:
                ipopt.update(warm_start_init_point="yes", warm_start_bound_push=1e-9,
                             warm_start_mult_bound_push=1e-9, mu_init=1e-6)
            opts = {"ipopt": ipopt, "print_time": False, "error_on_fail": False,
                    "expand": self.expand}
            self._solvers[warm] = ca.nlpsol(f"{self.problem.name}_ms", "ipopt", self._nlp, opts)
        return self._solvers[warm]

    # ------------------------------------------------------------------ solve
    def param_vector(self, params: dict[str, float]) -> np.ndarray:
        names = self.problem.param_names
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

    def initial_guess(self, T: float | None = None, x=None, u=None) -> np.ndarray:
        """Decision vector from a final time, states and controls.

        ``x``: array (N+1, nx), (nx,) or a function of normalised time in [0, 1];
        ``u``: array (N, nu), (nu,) or a function likewise.
        """
        pr, N = self.problem, self.N
        w = np.zeros(self.n_w)
        if self.layout.iT is not None:
            w[0] = pr.T_guess if T is None else T
        s = np.linspace(0, 1, N + 1)
        X = _fill(x, s, pr.nx)
        U = _fill(u, s[:-1], pr.nu)
        w[self.layout.iX] = X.ravel()
        w[self.layout.iU] = U.ravel()
        return w

    def solve(self, params: dict[str, float], guess: Solution | np.ndarray | None = None,
              warm_start: Solution | None = None) -> Solution:
        """Solve for the given parameter values.

        Parameters
        ----------
        params : dict
            A value for every declared parameter.
        guess : Solution or decision vector, optional
            Primal starting point (cold start). Default: :meth:`initial_guess`.
        warm_start : Solution, optional
            Start from this solution's primal and dual values (Ipopt warm start).

        Raises
        ------
        InfeasibleError, SolveError
            Carrying Ipopt's status and the last iterate.
        """
        pv = self.param_vector(params)
        lbw, ubw, lbg, ubg = (np.array(v, dtype=float).ravel() for v in self._bounds(pv))
        args = {"p": pv, "lbx": lbw, "ubx": ubw, "lbg": lbg, "ubg": ubg}
        if warm_start is not None:
            args.update(x0=warm_start.w, lam_x0=warm_start.lam_x, lam_g0=warm_start.lam_g)
        elif isinstance(guess, Solution):
            args["x0"] = guess.w
        elif guess is not None:
            args["x0"] = np.asarray(guess, dtype=float)
        else:
            args["x0"] = self.initial_guess()
        solver = self._solver(warm_start is not None)
        t0 = time.perf_counter()
        res = solver(**args)
        elapsed = time.perf_counter() - t0
        stats = solver.stats()
        sol = Solution.from_nlp(self, dict(zip(self.problem.param_names, pv, strict=True)),
                                res, stats, elapsed)
        if not sol.success:
            cls = InfeasibleError if sol.status in INFEASIBLE_STATUSES else SolveError
            raise cls(sol.status, sol, f"Ipopt failed: {sol.status} after {sol.iterations} "
                                       f"iterations")
        return sol


def _fill(spec, s: np.ndarray, n: int) -> np.ndarray:
    if spec is None:
        return np.zeros((len(s), n))
    if callable(spec):
        return np.array([np.ravel(spec(si)) for si in s], dtype=float).reshape(len(s), n)
    a = np.asarray(spec, dtype=float)
    if a.ndim == 1:
        return np.tile(a.reshape(1, n), (len(s), 1))
    if a.shape != (len(s), n):
        raise ValueError(f"guess has shape {a.shape}, expected {(len(s), n)}")
    return a


def continuation(transcription: MultipleShooting, params: dict[str, float], name: str,
                 values, guess: Solution | np.ndarray | None = None,
                 progress: bool = False) -> list[Solution]:
    """Solve along ``values`` of one parameter, each solve warm-started from the last.

    If a warm-started solve fails, it is retried once from the previous primal
    point only (a cold start), then the error is raised.
    """
    out: list[Solution] = []
    prev = guess if isinstance(guess, Solution) else None
    first_guess = guess
    it = values
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(values, desc=f"continuation in {name}", unit="solve")
    for v in it:
        pv = {**params, name: float(v)}
        if prev is None:
            sol = transcription.solve(pv, guess=first_guess)
        else:
            try:
                sol = transcription.solve(pv, warm_start=prev)
            except SolveError:
                sol = transcription.solve(pv, guess=prev)
        out.append(sol)
        prev = sol
    return out
