"""Structure-aware re-solve: Newton's method on a square active set, compiled once.

Once a switching-time NLP (:class:`ocp.structure.refinement.SwitchingNLP`) has been
solved, its active set usually survives a small change of the parameters (the
next velocity of a sweep, a continuation step). When that set is *square* (as
many active constraints and bounds as unknowns, the rule for time-optimal
bang-bang problems) the new solution is the root of the active rows, and the
optimisation is a root-finding problem.

:class:`ActiveSetNewton` builds, once per active set, a CasADi ``rootfinder``
(plugin ``newton``) on those rows, with the parameters and the values of the
active bounds as its parameters, and one function returning everything the
acceptance checks read (all rows, the active rows' Jacobian, the objective and
its gradient). A re-solve is then two CasADi calls, against a couple of dozen
for a Newton loop written in Python over the NLP's full KKT function.

Nothing here decides whether a root is the answer: the caller
(:meth:`ocp.structure.refinement.SwitchingNLP.newton`) checks the inactive constraints,
the bounds and the multipliers' signs, and falls back to Ipopt when any check
fails.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from ..transcriptions.solver_output import solver_output

RESIDUAL_TOL = 1e-14
"""Root accepted when every active row is within this of its limit, relative to
``max(1, |limit|)``, or once a Newton step is below it (rounding level)."""

MAX_ITER = 12
"""Newton steps allowed per start."""


class ActiveSetNewton:
    """Newton's method on the active rows of a switching-time NLP, built once.

    Parameters
    ----------
    nlp_dict : dict
        The NLP (``x``, ``p``, ``f``, ``g`` as CasADi SX).
    bounds_fn : casadi.Function
        ``p -> (lbg, ubg)``.
    rows, side : ndarray of int
        Active constraint rows and their sides (-1 lower, +1 upper, 0 equality).
    cols : ndarray of int
        Active variable bounds (their values are passed to :meth:`solve`).
    extra : casadi.Function, optional
        ``(w, p) -> ...`` evaluated in the same call as the checks (what the caller
        reports of a solution), returned by :meth:`check` after them.

    Attributes
    ----------
    free : ndarray of int
        The unknowns Newton moves (every variable not held at a bound).
    """

    def __init__(self, nlp_dict: dict[str, Any], bounds_fn: ca.Function, rows: np.ndarray,
                 side: np.ndarray, cols: np.ndarray, extra: ca.Function | None = None) -> None:
        w, p, g, f = (nlp_dict[k] for k in ("x", "p", "g", "f"))
        n_w = w.numel()
        self.rows, self.cols = np.asarray(rows, dtype=int), np.asarray(cols, dtype=int)
        self.free = np.setdiff1d(np.arange(n_w), self.cols)
        w_free = ca.SX.sym("w_free", len(self.free))
        w_held = ca.SX.sym("w_held", len(self.cols))
        parts: list[ca.SX] = [ca.SX(0, 1)] * n_w
        for k, i in enumerate(self.free):
            parts[int(i)] = w_free[k]
        for k, i in enumerate(self.cols):
            parts[int(i)] = w_held[k]
        w_full = ca.vertcat(*parts)
        lo, hi = bounds_fn(p)
        target = ca.vertcat(*[hi[int(r)] if s > 0 else lo[int(r)]
                              for r, s in zip(self.rows, side, strict=True)])
        g_act = ca.vertcat(*[g[int(r)] for r in self.rows])
        # relative residual: the same yardstick as the Python loop it replaces
        resid = ca.substitute((g_act - target) / ca.fmax(1, ca.fabs(target)), w, w_full)
        residual = ca.Function("active_rows", [w_free, ca.vertcat(p, w_held)], [resid])
        self.rootfinder = ca.rootfinder(
            "active_set_newton", "newton", residual,
            {"abstol": RESIDUAL_TOL, "abstolStep": RESIDUAL_TOL, "max_iter": MAX_ITER,
             "error_on_fail": False})
        more = list(extra(w, p)) if extra is not None else []
        self.check_fn = ca.Function("active_set_check", [w, p],
                                    [g, ca.jacobian(g_act, w), ca.gradient(f, w), f, *more])

    def solve(self, pv: np.ndarray, w0: np.ndarray,
              held: np.ndarray) -> tuple[np.ndarray, int] | None:
        """Root of the active rows from ``w0``, or None if Newton did not converge.

        Parameters
        ----------
        pv : ndarray
            Parameter values.
        w0 : ndarray
            Starting point (the free entries are used).
        held : ndarray
            Values of the active variable bounds, in the order of ``cols``.

        Returns
        -------
        (ndarray, int) or None
            The full decision vector and the Newton steps taken.
        """
        with solver_output():  # a trial point's NaN: logged, not printed
            z = self.rootfinder(np.asarray(w0, dtype=float)[self.free], np.r_[pv, held])
        st = self.rootfinder.stats()
        if not st["success"]:
            return None
        w = np.empty(len(self.free) + len(self.cols))
        w[self.free] = np.asarray(z, dtype=float).ravel()
        w[self.cols] = held
        if not np.all(np.isfinite(w)):
            return None
        return w, int(st["iter_count"])

    def check(self, w: np.ndarray, pv: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                            np.ndarray, float, list]:
        """All rows ``g``, the active rows' Jacobian, ``grad f``, ``f`` and the ``extra``
        outputs (CasADi DM) at ``w``.

        Parameters
        ----------
        w : ndarray
            The refinement NLP's variables.
        pv : ndarray
            Parameter values, in the problem's order.
        """
        g, Jg, gJ, f, *more = self.check_fn.call([w, pv])
        return (g.full().ravel(), np.asarray(ca.DM(Jg).full()), gJ.full().ravel(),
                float(f), more)
