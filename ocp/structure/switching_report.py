"""What a switching-time NLP reports at a point (:class:`SwitchingReport`, a base of
:class:`~ocp.structure.refinement.SwitchingNLP`): end state, time and objective, the
junction states, the exact arcs' step sizes and the integration's accuracy, the times of the
constraint rows and the states sampled inside an interval."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from .flows import THETA_MAX, ArcDynamics, numeric_affine_flow, numeric_rk8_flow
from .intervals import rk8_of

__all__ = ["SwitchingReport"]


class SwitchingReport:
    """Reports of a switching-time NLP at a point ``w = [durations, x0]`` (see the module);
    the attributes declared here are set by :class:`~ocp.structure.refinement.SwitchingNLP`'s
    build."""

    problem: OptimalControlProblem
    dyns: list[ArcDynamics]
    exact: tuple[bool, ...]
    substeps: tuple[int, ...]
    samples: int
    K: int
    n_g: int
    row_where: np.ndarray
    out_fn: ca.Function
    _nlp: dict[str, Any]

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
