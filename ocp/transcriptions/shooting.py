"""Multiple shooting of one phase: N intervals, piecewise-constant control.

Block of ``w``: ``[T?, X (nx, N+1), U (nu, N), t0?]`` (the final time first and
the states node by node, as before multi-phase support, so a single-phase
problem's decision vector is unchanged). The interval function (RK4 or
CVODES) is mapped over the N intervals with ``Function.map``: derivatives of
a map are maps of the small function's derivatives, so building the Hessian
stays cheap and no Python loop runs per interval.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..definition.compiled import CompiledPhase
from ..definition.multiphase import PhaseTimes
from .discretization import (
    PhaseData,
    PhaseDiscretization,
    PhaseLayout,
    PhaseNLP,
    linear_guess,
    static_vector,
)
from .integrators import cvodes_interval, rk4_interval


class ShootingPhase(PhaseDiscretization):
    """Multiple shooting of one phase.

    Parameters
    ----------
    cp : CompiledPhase
        The phase's functions.
    times : PhaseTimes
        How its times enter the NLP.
    nodes : int
        Shooting intervals N.
    integrator : {"rk4", "cvodes"}
        Interval integrator.
    substeps : int
        RK4 steps per interval (also the inner points for ``inner``).
    inner : bool
        Also impose the path constraints and state bounds at the integrator's
        inner steps (``substeps - 1`` points inside every interval).
    """

    method = "multiple_shooting"

    def __init__(self, cp: CompiledPhase, times: PhaseTimes, nodes: int, integrator: str,
                 substeps: int, inner: bool) -> None:
        super().__init__(cp, times)
        self.N, self.M, self.inner = nodes, substeps, inner
        self.integrator = integrator
        self.F = (rk4_interval(cp.ode, substeps) if integrator == "rk4"
                  else cvodes_interval(cp.ode, substeps))
        nx, nu, N = cp.nx, cp.nu, nodes
        self.iX = slice(self.nT, self.nT + nx * (N + 1))
        self.iU = slice(self.iX.stop, self.iX.stop + nu * N)
        self.it0 = self.iU.stop
        self._samplers: dict[tuple[int, int], ca.Function] = {}
        self._rk: dict[int, ca.Function] = {}

    def size(self) -> int:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.size`."""
        return self.it0 + self.nt0

    def layout(self, offset: int) -> PhaseLayout:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.layout`."""
        return PhaseLayout(offset if self.nT else None,
                           slice(offset + self.iX.start, offset + self.iX.stop),
                           slice(offset + self.iU.start, offset + self.iU.stop),
                           offset + self.it0 if self.nt0 else None)

    def build(self, wb: ca.MX, P: ca.MX, V: ca.MX, ends: tuple[ca.SX, ca.SX],
              ug: ca.SX) -> PhaseNLP:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.build`."""
        cp, N, nx, nu = self.cp, self.N, self.cp.nx, self.cp.nu
        t0, T = self._times(wb, self.it0)
        X = ca.reshape(wb[self.iX], nx, N + 1)
        U = ca.reshape(wb[self.iU], nu, N)
        s = static_vector(P, V, t0, T)
        tau = np.linspace(0.0, 1.0, N + 1)
        tn = t0 + (T - t0) * ca.DM(tau).T
        h = (T - t0) / N
        Xn, Q, Xs = self.F.map(N)(X[:, :N], U, tn[:, :N], ca.repmat(h, 1, N),
                                  ca.repmat(s, 1, N))
        zeros = ca.SX.zeros(nx * N)
        # F(X_k, U_k) - X_{k+1} = 0; see ocp.certificate.certify for what its multipliers mean
        cons = [("continuity", Xn - X[:, 1:], zeros, zeros)]
        hlo, hhi, xlo, xhi, ulo, uhi, clo, chi = cp.bounds(cp.phase.p)
        if cp.npath:
            Ucl = ca.horzcat(U, U[:, N - 1])  # the last node sees the last control
            H = cp.path.map(N + 1)(tn, X, Ucl, ca.repmat(s, 1, N + 1))
            cons.append(("path", H, ca.repmat(hlo, N + 1, 1), ca.repmat(hhi, N + 1, 1)))
        if self.inner and cp.ncheck and self.M > 1:
            cons.append(self._inner(tn[:, :N], h, U, Xs, s, clo, chi))
        lbT, ubT, gT, lbt0, ubt0, gt0 = self._time_bounds()
        lbw = ca.vertcat(*lbT, ca.repmat(xlo, N + 1, 1), ca.repmat(ulo, N, 1), *lbt0)
        ubw = ca.vertcat(*ubT, ca.repmat(xhi, N + 1, 1), ca.repmat(uhi, N, 1), *ubt0)
        w0 = ca.vertcat(*gT, ca.vec(linear_guess(ends[0], ends[1], tau)),
                        ca.repmat(ug, N, 1), *gt0)
        return PhaseNLP(t0, T, X[:, 0], U[:, 0], X[:, N], U[:, N - 1], ca.sum2(Q[1:, :]),
                        ca.sum2(Q[0, :]), cons, lbw, ubw, w0)

    def _inner(self, tk: ca.MX, h: ca.MX, U: ca.MX, Xs: ca.MX, s: ca.MX, clo: ca.SX,
               chi: ca.SX) -> tuple[str, ca.MX, ca.SX, ca.SX]:
        """Path constraints and state bounds at the inner RK steps of every interval."""
        N, M = self.N, self.M
        n = N * (M - 1)
        frac = ca.DM(np.arange(1, M) / M)
        tin = ca.reshape(ca.repmat(tk, M - 1, 1) + ca.repmat(frac * h, 1, N), 1, n)
        Urep = ca.kron(U, ca.DM.ones(1, M - 1)) if self.cp.nu else ca.MX(0, n)
        C = self.cp.check.map(n)(tin, Xs, Urep, ca.repmat(s, 1, n))
        return "path_inner", C, ca.repmat(clo, n, 1), ca.repmat(chi, n, 1)

    def unpack(self, wb: np.ndarray, pv: np.ndarray, vv: np.ndarray) -> PhaseData:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.unpack`."""
        nx, nu, N = self.cp.nx, self.cp.nu, self.N
        t0, T = self._unpack_times(wb, self.it0)
        X = wb[self.iX].reshape(N + 1, nx)
        U = wb[self.iU].reshape(N, nu)
        mesh = t0 + (T - t0) * np.linspace(0.0, 1.0, N + 1)
        return PhaseData(t0, T, mesh, X, U, np.vstack([U, U[-1:]]), mesh,
                         np.r_[pv, vv, t0, T])

    def sampler(self, substeps: int, n: int) -> ca.Function:
        """RK4 re-integration from a node, mapped over ``n`` samples (cached).

        Parameters
        ----------
        substeps : int
            RK4 steps per sample.
        n : int
            Number of samples.
        """
        key = (substeps, n)
        if key not in self._samplers:
            if substeps not in self._rk:
                self._rk[substeps] = rk4_interval(self.cp.ode, substeps)
            self._samplers[key] = self._rk[substeps].map(n)
        return self._samplers[key]

    def interpolate(self, data: PhaseData, k: np.ndarray, theta: np.ndarray,
                    substeps: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.interpolate`:
        the dynamics integrated from node ``k`` (RK4, ``substeps`` steps) over the
        fraction ``theta`` of its interval with the interval's constant control."""
        k = np.asarray(k, dtype=int)
        n = k.size
        h = np.diff(data.mesh)[k] * np.asarray(theta, dtype=float)
        xs = self.sampler(substeps, n)(data.x[k].T, data.u[k].T, data.mesh[k][None, :],
                                       h[None, :], data.s)[0]
        return np.array(xs, dtype=float).T.reshape(n, -1), data.u[k]

    def guess_from(self, sample: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                   t0: float, T: float) -> np.ndarray:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.guess_from`."""
        mesh = t0 + (T - t0) * np.linspace(0.0, 1.0, self.N + 1)
        x, _ = sample(mesh)
        _, u = sample((mesh[:-1] + mesh[1:]) / 2)
        parts: list[Any] = [[T]] if self.nT else []
        parts += [x.ravel(), u.ravel()]
        parts += [[t0]] if self.nt0 else []
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def multipliers(self, lam: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.multipliers`."""
        out = dict(lam)
        shapes = {"continuity": (self.N, self.cp.nx), "path": (self.N + 1, self.cp.npath),
                  "path_inner": (self.N * (self.M - 1), self.cp.ncheck)}
        for k, shp in shapes.items():
            if k in out:
                out[k] = out[k].reshape(shp)
        return out
