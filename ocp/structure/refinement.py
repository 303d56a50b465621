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
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.blas import default_blas_threads
from ..transcriptions.solver_output import solver_output
from .active_set_resolve import KKT_PRIMAL, ActiveSetResolve
from .derived_times import refuse_shifted_time
from .flows import has_running_cost
from .intervals import (
    DEFAULT_TOL,
    ConstraintBlocks,
    Modes,
    arc_dynamics,
    build_intervals,
    check_control_set,
    forget_arc_dynamics,
    interval_flow,
    required_substeps,
    rk8_of,
)

# the intervals' names, importable from here as before the split
__all__ = ["DEFAULT_TOL", "KKT_DUAL", "KKT_MACHINE", "KKT_PRIMAL", "NEAR_CONVERGED",
           "REFINE_IPOPT", "ConstraintBlocks", "Modes", "SwitchingNLP", "arc_dynamics",
           "build_intervals", "cached_nlps", "check_control_set", "clear_cache",
           "converged_status", "interval_flow", "kkt_converged", "refuse_shifted_time",
           "required_substeps", "rk8_of", "solved_nlp", "switching_nlp"]

REFINE_IPOPT: dict[str, Any] = {
    "tol": 1e-14, "acceptable_tol": 1e-12, "constr_viol_tol": 1e-13, "max_iter": 200,
    "print_level": 0, "sb": "yes", "bound_relax_factor": 0.0, "nlp_scaling_method": "none"}
"""Ipopt options of the refinement (overridable per call)."""

NEAR_CONVERGED = ("Search_Direction_Becomes_Too_Small", "Solved_To_Acceptable_Level")
"""Ipopt statuses accepted when our own KKT check passes (rounding-level stalls)."""

KKT_DUAL = 1e-8
"""Relative dual residual accepted by that check (with the primal violation below
:data:`KKT_PRIMAL`)."""

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


class SwitchingNLP(ActiveSetResolve):
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
        refuse_shifted_time(problem)
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
        # time runs from 0 here (refuse_shifted_time): T is the sum of the durations, and a
        # duration's bounds (free_duration, fixed_duration) are T's
        lo, hi = pr.duration if pr.duration is not None else pr.T_bounds
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


_NLP_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()



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
    else:
        _NLP_CACHE.pop(problem, None)
    forget_arc_dynamics(problem)


def _freeze(d: dict | None) -> tuple:
    return tuple(sorted((k, repr(v)) for k, v in (d or {}).items()))
