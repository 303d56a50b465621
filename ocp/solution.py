"""The result of a transcribed solve: trajectories, multipliers, solver figures."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np


def along(fn: ca.Function, *args) -> list[np.ndarray]:
    """Evaluate ``fn`` at n samples in one mapped call.

    Each argument is an (n, k) array of per-sample rows or a single vector
    broadcast to every sample. Returns one (n, m) array per output.
    """
    n = max(np.atleast_2d(a).shape[0] if np.ndim(a) == 2 else 1 for a in args)
    cols = [np.asarray(a, dtype=float).T if np.ndim(a) == 2 else np.asarray(a, dtype=float)
            for a in args]
    out = fn.map(n)(*cols)
    out = out if isinstance(out, tuple | list) else [out]
    return [np.array(o, dtype=float).T.reshape(n, -1) for o in out]


class Solution:
    """A solved (or failed) multiple-shooting NLP, scipy-``OptimizeResult``-like.

    Attributes
    ----------
    t : (N+1,) node times; ``x`` : (N+1, nx) node states; ``u`` : (N, nu)
        piecewise-constant controls; ``T`` : final time; ``fun``/``objective``.
    success, status, message, iterations, solve_time
        Ipopt's outcome: ``status`` is its return status string.
    w, lam_x, lam_g : the raw primal vector and multipliers. CasADi's
        Lagrangian is ``f + lam_g^T g + lam_x^T w``.
    multipliers : dict
        ``lam_g`` split by constraint block: ``continuity`` (N, nx), ``path``
        (N+1, n_path), ``initial``, ``terminal``.
    params : dict of the parameter values solved for.
    """

    def __init__(self, **kw: Any) -> None:
        self.__dict__.update(kw)

    # python-control / scipy style aliases
    @property
    def fun(self) -> float:
        return self.objective

    @property
    def message(self) -> str:
        return self.status

    @classmethod
    def from_nlp(cls, tr, params: dict, res: dict, stats: dict, elapsed: float) -> Solution:
        pr, N, lay = tr.problem, tr.N, tr.layout
        w = np.array(res["x"]).ravel()
        lam_g = np.array(res["lam_g"]).ravel()
        T = float(w[lay.iT]) if lay.iT is not None else pr.T_bounds[0]
        X = w[lay.iX].reshape(N + 1, pr.nx)
        U = w[lay.iU].reshape(N, pr.nu)
        mult = {}
        for name, sl in lay.blocks.items():
            m = lam_g[sl]
            if name == "continuity":
                m = m.reshape(N, pr.nx)
            elif name == "path":
                m = m.reshape(N + 1, len(pr.path))
            mult[name] = m
        return cls(
            problem=pr, transcription=tr, N=N, t=np.linspace(0, T, N + 1), x=X, u=U, T=T,
            objective=float(res["f"]), w=w, lam_x=np.array(res["lam_x"]).ravel(), lam_g=lam_g,
            multipliers=mult, success=bool(stats["success"]),
            status=str(stats["return_status"]), iterations=int(stats["iter_count"]),
            solve_time=elapsed, params=dict(params),
        )

    # ------------------------------------------------------------------ access
    def state(self, name: str) -> np.ndarray:
        return self.x[:, self.problem.state_names.index(name)]

    def control(self, name: str) -> np.ndarray:
        return self.u[:, self.problem.control_names.index(name)]

    def sample(self, n: int = 1000, substeps: int = 8) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
        """Trajectory on ``n`` points: re-integrated from each node with the
        dynamics (RK4, ``substeps`` per sub-interval), control held constant.

        Returns ``t`` (n,), ``x`` (n, nx), ``u`` (n, nu).
        """
        from .transcription import rk4_function

        pr = self.problem
        F = rk4_function(pr.dynamics_function(), pr.lagrange_function(), pr.nx, pr.nu, pr.np,
                         substeps)
        pv = np.array([self.params[k] for k in pr.param_names])
        t = np.linspace(0.0, self.T, n)
        h = self.T / self.N
        k = np.minimum((t / h).astype(int), self.N - 1) if h > 0 else np.zeros(n, int)
        xs, _ = along(F, self.x[k], self.u[k], (t - k * h)[:, None], pv)
        return t, xs, self.u[k]

    def evaluate(self, expr: ca.SX) -> np.ndarray:
        """An expression of (x, u, p) at every node (the last node uses the last control)."""
        pr = self.problem
        fn = ca.Function("e", [pr.x, pr.u, pr.p], [expr])
        pv = np.array([self.params[k] for k in pr.param_names])
        return along(fn, self.x, np.vstack([self.u, self.u[-1:]]), pv)[0].ravel()

    def to_dict(self) -> dict[str, Any]:
        """Plain, JSON-able dict."""
        pr = self.problem

        def clean(v):
            return v if math.isfinite(v) else None

        return {
            "status": self.status, "success": self.success, "iterations": self.iterations,
            "solve_time_s": self.solve_time, "objective": clean(self.objective), "T": self.T,
            "params": self.params, "t": self.t.tolist(),
            "states": {n: self.x[:, i].tolist() for i, n in enumerate(pr.state_names)},
            "controls": {n: self.u[:, i].tolist() for i, n in enumerate(pr.control_names)},
        }

    def plot(self, fig=None):
        """States and controls against time (one axis each); returns the figure."""
        import matplotlib.pyplot as plt

        pr = self.problem
        n = pr.nx + pr.nu
        if fig is None:
            fig, axes = plt.subplots(n, 1, sharex=True, figsize=(7, 1.6 * n + 1))
        else:
            axes = fig.subplots(n, 1, sharex=True)
        axes = np.atleast_1d(axes)
        for i, name in enumerate(pr.state_names):
            axes[i].plot(self.t, self.x[:, i], ".-")
            axes[i].set_ylabel(name)
        for j, name in enumerate(pr.control_names):
            ax = axes[pr.nx + j]
            ax.step(self.t, np.r_[self.u[:, j], self.u[-1, j]], where="post")
            ax.set_ylabel(name)
        axes[-1].set_xlabel("time")
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        return (f"Solution(status={self.status!r}, objective={self.objective:.10g}, "
                f"T={self.T:.6g}, iterations={self.iterations})")
