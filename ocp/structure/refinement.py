"""Switching-time refinement: the induced optimisation problem over arc durations.

Given an arc structure (:mod:`ocp.structure.arcs`) the unknowns are the durations of
the intervals between consecutive switch events of any control, plus the
initial state; on each interval every control is at a bound or, on a boundary
arc, follows the control law that keeps its path constraint at the limit
(:class:`ocp.structure.flows.ArcDynamics`). Entering a boundary arc imposes the entry
conditions ``c = limit, c' = 0, ...``; path constraints are imposed at the
arc junctions and at sample points inside every arc (not at ``t = 0`` and
``t = T``, where the initial and terminal conditions rule, nor where a
boundary arc holds the constraint by construction).

Each interval is integrated

* **exactly** when its closed loop and running cost are affine in the state:
  ``m`` sub-steps of a degree-18 Taylor polynomial of the matrix exponential
  of ``M(p) tau / m`` (``||A|| tau / m <= 1``: accurate to rounding), a CasADi
  expression of the parameters and the duration;
* otherwise by ``n`` fixed steps of an explicit 8th-order Runge-Kutta method,
  ``n`` chosen from the requested accuracy ``tol`` and verified by halving at
  the solution (re-solved with more steps if the check fails; never silently
  looser). Fixed steps make the NLP a smooth function of the durations, so
  Ipopt converges to its tight tolerance (an adaptive integrator's output is
  not smooth at that level).

The NLP is **built once** per (problem, interval modes, sub-steps) and cached
(:func:`switching_nlp`): the problem's parameters are NLP parameters, so a new
parameter value re-solves the same object. A structure-aware fast path
(:meth:`SwitchingNLP.newton`) re-solves a *square* active set (as many active
constraints as unknowns, as in time-optimal bang-bang problems) by Newton's
method and checks the inactive constraints and multiplier signs, falling back
to Ipopt when a check fails.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..definition.symbols import INF, constant
from ..transcriptions.blas import default_blas_threads
from ..transcriptions.solver_output import solver_output
from .active_set_newton import ActiveSetNewton
from .constraint_kinds import control_constraints
from .control_set import violated_control_constraint
from .flows import (
    THETA_MAX,
    ArcDynamics,
    Mode,
    expm_taylor,
    has_running_cost,
    numeric_affine_flow,
    numeric_rk8_flow,
    rk8_step,
    rk8_step_function,
    rk8_steps_for,
)

REFINE_IPOPT: dict[str, Any] = {
    "tol": 1e-14, "acceptable_tol": 1e-12, "constr_viol_tol": 1e-13, "max_iter": 200,
    "print_level": 0, "sb": "yes", "bound_relax_factor": 0.0, "nlp_scaling_method": "none"}
"""Ipopt options of the refinement (overridable per call)."""

NEAR_CONVERGED = ("Search_Direction_Becomes_Too_Small", "Solved_To_Acceptable_Level")
"""Ipopt statuses accepted when our own KKT check passes (rounding-level stalls)."""

KKT_PRIMAL, KKT_DUAL = 1e-12, 1e-8
"""Relative primal violation and dual residual accepted by that check."""

KKT_MACHINE = 1e-10
"""Dual and complementarity residuals below which any Ipopt ending is a converged point
(with the primal violation below :data:`KKT_PRIMAL`): rounding level for these NLPs."""


def kkt_converged(res: dict[str, Any]) -> bool:
    """Whether a solve's result is a KKT point to rounding, whatever Ipopt's last message.

    A rounding-level stall (:data:`NEAR_CONVERGED`) needs the primal violation below
    :data:`KKT_PRIMAL` and the dual and complementarity residuals below :data:`KKT_DUAL`;
    any other ending needs them below :data:`KKT_MACHINE`. Non-finite residuals never pass.

    Parameters
    ----------
    res : dict
        With ``status``, ``primal``, ``dual`` and ``complementarity`` (as returned by
        :meth:`SwitchingNLP.solve`).
    """
    primal, dual = float(res["primal"]), float(res["dual"])
    comp = float(res.get("complementarity", 0.0))
    if not all(np.isfinite([primal, dual, comp])):
        return False
    limit = KKT_DUAL if res["status"] in NEAR_CONVERGED else KKT_MACHINE
    return primal <= KKT_PRIMAL and dual <= limit and comp <= limit


def converged_status(res: dict[str, Any]) -> str:
    """The status text of a result :func:`kkt_converged` accepted, naming Ipopt's message.

    Parameters
    ----------
    res : dict
        As for :func:`kkt_converged`.
    """
    r = max(float(res["primal"]), float(res["dual"]), float(res.get("complementarity", 0.0)))
    return f"Solve_Succeeded (KKT residual {r:.0e}; Ipopt said {res['status']})"


DEFAULT_TOL = 1e-12
"""Requested relative accuracy of the non-affine arcs' end states (RK8 steps)."""

Modes = tuple[tuple[Mode, ...], ...]

_DYN_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_NLP_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def arc_dynamics(problem: OptimalControlProblem, modes: tuple[Mode, ...]) -> ArcDynamics:
    """The :class:`~ocp.structure.flows.ArcDynamics` of ``modes``, built once per problem
    and cached.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of Mode
        One per control.

    Returns
    -------
    ArcDynamics
    """
    per = _DYN_CACHE.setdefault(problem, {})
    if modes not in per:
        per[modes] = ArcDynamics(problem, modes)
    return per[modes]


class _Rk8:
    """RK8 step function and its ``mapaccum`` variants of one arc mode (cached)."""

    def __init__(self, dyn: ArcDynamics) -> None:
        self.step = rk8_step_function(dyn.f_z, dyn.nz, dyn.problem.np)


def rk8_of(dyn: ArcDynamics) -> ca.Function:
    """The RK8 step function ``(z, h, p) -> z_next`` of an arc mode (cached on it).

    Parameters
    ----------
    dyn : ArcDynamics
        The arc mode.
    """
    if not hasattr(dyn, "_rk8"):
        dyn._rk8 = _Rk8(dyn)  # type: ignore[attr-defined]
    return dyn._rk8.step  # type: ignore[attr-defined]


@dataclass
class ConstraintBlocks:
    """Constraint rows of a switching-time NLP, by block name.

    Built row block by row block (entry conditions, path samples, law bounds, end
    points, linkage) by :class:`SwitchingNLP` and the multi-phase
    :class:`~ocp.structure.phase_refinement.PhaseSwitchingNLP`; the block names let the
    multipliers be read back (e.g. the path rows' for the costate jumps).

    Attributes
    ----------
    exprs, lower, upper : list of casadi.SX
        Per added block: the rows (a column) and their bounds.
    index : dict of str to list of int
        Row numbers of each block name.
    times : list of (int, int)
        Per row: (interval, sample) where it is imposed.
    n : int
        Number of rows so far.
    """

    exprs: list = field(default_factory=list)
    lower: list = field(default_factory=list)
    upper: list = field(default_factory=list)
    index: dict[str, list[int]] = field(default_factory=dict)
    times: list[tuple[int, int]] = field(default_factory=list)  # (interval, sample) per row
    n: int = 0

    def add(self, name: str, expr: ca.SX, lo: Any, hi: Any, where: tuple[int, int]) -> None:
        """Append the rows ``lo <= expr <= hi`` under block ``name``.

        Parameters
        ----------
        name : str
            Block name (rows of one name need not be contiguous).
        expr : casadi.SX
            The rows (any shape; flattened); nothing is added when empty.
        lo, hi : casadi.SX or float
            Bounds, one per row or one for all.
        where : (int, int)
            (interval, sample) of these rows.
        """
        expr = ca.vec(ca.SX(expr))
        k = expr.numel()
        if k == 0:
            return
        self.exprs.append(expr)
        for store, v in ((self.lower, ca.SX(lo)), (self.upper, ca.SX(hi))):
            store.append(ca.vec(v) if v.numel() == k else ca.repmat(v, k, 1))
        self.index.setdefault(name, []).extend(range(self.n, self.n + k))
        self.times.extend([where] * k)
        self.n += k

    def substitute(self, first: int, old: ca.SX, new: ca.SX) -> None:
        """Replace the symbols ``old`` by ``new`` in the rows and bounds of the blocks added
        from the ``first``-th on (e.g. a derived phase's parameters by the problem's).

        Parameters
        ----------
        first : int
            Index of the first block (``len(exprs)`` before adding them).
        old, new : casadi.SX
            Symbols and what replaces them.
        """
        for store in (self.exprs, self.lower, self.upper):
            store[first:] = [ca.substitute(e, old, new) for e in store[first:]]


class SwitchingNLP:
    """The switching-time NLP of one problem and interval structure, built once.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    substeps : tuple of int
        Per interval: exact sub-steps ``m`` (affine arcs) or RK8 steps ``n``.
    samples : int
        Path constraints are imposed at about this many points inside each arc.
    ipopt_options : dict, optional
        Overrides of :data:`REFINE_IPOPT`.

    Attributes
    ----------
    build_time : float
        Seconds spent building (symbolic graph and Ipopt instance).
    n_solves : int
        How many times it was solved.
    """

    solver_name = "refine"  # (CasADi's name of the Ipopt instance)

    def __init__(self, problem: OptimalControlProblem, modes: Modes, substeps: tuple[int, ...],
                 samples: int = 16, ipopt_options: dict | None = None) -> None:
        t0 = time.perf_counter()
        self.problem, self.modes, self.substeps = problem, tuple(modes), tuple(substeps)
        self.samples = int(samples)
        self.dyns = [arc_dynamics(problem, m) for m in self.modes]
        self.exact = tuple(d.exact for d in self.dyns)
        self.K = len(self.modes)
        self.has_quad = has_running_cost(problem)
        self._build()
        # a trial step outside the arcs' domain evaluates to NaN and Ipopt backtracks: normal,
        # so CasADi's per-evaluation warnings are off (a failed solve reports its status)
        self._opts: dict[str, Any] = {"ipopt": {**REFINE_IPOPT, **(ipopt_options or {})},
                                      "print_time": False, "error_on_fail": False,
                                      "show_eval_warnings": False}
        self._solver: Any = None  # Ipopt, built on first use (the Newton path needs none)
        self.build_time = time.perf_counter() - t0
        self.n_solves = 0

    @property
    def solver(self) -> Any:
        """Ipopt on the refinement NLP, built on first use (its time added to
        :attr:`build_time`): a structure that the active-set Newton re-solves never pays
        for the Hessian's derivation."""
        if self._solver is None:
            t0 = time.perf_counter()
            default_blas_threads()
            self._solver = ca.nlpsol(self.solver_name, "ipopt", self._nlp, self._opts)
            self.build_time += time.perf_counter() - t0
        return self._solver

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        pr, K = self.problem, self.K
        nx = pr.nx
        p, tau, x0 = pr.p, ca.SX.sym("tau", K), ca.SX.sym("x0", nx)
        z = ca.vertcat(x0, 0) if self.has_quad else x0
        G = ConstraintBlocks()
        self.entry_names: list[str] = []
        z, ends = build_intervals(G, pr, self.dyns, self.substeps, self.samples, tau, z, p,
                                  self.entry_names)
        self._finish(G, p, tau, x0, z, ends)

    def _finish(self, G: ConstraintBlocks, p: ca.SX, tau: ca.SX, x0: ca.SX, z: ca.SX,
                ends: list[ca.SX]) -> None:
        pr = self.problem
        nx = pr.nx
        xT, T = z[:nx], ca.sum1(tau)
        K = self.K
        if pr.initial:
            G0 = ca.vertcat(*[c.expr for c in pr.initial])
            G.add("initial", ca.substitute(G0, pr.x, x0),
                  ca.vertcat(*[c.lower for c in pr.initial]),
                  ca.vertcat(*[c.upper for c in pr.initial]), (0, 0))
        if pr.terminal:
            GT = ca.substitute(ca.vertcat(*[c.expr for c in pr.terminal]),
                               ca.vertcat(pr.x, pr.T), ca.vertcat(xT, T))
            G.add("terminal", GT, ca.vertcat(*[c.lower for c in pr.terminal]),
                  ca.vertcat(*[c.upper for c in pr.terminal]), (K - 1, -1))
        lo, hi = pr.T_bounds
        G.add("final_time", T, lo, hi, (K - 1, -1))
        J = ca.substitute(ca.SX(pr.mayer), ca.vertcat(pr.x, pr.T), ca.vertcat(xT, T))
        if self.has_quad:
            J = J + z[nx]
        w = ca.vertcat(tau, x0)
        g = ca.vertcat(*G.exprs)
        self._nlp = {"x": w, "p": p, "f": J, "g": g}
        self.blocks = {k: np.array(v, dtype=int) for k, v in G.index.items()}
        self.row_where = np.array(G.times, dtype=int).reshape(-1, 2)
        self.n_g, self.n_w = G.n, K + nx
        self.bounds_fn = ca.Function("bounds", [p], [ca.vertcat(*G.lower), ca.vertcat(*G.upper)])
        self.out_fn = ca.Function("out", [w, p], [xT, T, J, ca.horzcat(*ends)])
        self.kkt_fn = ca.Function("kkt", [w, p], [g, ca.jacobian(g, w), ca.gradient(J, w)])
        self.T_max = hi

    # ------------------------------------------------------------------ solve
    def bounds(self, pv: np.ndarray) -> dict[str, np.ndarray]:
        """Numeric ``lbx, ubx, lbg, ubg`` at parameters ``pv`` (read-only arrays; the
        last parameter values' bounds are remembered).

        Parameters
        ----------
        pv : ndarray
            Parameter values, in the problem's order.
        """
        key = np.asarray(pv, dtype=float).tobytes()
        memo = self.__dict__.get("_bounds_memo")
        if memo is None or memo[0] != key:
            out = self._bounds(pv)
            for v in out.values():
                v.setflags(write=False)
            memo = self._bounds_memo = (key, out)
        return memo[1]

    def _bounds(self, pv: np.ndarray) -> dict[str, np.ndarray]:
        lbg, ubg = (v.full().ravel() for v in self.bounds_fn(pv))
        if "_box" not in self.__dict__:  # durations in [0, T_max], states free
            nx = self.problem.nx
            self._box = (np.r_[np.zeros(self.K), -np.inf * np.ones(nx)],
                         np.r_[np.full(self.K, self.T_max), np.inf * np.ones(nx)])
        return {"lbx": self._box[0], "ubx": self._box[1], "lbg": lbg, "ubg": ubg}

    def solve(self, pv: np.ndarray, w0: np.ndarray, lam_g0: np.ndarray | None = None,
              lam_x0: np.ndarray | None = None) -> dict[str, Any]:
        """Solve by Ipopt.

        Parameters
        ----------
        pv : ndarray
            Parameter values.
        w0 : ndarray
            Starting point ``[durations, x0]``.
        lam_g0, lam_x0 : ndarray, optional
            Starting multipliers (a warm start).

        Returns
        -------
        dict
            ``w``, ``f``, ``lam_g``, ``lam_x``, ``status``, ``success``,
            ``iterations``, ``time``, ``path`` (``"ipopt"``), ``primal`` and
            ``dual`` (the KKT residuals of :meth:`kkt`), ``complementarity``
            (:meth:`complementarity`) and ``ipopt_status`` (Ipopt's own word).
            Whatever Ipopt's last message, the result counts as converged when
            :func:`kkt_converged` says the point is a KKT point to rounding;
            ``status`` then reads e.g. ``"Solve_Succeeded (KKT residual 3e-15;
            Ipopt said Search_Direction_Becomes_Too_Small)"``.
        """
        args: dict[str, Any] = {"p": pv, "x0": w0, **self.bounds(pv)}
        n_eq = int(np.sum(args["lbg"] == args["ubg"]))
        if n_eq > int(np.sum(args["lbx"] < args["ubx"])):
            # more equalities than free variables (a structure that no longer fits): what
            # Ipopt would answer at once, without building it (nor CasADi's warning)
            return self._not_solved(np.asarray(w0, dtype=float), pv,
                                    "Not_Enough_Degrees_Of_Freedom")
        if lam_g0 is not None and np.size(lam_g0) == self.solver.nnz_in("lam_g0"):
            # (multipliers of an NLP rebuilt with more RK8 steps have another size: cold)
            args.update(lam_g0=lam_g0, lam_x0=lam_x0)
        t0 = time.perf_counter()
        with solver_output():  # CasADi's messages: logged, not printed
            res = self.solver(**args)
        elapsed = time.perf_counter() - t0
        st = self.solver.stats()
        self.n_solves += 1
        out: dict[str, Any] = {"w": np.array(res["x"], dtype=float).ravel(), "f": float(res["f"]),
               "lam_g": np.array(res["lam_g"], dtype=float).ravel(),
               "lam_x": np.array(res["lam_x"], dtype=float).ravel(),
               "status": str(st["return_status"]), "success": bool(st["success"]),
               "iterations": int(st["iter_count"]), "time": elapsed, "path": "ipopt"}
        out["primal"], out["dual"] = self.kkt(out["w"], out["lam_g"], out["lam_x"], pv)
        out["complementarity"] = self.complementarity(out["w"], out["lam_g"], out["lam_x"], pv)
        out["ipopt_status"] = out["status"]
        if out["status"] != "Solve_Succeeded" and kkt_converged(out):
            # Ipopt stopped on a message, but the point is a KKT point to rounding: say so
            out["success"] = True
            out["status"] = converged_status(out)
        if out["success"]:
            self.last = {"w": out["w"], "lam_g": out["lam_g"], "lam_x": out["lam_x"],
                         "pv": np.array(pv, dtype=float)}
        return out

    def _not_solved(self, w: np.ndarray, pv: np.ndarray, status: str) -> dict[str, Any]:
        """The result of a solve Ipopt would refuse (``status``), at the start ``w``."""
        out: dict[str, Any] = {
            "w": w.copy(), "f": math.nan, "lam_g": np.zeros(self.n_g),
            "lam_x": np.zeros(self.n_w), "status": status, "success": False, "iterations": 0,
            "time": 0.0, "path": "ipopt", "ipopt_status": status}
        out["primal"], out["dual"] = self.kkt(out["w"], out["lam_g"], out["lam_x"], pv)
        out["complementarity"] = self.complementarity(out["w"], out["lam_g"], out["lam_x"], pv)
        return out

    def kkt(self, w: np.ndarray, lam_g: np.ndarray, lam_x: np.ndarray,
            pv: np.ndarray) -> tuple[float, float]:
        """Primal violation and dual residual of a KKT point, each relative.

        Parameters
        ----------
        w, lam_g, lam_x : ndarray
            Primal point and multipliers (CasADi's signs).
        pv : ndarray
            Parameter values.

        Returns
        -------
        (float, float)
            Largest bound or constraint violation over ``max(1, |g|)``, and
            ``||grad J + Jg^T lam_g + lam_x||_inf`` over ``max(1, ||grad J||_inf)``.
        """
        b = self.bounds(pv)
        g, Jg, gJ = self.kkt_fn(w, pv)
        g = np.array(g, dtype=float).ravel()
        Jg = np.array(ca.DM(Jg), dtype=float)
        gJ = np.array(gJ, dtype=float).ravel()
        sc = np.maximum(1.0, np.abs(g))
        viol = np.r_[(b["lbg"] - g) / sc, (g - b["ubg"]) / sc, b["lbx"] - w, w - b["ubx"], 0.0]
        dual = gJ + Jg.T @ lam_g + lam_x
        return (float(np.max(viol)),
                float(np.max(np.abs(dual), initial=0.0) / max(1.0, np.max(np.abs(gJ)))))

    def complementarity(self, w: np.ndarray, lam_g: np.ndarray, lam_x: np.ndarray,
                        pv: np.ndarray) -> float:
        """Largest complementarity or multiplier-sign violation, relative.

        With CasADi's signs a positive multiplier belongs to an active upper
        bound and a negative one to an active lower bound: each multiplier times
        its row's distance to the bound it claims (infinite: the multiplier's own
        size) must vanish.

        Parameters
        ----------
        w, lam_g, lam_x : ndarray
            Primal point and multipliers (CasADi's signs).
        pv : ndarray
            Parameter values.

        Returns
        -------
        float
            ``max |lam| * slack / max(1, |value|)`` over ``max(1, max |lam|)``.
        """
        b = self.bounds(pv)
        g = np.array(self.kkt_fn(w, pv)[0], dtype=float).ravel()
        worst = 0.0
        for val, lam, lo, hi in ((g, lam_g, b["lbg"], b["ubg"]), (w, lam_x, b["lbx"], b["ubx"])):
            with np.errstate(invalid="ignore"):
                slack = np.where(lam > 0, hi - val, val - lo)
            slack = np.where(np.isfinite(slack), np.abs(slack) / np.maximum(1.0, np.abs(val)),
                             1.0)
            worst = max(worst, float(np.max(np.abs(lam) * slack, initial=0.0)))
        scale = max(1.0, float(np.max(np.abs(np.r_[lam_g, lam_x]), initial=0.0)))
        return worst / scale

    def outputs(self, w: np.ndarray, pv: np.ndarray) -> tuple[np.ndarray, float, float,
                                                             np.ndarray]:
        """Final state, final time, objective and junction states at a point.

        Parameters
        ----------
        w : ndarray
            ``[durations, x0]``.
        pv : ndarray
            Parameter values.

        Returns
        -------
        xT : ndarray (nx,)
        T, J : float
        Z : ndarray (K+1, nz)
        """
        xT, T, J, Z = self.out_fn(w, pv)
        return (np.array(xT, dtype=float).ravel(), float(T), float(J),
                np.array(Z, dtype=float).T)

    def active_set(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """Active rows and variable bounds of the last Ipopt solution, with their sides.

        Returns ``(rows, row_side, cols, col_side)``; side -1 lower, +1 upper, 0 equality.
        A constraint is active when its multiplier exceeds ``1e-9`` of the largest one.
        """
        last = getattr(self, "last", None)
        if last is None:
            return None
        if "active" in last:
            return last["active"]
        b = self.bounds(last["pv"])
        lam_g, lam_x = last["lam_g"], last["lam_x"]
        big = max(1.0, float(np.max(np.abs(np.r_[lam_g, lam_x]), initial=0.0)))
        eq = b["lbg"] == b["ubg"]
        act_g = eq | (np.abs(lam_g) > 1e-9 * big)
        act_x = np.abs(lam_x) > 1e-9 * big
        rows = np.flatnonzero(act_g)
        cols = np.flatnonzero(act_x)
        last["active"] = (rows, np.where(eq[rows], 0, np.sign(lam_g[rows])).astype(int), cols,
                          np.sign(lam_x[cols]).astype(int))
        return last["active"]

    def newton(self, pv: np.ndarray, w0: np.ndarray, max_iter: int = 12) -> dict[str, Any] | None:
        """Re-solve by Newton's method on the last solution's active set, if it is square.

        The active constraints (and active variable bounds) of the last Ipopt
        solution are solved as equations at the new parameters, from ``w0``
        and then from the last solution, by a CasADi rootfinder compiled once
        per active set (:class:`ocp.structure.active_set_newton.ActiveSetNewton`; a
        Python Newton loop over the KKT function is the second chance). The
        result is accepted only if every other constraint and every bound
        holds (to :data:`KKT_PRIMAL`), the multipliers from
        ``J_A^T mu = -grad J`` have the signs their sides demand, and the
        iteration converged to rounding level.

        Parameters
        ----------
        pv : ndarray
            New parameter values.
        w0 : ndarray
            Starting point ``[durations, x0]``.
        max_iter : int
            Newton steps allowed per start (Python loop).

        Returns
        -------
        dict or None
            As :meth:`solve` (``path = "newton"``), or None when the active set
            is not square or any check fails (the caller then runs Ipopt).
        """
        act = self.active_set()
        if act is None:
            return None
        rows, side, cols, cside = act
        if len(rows) + len(cols) != self.n_w:
            return None
        t0 = time.perf_counter()
        b = self.bounds(pv)
        held = np.where(cside > 0, b["ubx"][cols], b["lbx"][cols])
        solver = self._compiled_newton(rows, side, cols)
        target = np.where(side > 0, b["ubg"][rows], b["lbg"][rows])
        for start in (w0, self.last["w"]):
            found = solver.solve(pv, start, held)
            if found is None:  # second chance: the Python loop (other stopping rule)
                w = np.array(start, dtype=float)
                w[cols] = held
                it = self._newton_iterate(w, pv, rows, target, cols, max_iter)
                found = (w, it) if it else None
            if found is not None:
                out = self._newton_result(solver, b, found[0], pv, side, cside, found[1],
                                          time.perf_counter() - t0)
                if out is not None:
                    return out
        return None

    def _compiled_newton(self, rows: np.ndarray, side: np.ndarray,
                         cols: np.ndarray) -> ActiveSetNewton:
        """The :class:`ActiveSetNewton` of an active set, built on first use."""
        cache = self.__dict__.setdefault("_newton_cache", {})
        key = (rows.tobytes(), side.tobytes(), cols.tobytes())
        if key not in cache:
            cache[key] = ActiveSetNewton(self._nlp, self.bounds_fn, rows, side, cols,
                                         self._report_fn())
        return cache[key]

    def _newton_iterate(self, w: np.ndarray, pv: np.ndarray, rows: np.ndarray,
                        target: np.ndarray, cols: np.ndarray, max_iter: int) -> int:
        """Newton steps on ``g_rows(w) = target`` (in place); iterations used, 0 on failure.

        Converged when the residual is at rounding level: below 1e-14 relative,
        or below 1e-12 once a step no longer changes w beyond 1e-14 relative.
        """
        free = np.setdiff1d(np.arange(self.n_w), cols)
        for it in range(1, max_iter + 1):
            g, Jg, _ = (np.array(ca.DM(v), dtype=float) for v in self.kkt_fn(w, pv))
            r = g.ravel()[rows] - target
            res = float(np.max(np.abs(r) / np.maximum(1.0, np.abs(target)), initial=0.0))
            if not np.isfinite(res):
                return 0
            if res <= 1e-14:
                return it
            try:
                step = np.linalg.solve(Jg[np.ix_(rows, free)], r)
            except np.linalg.LinAlgError:
                return 0
            w[free] -= step
            if res <= 1e-12 and np.max(np.abs(step) / np.maximum(1.0, np.abs(w[free]))) <= 1e-14:
                return it
        return 0

    def _newton_result(self, solver: ActiveSetNewton, b: dict[str, np.ndarray], w: np.ndarray,
                       pv: np.ndarray, side: np.ndarray, cside: np.ndarray, it: int,
                       elapsed: float) -> dict[str, Any] | None:
        """Multipliers and the acceptance checks of :meth:`newton` (one CasADi call)."""
        rows, cols = solver.rows, solver.cols
        g, Jr, gJ, f, more = solver.check(w, pv)
        if more:  # what the result reports, evaluated in the same call
            self._summary_memo = (self._summary_key(w, pv), self._decode_summary(more))
        if not np.all(np.isfinite(g)):  # (a NaN would pass the test below)
            return None
        sc = np.maximum(1.0, np.abs(g))
        viol = np.r_[(b["lbg"] - g) / sc, (g - b["ubg"]) / sc, 0.0]
        if np.max(viol) > KKT_PRIMAL:
            return None
        if np.any(w < b["lbx"]) or np.any(w > b["ubx"]):
            return None  # e.g. a negative duration: the structure no longer fits
        A = np.vstack([Jr, np.eye(self.n_w)[cols]])
        try:
            mu = np.linalg.solve(A.T, -gJ)
        except np.linalg.LinAlgError:
            return None
        sides = np.r_[side, cside]
        scale = max(1.0, float(np.max(np.abs(mu))))
        if np.any((sides != 0) & (sides * mu < -1e-9 * scale)):
            return None  # a multiplier with the wrong sign: the active set changed
        lam_g = np.zeros(self.n_g)
        lam_g[rows] = mu[:len(rows)]
        lam_x = np.zeros(self.n_w)
        lam_x[cols] = mu[len(rows):]
        # the KKT residuals of :meth:`kkt`, from the same numbers (lam_g is zero off the rows)
        dual = gJ + Jr.T @ mu[:len(rows)] + lam_x
        primal = float(max(np.max(viol), np.max(np.r_[b["lbx"] - w, w - b["ubx"]])))
        self.n_solves += 1
        return {"w": w, "f": f, "lam_g": lam_g, "lam_x": lam_x,
                "status": "Solve_Succeeded", "success": True, "iterations": it,
                "time": elapsed, "path": "newton", "primal": primal,
                "dual": float(np.max(np.abs(dual), initial=0.0) / max(1.0, np.max(np.abs(gJ))))}

    # ----------------------------------------------------------- verification
    def accuracy(self, w: np.ndarray, pv: np.ndarray, tol: float) -> tuple[bool, float,
                                                                          list[int]]:
        """Check every interval's integration at the solution ``w``.

        Exact intervals need ``||A|| tau / m <= THETA_MAX``; RK8 intervals are
        integrated with ``n`` and ``2 n`` steps from the same start state and
        must agree to ``tol`` (relative).

        Parameters
        ----------
        w : ndarray
            ``[durations, x0]``.
        pv : ndarray
            Parameter values.
        tol : float
            Required relative accuracy of the RK8 intervals' end states.

        Returns
        -------
        (bool, float, list of int)
            All good; the worst RK8 error estimate; the intervals that fail.
        """
        theta = self.summary(w, pv)["theta"]
        bad = [k for k in range(self.K) if self.exact[k] and theta[k] > THETA_MAX]
        worst = 0.0
        if all(self.exact):
            return not bad, worst, bad
        _, _, _, Z = self.outputs(w, pv)
        for k, d in enumerate(self.dyns):
            tau, m = float(w[k]), self.substeps[k]
            if d.exact:
                continue
            step = rk8_of(d)
            a = numeric_rk8_flow(step, Z[k], tau, m, pv)[-1]
            b = numeric_rk8_flow(step, Z[k], tau, 2 * m, pv)[-1]
            with np.errstate(invalid="ignore"):
                err = float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b)))))
            err = err if math.isfinite(err) else math.inf  # a non-finite flow is no accuracy
            worst = max(worst, err)
            if not err <= tol:
                bad.append(k)
        return not bad, worst, bad

    def summary(self, w: np.ndarray, pv: np.ndarray) -> dict[str, Any]:
        """What a result reports at ``w``, from one call of a function built once.

        Parameters
        ----------
        w : ndarray
            ``[durations, x0]``.
        pv : ndarray
            Parameter values.

        Returns
        -------
        dict
            ``xT``, ``T``, ``J``; ``theta`` (``||A||_1 tau / m`` per interval, 0 on
            RK8 intervals); ``control_bounds`` (``(lower, upper)`` per control);
            ``end_violation`` (largest path-constraint violation at ``t = 0`` and
            ``t = T``, where the boundary conditions rule and the NLP imposes no
            path row, with the first and last arcs' control laws).
        """
        key = self._summary_key(w, pv)
        memo = self.__dict__.get("_summary_memo")
        if memo is not None and memo[0] == key:
            return memo[1]
        out = self._decode_summary(self._report_fn().call([w, pv]))  # type: ignore[union-attr]
        self._summary_memo = (key, out)
        return out

    @staticmethod
    def _summary_key(w: np.ndarray, pv: np.ndarray) -> tuple[bytes, bytes]:
        return (np.asarray(w, dtype=float).tobytes(), np.asarray(pv, dtype=float).tobytes())

    def _decode_summary(self, values: list) -> dict[str, Any]:
        xT, T, J, theta, cb, viol = values
        cb = cb.full().ravel()
        return {"xT": xT.full().ravel(), "T": float(T), "J": float(J),
                "theta": theta.full().ravel(),
                "control_bounds": [(float(cb[2 * j]), float(cb[2 * j + 1]))
                                   for j in range(self.problem.nu)],
                "end_violation": float(viol)}

    def _report_fn(self) -> ca.Function | None:
        """The function behind :meth:`summary` (None where it does not apply)."""
        return self.__dict__.get("_summary_fn") or self._build_summary()

    def _build_summary(self) -> ca.Function:
        pr, K = self.problem, self.K
        w, p = self._nlp["x"], self._nlp["p"]
        xT, T, J, _ = self.out_fn(w, p)
        theta = [ca.mmax(ca.sum1(ca.fabs(d.A_fn(p)[0]))) * w[k] / self.substeps[k]
                 if d.exact else ca.SX(0) for k, d in enumerate(self.dyns)]
        cb = ca.vertcat(*[ca.vertcat(*pr.control_limits[n]) for n in pr.control_names])
        # limits that move with a state (a decision variable refined as a constant state,
        # ocp.structure.variables): their values at the start
        cb = ca.substitute(cb, pr.x, w[K:K + pr.nx])
        viol = ca.SX(0)
        if pr.structure_path:
            h = ca.vertcat(*[c.expr for c in pr.structure_path])
            lo, hi = (ca.vertcat(*[getattr(c, s) for c in pr.structure_path])
                      for s in ("lower", "upper"))
            for x, d in ((w[K:K + pr.nx], self.dyns[0]), (xT, self.dyns[-1])):
                he = ca.substitute(ca.substitute(h, pr.u, d.u), pr.x, x)
                viol = ca.fmax(viol, ca.mmax(ca.vertcat(lo - he, he - hi, 0)))
        fn = self._summary_fn = ca.Function("summary", [w, p], [xT, T, J, ca.vertcat(*theta),
                                                                 cb, viol])
        return fn

    def row_times(self, w: np.ndarray) -> np.ndarray:
        """Time of every constraint row at the solution ``w`` (samples, junctions, ends).

        Parameters
        ----------
        w : ndarray
            A solution of the refinement NLP.
        """
        edges = np.r_[0.0, np.cumsum(w[:self.K])]
        out = np.empty(self.n_g)
        for r, (k, j) in enumerate(self.row_where):
            if j < 0:
                out[r] = edges[k + 1]
            else:
                stride = max(1, self.substeps[k] // max(1, self.samples + 1))
                out[r] = edges[k] + w[k] * j * stride / self.substeps[k]
        return out

    def sample_interval(self, k: int, z0: np.ndarray, tau: float, pv: np.ndarray,
                        points: int) -> np.ndarray:
        """States at ``points + 1`` equally spaced times of interval k.

        Parameters
        ----------
        k : int
            Interval index.
        z0 : ndarray (nz,)
            State (and cost quadrature) at the interval's start.
        tau : float
            Its duration.
        pv : ndarray
            Parameter values.
        points : int
            Number of equal steps to report.

        Returns
        -------
        ndarray (points+1, nz)
        """
        d = self.dyns[k]
        if d.exact:
            A, b = d.affine_numeric(pv)
            return numeric_affine_flow(A, b, z0, tau, points)
        per = max(1, -(-self.substeps[k] // points))
        Z = numeric_rk8_flow(rk8_of(d), z0, tau, per * points, pv)
        return Z[::per]


def interval_flow(d: ArcDynamics, m: int, samples: int, z: ca.SX, tau: ca.SX,
                  p: ca.SX) -> tuple[list[ca.SX], ca.SX]:
    """Sample states (start and interior points) and the end state of one interval.

    Parameters
    ----------
    d : ArcDynamics
        The interval's closed-loop dynamics.
    m : int
        Exact sub-steps (affine arcs) or RK8 steps.
    samples : int
        About how many interior samples to return.
    z : SX
        State (and cost quadrature) at the interval's start.
    tau : SX
        Its duration.
    p : SX
        Parameters.
    """
    stride = max(1, m // max(1, samples + 1))
    out: list[ca.SX] = []
    if d.exact:
        A, b = d.A_fn(p)
        n = d.nz
        M = ca.vertcat(ca.horzcat(A, b), ca.SX.zeros(1, n + 1))
        E = expm_taylor(M * (tau / m))
        zz = ca.vertcat(z, 1)
        for j in range(m):
            if j % stride == 0:
                out.append(zz[:n])
            zz = ca.mtimes(E, zz)
        return out, zz[:n]
    h = tau / m
    for j in range(m):
        if j % stride == 0:
            out.append(z)
        z = rk8_step(d.f_z, z, h, p)
    return out, z


def build_intervals(G: ConstraintBlocks, pr: OptimalControlProblem, dyns: list[ArcDynamics],
                    substeps: tuple[int, ...], samples: int, tau: ca.SX, z: ca.SX, p: ca.SX,
                    entry_names: list[str], check_start: bool = False
                    ) -> tuple[ca.SX, list[ca.SX]]:
    """Flow one phase's intervals, adding entry, path and law-bound rows to ``G``.

    Path constraints are imposed at the samples of every interval but the phase's start
    (unless ``check_start``) and where a boundary arc holds them by construction.
    Control-only constraints are not rows: on an interval they are constants of the
    parameters (a row at its limit with no dependence on the unknowns would leave an
    interior-point method no slack); :func:`check_control_set` checks them instead.

    Parameters
    ----------
    G : ConstraintBlocks
        Constraint rows (appended to).
    pr : OptimalControlProblem
        The phase.
    dyns : list of ArcDynamics
        One per interval.
    substeps : tuple of int
        Per interval.
    samples : int
        Path-constraint samples per interval.
    tau : SX
        Interval durations.
    z : SX
        State (and cost quadrature) at the phase's start.
    p : SX
        Parameters.
    entry_names : list of str
        Receives the names of the entry conditions.
    check_start : bool
        Also impose the path constraints at the phase's start state.

    Returns
    -------
    (SX, list of SX)
        The end state and the junction states (start first).
    """
    nx = pr.nx
    names = [c.name for c in pr.structure_path]
    control_only = {c.name for c in control_constraints(pr)}
    hfn = ca.Function("h", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in pr.structure_path])]) \
        if pr.structure_path else None
    hlo = ca.vertcat(*[c.lower for c in pr.structure_path]) if pr.structure_path else ca.SX(0, 1)
    hhi = ca.vertcat(*[c.upper for c in pr.structure_path]) if pr.structure_path else ca.SX(0, 1)
    ends = [z]
    held_prev: tuple[str, ...] = ()
    for k, d in enumerate(dyns):
        _entry_rows(G, pr, k, d, z, held_prev, entry_names)
        pts, z_end = interval_flow(d, substeps[k], samples, z, tau[k], p)
        # constant controls meet the control-only constraints once for all
        # (check_control_set); a control following a boundary law may leave them
        settled = control_only if not ca.depends_on(d.u, pr.x) else set()
        for j, zj in enumerate(pts):
            if k == 0 and j == 0 and not check_start:
                continue
            skip = set(d.held) | settled | (set(held_prev) if j == 0 else set())
            keep = [i for i, n in enumerate(names) if n not in skip]
            if hfn is not None and keep:
                hv = hfn(zj[:nx], ca.substitute(d.u, pr.x, zj[:nx]), p)
                G.add("path", hv[keep], hlo[keep], hhi[keep], (k, j))
            _law_rows(G, pr, k, d, zj, j)
        _law_rows(G, pr, k, d, z_end, -1)
        z = z_end
        ends.append(z)
        held_prev = d.held
    return z, ends


def _entry_rows(G: ConstraintBlocks, pr: OptimalControlProblem, k: int, d: ArcDynamics, z: ca.SX,
                held_prev: tuple[str, ...], entry_names: list[str]) -> None:
    for (what, e), name in zip(d.entry, _entry_owners(d), strict=True):
        if name in held_prev:
            continue  # the boundary arc continues from the previous interval
        G.add("entry", ca.substitute(e, pr.x, z[:pr.nx]), 0, 0, (k, 0))
        entry_names.append(what)


def _law_rows(G: ConstraintBlocks, pr: OptimalControlProblem, k: int, d: ArcDynamics, z: ca.SX,
              j: int) -> None:
    for _, e, lo, hi in d.law_bounds:
        at = ca.substitute(e, pr.x, z[:pr.nx])
        if not ca.depends_on(ca.vertcat(lo, hi), pr.x):
            G.add("law", at, lo, hi, (k, j))
            continue
        # limits that move with a state (a decision variable refined as a constant state,
        # ocp.structure.variables): rows of the unknowns, one per finite side
        for b, low, high in ((lo, 0.0, INF), (hi, -INF, 0.0)):
            if constant(b) not in (-INF, INF):
                G.add("law", at - ca.substitute(b, pr.x, z[:pr.nx]), low, high, (k, j))


def _entry_owners(d: ArcDynamics) -> list[str]:
    """The held constraint each entry condition belongs to (they are listed in order)."""
    owners: list[str] = []
    for m in d.modes:
        if m.constraint is not None:
            owners.extend([m.constraint] * d.orders[m.constraint])
    return owners


def check_control_set(problem: OptimalControlProblem, modes: Modes, pv: np.ndarray,
                      tol: float = 1e-9) -> None:
    """Raise if an interval's controls violate a control-only path constraint.

    On an interval whose controls are all at bounds the control-only constraints
    (``u1 + u2 <= 1``) are numbers: a mode outside the control set (both ``u1``
    and ``u2`` at their upper bound) is no vertex of it.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    pv : ndarray
        Parameter values.
    tol : float
        Allowed violation, relative to ``max(1, |value|)``.

    Raises
    ------
    ValueError
        Naming the interval, its modes and the constraint.
    """
    if not control_constraints(problem):
        return
    for k, m in enumerate(modes):
        d = arc_dynamics(problem, m)
        if ca.depends_on(d.u, problem.x):
            continue  # a boundary law: the constraints are rows of the refinement NLP
        u = np.array(d.u_fn(np.zeros(problem.nx), pv), dtype=float).ravel()
        labels = [mm.label() for mm in m]
        bad = violated_control_constraint(problem, u, pv, tol)
        if bad is not None:
            raise ValueError(f"interval {k} ({labels}) violates the control-only constraint "
                             f"{bad!r}: not a vertex of the control set")
        for j, (name, mm) in enumerate(zip(problem.control_names, m, strict=True)):
            limits = ca.vertcat(*problem.control_limits[name])
            if ca.depends_on(limits, problem.x):
                continue  # a limit that moves with a (constant) state: a row of the NLP
            fb = ca.Function("b", [problem.p], [limits])
            blo, bhi = (float(b) for b in fb(pv).full().ravel())
            if mm.kind == "vertex" and not blo - tol <= u[j] <= bhi + tol:
                raise ValueError(f"interval {k} ({labels}): the vertex value {u[j]:.6g} of "
                                 f"{name!r} is outside its bounds [{blo:g}, {bhi:g}]")


def required_substeps(problem: OptimalControlProblem, modes: Modes, pv: np.ndarray,
                      durations: np.ndarray, x0: np.ndarray, samples: int, tol: float,
                      theta: float = 0.5) -> tuple[int, ...]:
    """Sub-steps per interval for a guess.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    pv : ndarray
        Parameter values.
    durations : ndarray
        Guessed interval lengths.
    x0 : ndarray
        Guessed initial state (propagated through the intervals).
    samples : int
        At least ``samples + 1`` sub-steps on exact intervals.
    tol : float
        Accuracy the RK8 intervals must meet (by halving).
    theta : float
        Exact intervals get ``||A|| tau / m <= theta``.

    Returns
    -------
    tuple of int
    """
    out = []
    z = np.r_[x0, 0.0] if has_running_cost(problem) else np.asarray(x0, dtype=float)
    for k, m in enumerate(modes):
        d = arc_dynamics(problem, m)
        tau = float(max(durations[k], 0.0))
        if d.exact:
            A, b = d.affine_numeric(pv)
            n = max(samples + 1, int(np.ceil(float(np.abs(A).sum(axis=0).max()) * tau / theta)))
            z = numeric_affine_flow(A, b, z, tau, n)[-1] if tau > 0 else z
        else:
            step = rk8_of(d)
            n, _ = rk8_steps_for(step, z, tau, pv, tol, minimum=max(4, (samples + 1) // 2))
            z = numeric_rk8_flow(step, z, tau, n, pv)[-1] if tau > 0 else z
        out.append(int(n))
    return tuple(out)


def switching_nlp(problem: OptimalControlProblem, modes: Modes, substeps: tuple[int, ...],
                  samples: int = 16, ipopt_options: dict | None = None) -> SwitchingNLP:
    """A cached :class:`SwitchingNLP` whose sub-steps are at least ``substeps``.

    The cache is keyed on the problem object (weakly), the modes, the samples
    and the Ipopt options; among the NLPs built for that key, the first whose
    every interval has at least the requested sub-steps (and at most four
    times as many) is reused, else a new one is built with ``substeps``.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
    substeps : tuple of int
        Sub-steps needed per interval (:func:`required_substeps`).
    samples : int
        Path-constraint samples per interval.
    ipopt_options : dict, optional
        Overrides of :data:`REFINE_IPOPT`.

    Returns
    -------
    SwitchingNLP
    """
    built = cached_nlps(problem, modes, samples, ipopt_options)
    for nlp in built:
        if all(a >= b for a, b in zip(nlp.substeps, substeps, strict=True)) and \
                all(a <= 4 * b for a, b in zip(nlp.substeps, substeps, strict=True)):
            return nlp
    nlp = SwitchingNLP(problem, modes, substeps, samples, ipopt_options)
    built.append(nlp)
    return nlp


def cached_nlps(problem: OptimalControlProblem, modes: Modes, samples: int = 16,
                ipopt_options: dict | None = None) -> list[SwitchingNLP]:
    """The cached NLPs of a structure, oldest first (the list itself: appending caches).

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    samples : int
        Path-constraint samples per interval.
    ipopt_options : dict, optional
        Overrides of :data:`REFINE_IPOPT` (part of the cache key).

    Returns
    -------
    list of SwitchingNLP
    """
    key = (tuple(modes), int(samples), _freeze(ipopt_options))
    return _NLP_CACHE.setdefault(problem, {}).setdefault(key, [])


def solved_nlp(problem: OptimalControlProblem, modes: tuple, samples: int,
               ipopt_options: dict | None) -> SwitchingNLP | None:
    """The most recently built cached NLP of this structure that Ipopt has solved, if any.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    samples : int
        Path-constraint samples per interval.
    ipopt_options : dict or None
        Overrides of :data:`REFINE_IPOPT` (part of the cache key).

    Returns
    -------
    SwitchingNLP or None
    """
    for nlp in reversed(cached_nlps(problem, modes, samples, ipopt_options)):
        if getattr(nlp, "last", None) is not None:
            return nlp
    return None


def clear_cache(problem: OptimalControlProblem | None = None) -> None:
    """Forget the cached refinement NLPs (of one problem, or all).

    Parameters
    ----------
    problem : OptimalControlProblem, optional
        Forget only this problem's NLPs (default: all).
    """
    if problem is None:
        _NLP_CACHE.clear()
        _DYN_CACHE.clear()
    else:
        _NLP_CACHE.pop(problem, None)
        _DYN_CACHE.pop(problem, None)


def _freeze(d: dict | None) -> tuple:
    return tuple(sorted((k, repr(v)) for k, v in (d or {}).items()))
