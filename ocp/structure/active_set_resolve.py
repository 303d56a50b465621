"""The structure-aware fast path of a switching-time NLP (:class:`ActiveSetResolve`, a base
of :class:`~ocp.structure.refinement.SwitchingNLP`): a re-solve by Newton's method on the
last Ipopt solution's active set where it is square, accepted only when every other
constraint, every bound and the multipliers' signs check."""

from __future__ import annotations

import time
from typing import Any

import casadi as ca
import numpy as np

from .active_set_newton import ActiveSetNewton
from .switching_report import SwitchingReport

__all__ = ["ActiveSetResolve", "KKT_PRIMAL"]

KKT_PRIMAL = 1e-12
"""Relative primal violation accepted by the KKT checks (the Newton path's and
:func:`~ocp.structure.refinement.kkt_converged`'s)."""


class ActiveSetResolve(SwitchingReport):
    """Newton re-solves on an active set (see the module); the attributes declared here are
    set by :class:`~ocp.structure.refinement.SwitchingNLP`."""

    n_w: int
    n_solves: int
    last: dict[str, Any]
    kkt_fn: ca.Function
    bounds_fn: ca.Function

    def bounds(self, pv: np.ndarray) -> dict[str, np.ndarray]:
        """Numeric ``lbx, ubx, lbg, ubg`` at parameters ``pv`` (the NLP's: overridden).

        Parameters
        ----------
        pv : ndarray
            Parameter values, in the problem's order.
        """
        raise NotImplementedError

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
        if solver is None:
            return None
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
                         cols: np.ndarray) -> ActiveSetNewton | None:
        """The :class:`ActiveSetNewton` of an active set, built on first use; None when
        CasADi refuses to build it (a structurally singular Jacobian of the active rows, as
        a circle's end condition against its multiplier gives): Ipopt then re-solves."""
        cache = self.__dict__.setdefault("_newton_cache", {})
        key = (rows.tobytes(), side.tobytes(), cols.tobytes())
        if key not in cache:
            try:
                cache[key] = ActiveSetNewton(self._nlp, self.bounds_fn, rows, side, cols,
                                             self._report_fn())
            except RuntimeError:  # CasADi's "structurally rank-deficient" and the like
                cache[key] = None
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
