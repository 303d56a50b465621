"""Direct collocation of one phase on Legendre-Gauss-Radau points (as GPOPS-II, dymos' Radau).

On every mesh interval ``[t_k, t_k+1]`` of length ``h_k`` the state is a
polynomial of degree ``d`` through the interval's start ``X_k`` and ``d``
Radau points ``c_1 < ... < c_d = 1``, where the dynamics are collocated and
the control takes its values ``U_kj``: ``sum_r C_rj Z_kr = h_k f(Z_kj, U_kj,
t_kj)``. The last point is the interval end, so continuity reads
``X_k+1 = Z_kd``. The running cost and integrals use the Radau quadrature
(exact to degree 2d - 2). Path constraints are imposed at every collocation
point; state bounds at every state point. Radau IIA collocation has order
``2d - 1`` at the mesh points.

Block of ``w``: ``[T?, X (nx, N+1), U (nu, N d), t0?, Z (nx, N d)]``. One
interval function is mapped over the N intervals.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
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
    lagrange_basis,
    linear_guess,
    segment_index,
    static_vector,
)


def radau_points(d: int) -> np.ndarray:
    """The ``d`` Legendre-Gauss-Radau points in (0, 1], the last being 1 (read-only,
    computed once per degree).

    Parameters
    ----------
    d : int
        Number of points (the degree).
    """
    return _radau_points(int(d))


@cache
def _radau_points(d: int) -> np.ndarray:
    return _frozen(np.array(ca.collocation_points(d, "radau"), dtype=float))


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def degree_matrices(d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`collocation_matrices` of the degree-``d`` Radau points, computed once per
    degree (read-only arrays: every mesh and every solve of that degree shares them).

    Parameters
    ----------
    d : int
        The degree.
    """
    return _degree_matrices(int(d))


@cache
def _degree_matrices(d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    C, D, B = collocation_matrices(radau_points(d))
    return _frozen(C), _frozen(D), _frozen(B)


def collocation_matrices(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Derivative matrix ``C`` (d+1, d), end weights ``D`` (d+1,), quadrature weights ``B`` (d,).

    ``C[r, j]`` is the derivative at ``c_j`` of the Lagrange polynomial of node
    ``r`` on ``[0, c_1..c_d]``; ``D[r]`` its value at 1; ``B[j]`` the integral
    over [0, 1] of the Lagrange polynomial of ``c_j`` on ``c_1..c_d``.

    Parameters
    ----------
    c : ndarray
        The collocation points in (0, 1].
    """
    nodes = np.r_[0.0, c]
    d = c.size
    C = np.zeros((d + 1, d))
    D = np.zeros(d + 1)
    for r in range(d + 1):
        poly = np.poly1d([1.0])
        for m in range(d + 1):
            if m != r:
                poly *= np.poly1d([1.0, -nodes[m]]) / (nodes[r] - nodes[m])
        C[r] = np.polyder(poly)(c)
        D[r] = poly(1.0)
    B = np.zeros(d)
    for j in range(d):
        poly = np.poly1d([1.0])
        for m in range(d):
            if m != j:
                poly *= np.poly1d([1.0, -c[m]]) / (c[j] - c[m])
        B[j] = np.polyint(poly)(1.0)
    return C, D, B


class CollocationPhase(PhaseDiscretization):
    """Radau collocation of one phase on a (possibly non-uniform) mesh.

    Parameters
    ----------
    cp : CompiledPhase
        The phase's functions.
    times : PhaseTimes
        How its times enter the NLP.
    mesh : array_like
        Normalised mesh points, increasing from 0 to 1 (N + 1 of them).
    degree : int
        Collocation points per interval (polynomial degree of the state).
    functions : dict, optional
        Where the interval function is kept for other meshes of the same phase and
        degree (:attr:`ocp.transcriptions.nlp.GridFree.functions`).
    """

    method = "collocation"

    def __init__(self, cp: CompiledPhase, times: PhaseTimes, mesh: np.ndarray,
                 degree: int, functions: dict | None = None) -> None:
        super().__init__(cp, times)
        self.tau = np.asarray(mesh, dtype=float)
        self.N, self.d = self.tau.size - 1, degree
        self.c = radau_points(degree)
        self.C, self.D, self.B = degree_matrices(degree)
        self.u0_weights = lagrange_basis(self.c, np.zeros(1))[0] if degree > 1 \
            else np.ones(1)
        nx, nu, N, d = cp.nx, cp.nu, self.N, degree
        self.iX = slice(self.nT, self.nT + nx * (N + 1))
        self.iU = slice(self.iX.stop, self.iX.stop + nu * N * d)
        self.it0 = self.iU.stop
        self.iZ = slice(self.it0 + self.nt0, self.it0 + self.nt0 + nx * N * d)
        key = ("radau interval", cp, degree)
        functions = {} if functions is None else functions
        if key not in functions:
            functions[key] = self._interval_function()
        self.G = functions[key]
        # normalised times of the collocation points, interval by interval
        self.tau_c = (self.tau[:-1, None] + np.diff(self.tau)[:, None] * self.c[None, :]).ravel()
        self.tau_points = np.concatenate([[0.0], self.tau_c])  # every point, normalised
        self._check_bases: dict[int, tuple[np.ndarray, ...]] = {}

    def _interval_function(self) -> ca.Function:
        cp, d = self.cp, self.d
        xk, Z = ca.SX.sym("xk", cp.nx), ca.SX.sym("Z", cp.nx, d)
        U = ca.SX.sym("U", cp.nu, d)
        t, h, s = ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("s", cp.ns)
        Zf = ca.horzcat(xk, Z)
        defects, paths, q = [], [], ca.SX.zeros(cp.nq)
        for j in range(d):
            tj = t + self.c[j] * h
            f, qd = cp.ode(tj, Z[:, j], U[:, j], s)
            defects.append(ca.mtimes(Zf, ca.DM(self.C[:, j])) - h * f)
            q = q + self.B[j] * h * qd
            paths.append(cp.path(tj, Z[:, j], U[:, j], s))
        xend = ca.mtimes(Zf, ca.DM(self.D))
        return ca.Function("G", [xk, Z, U, t, h, s],
                           [ca.horzcat(*defects), xend, q, ca.horzcat(*paths)],
                           ["xk", "Z", "U", "t", "h", "s"], ["defect", "xend", "q", "path"])

    def size(self) -> int:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.size`."""
        return self.iZ.stop

    def layout(self, offset: int) -> PhaseLayout:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.layout`."""
        return PhaseLayout(offset if self.nT else None,
                           slice(offset + self.iX.start, offset + self.iX.stop),
                           slice(offset + self.iU.start, offset + self.iU.stop),
                           offset + self.it0 if self.nt0 else None,
                           slice(offset + self.iZ.start, offset + self.iZ.stop))

    def build(self, wb: ca.MX, P: ca.MX, V: ca.MX, ends: tuple[ca.SX, ca.SX],
              ug: ca.SX) -> PhaseNLP:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.build`."""
        cp, N, d, nx, nu = self.cp, self.N, self.d, self.cp.nx, self.cp.nu
        t0, T = self._times(wb, self.it0)
        X = ca.reshape(wb[self.iX], nx, N + 1)
        U = ca.reshape(wb[self.iU], nu, N * d)
        Z = ca.reshape(wb[self.iZ], nx, N * d)
        s = static_vector(P, V, t0, T)
        tk = t0 + (T - t0) * ca.DM(self.tau[:-1]).T
        hk = (T - t0) * ca.DM(np.diff(self.tau)).T
        defect, xend, Q, H = self.G.map(N)(X[:, :N], Z, U, tk, hk, ca.repmat(s, 1, N))
        hlo, hhi, xlo, xhi, ulo, uhi, _, _ = cp.bounds(cp.phase.p)
        zc, zx = ca.SX.zeros(nx * d * N), ca.SX.zeros(nx * N)
        cons = [("continuity", xend - X[:, 1:], zx, zx), ("collocation", defect, zc, zc)]
        if cp.npath:
            cons.append(("path", H, ca.repmat(hlo, N * d, 1), ca.repmat(hhi, N * d, 1)))
        lbT, ubT, gT, lbt0, ubt0, gt0 = self._time_bounds()
        lbw = ca.vertcat(*lbT, ca.repmat(xlo, N + 1, 1), ca.repmat(ulo, N * d, 1), *lbt0,
                         ca.repmat(xlo, N * d, 1))
        ubw = ca.vertcat(*ubT, ca.repmat(xhi, N + 1, 1), ca.repmat(uhi, N * d, 1), *ubt0,
                         ca.repmat(xhi, N * d, 1))
        w0 = ca.vertcat(*gT, ca.vec(linear_guess(ends[0], ends[1], self.tau)),
                        ca.repmat(ug, N * d, 1), *gt0,
                        ca.vec(linear_guess(ends[0], ends[1], self.tau_c)))
        u0 = ca.mtimes(U[:, :d], ca.DM(self.u0_weights)) if nu else ca.MX(0, 1)
        return PhaseNLP(t0, T, X[:, 0], u0, X[:, N], U[:, N * d - 1], ca.sum2(Q[1:, :]),
                        ca.sum2(Q[0, :]), cons, lbw, ubw, w0)

    def unpack(self, wb: np.ndarray, pv: np.ndarray, vv: np.ndarray) -> PhaseData:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.unpack`."""
        nx, nu, N, d = self.cp.nx, self.cp.nu, self.N, self.d
        t0, T = self._unpack_times(wb, self.it0)
        X = wb[self.iX].reshape(N + 1, nx)
        U = wb[self.iU].reshape(N * d, nu)
        Z = wb[self.iZ].reshape(N * d, nx)
        t = t0 + (T - t0) * self.tau_points
        u0 = self.u0_weights @ U[:d] if nu else np.zeros(0)
        return PhaseData(t0, T, t, np.vstack([X[:1], Z]), U, np.vstack([u0[None, :], U]),
                         t0 + (T - t0) * self.tau, np.concatenate([pv, vv, (t0, T)]),
                         {"X": X, "Z": Z, "U": U})

    def local(self, data: PhaseData, k: np.ndarray,
              theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """States and controls on interval ``k`` at local fractions ``theta`` in [0, 1].

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        k : ndarray of int
            Interval of each sample.
        theta : ndarray
            Local fraction of each sample.
        """
        N, d = self.N, self.d
        Zf = np.concatenate([data.raw["X"][:N, None, :],
                             data.raw["Z"].reshape(N, d, -1)], axis=1)[k]
        x = np.einsum("nr,nri->ni", lagrange_basis(np.r_[0.0, self.c], theta), Zf)
        Uk = data.raw["U"].reshape(N, d, -1)[k]
        u = np.einsum("nr,nri->ni", lagrange_basis(self.c, theta), Uk) if d > 1 \
            else Uk[:, 0, :]
        return x, u

    def sample(self, data: PhaseData, t: np.ndarray,
               substeps: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.sample`."""
        t = np.asarray(t, dtype=float)
        k = segment_index(data.mesh, t)
        h = np.diff(data.mesh)[k]
        theta = np.where(h > 0, (t - data.mesh[k]) / np.where(h > 0, h, 1.0), 0.0)
        return self.local(data, k, theta)

    def check_samples(self, data: PhaseData,
                      per_interval: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Times, states and controls where the path constraints are checked after a solve.

        The states are the collocation polynomials. The control is the method's between
        its points, never extrapolated: on ``[c_1, 1]`` of an interval the Lagrange
        polynomial through its values at the collocation points; before ``c_1``, the
        straight line from the previous interval's last point (the mesh point, where the
        control is that point's) to ``c_1`` -- on the first interval, the value at ``c_1``.

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        per_interval : int
            Points per mesh interval.
        """
        if per_interval not in self._check_bases:
            # the check points' fractions, the polynomial bases there and the indices of
            # the intervals' values they combine depend on the mesh only: computed once
            # per per_interval
            N, d = self.N, self.d
            frac = np.arange(per_interval) / per_interval
            k = np.concatenate([np.repeat(np.arange(N), per_interval), [N - 1]])
            theta = np.concatenate([np.tile(frac, N), [1.0]])
            inside = theta >= self.c[0]
            bu = lagrange_basis(self.c, theta[inside]) if d > 1 \
                else np.ones((int(inside.sum()), 1))
            kb = k[~inside]
            self._check_bases[per_interval] = (
                k, lagrange_basis(np.concatenate([[0.0], self.c]), theta),
                np.flatnonzero(inside), np.flatnonzero(~inside), k[inside], bu, kb,
                (kb > 0)[:, None], np.maximum(kb - 1, 0),
                (theta[~inside] / self.c[0])[:, None])
        k, bx, at_in, at_out, k_in, bu, kb, has_left, k_left, slope = \
            self._check_bases[per_interval]
        t = self.check_points(data, per_interval)
        N, d = self.N, self.d
        Zf = np.concatenate([data.raw["X"][:N, None, :], data.raw["Z"].reshape(N, d, -1)],
                            axis=1)[k]
        x = np.einsum("nr,nri->ni", bx, Zf)
        Uk = data.raw["U"].reshape(N, d, -1)
        u = np.empty((t.size, Uk.shape[2]))
        u[at_in] = np.einsum("nr,nri->ni", bu, Uk[k_in])
        first = Uk[kb, 0, :]
        left = np.where(has_left, Uk[k_left, d - 1, :], first)
        u[at_out] = left + slope * (first - left)
        return t, x, u

    def guess_from(self, sample: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                   t0: float, T: float) -> np.ndarray:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.guess_from`."""
        x_mesh, _ = sample(t0 + (T - t0) * self.tau)
        x_c, u_c = sample(t0 + (T - t0) * self.tau_c)
        parts: list[Any] = [[T]] if self.nT else []
        parts += [x_mesh.ravel(), u_c.ravel()]
        parts += [[t0]] if self.nt0 else []
        parts += [x_c.ravel()]
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def multipliers(self, lam: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.multipliers`."""
        out = dict(lam)
        shapes = {"continuity": (self.N, self.cp.nx),
                  "collocation": (self.N * self.d, self.cp.nx),
                  "path": (self.N * self.d, self.cp.npath)}
        for k, shp in shapes.items():
            if k in out:
                out[k] = out[k].reshape(shp)
        return out

    def weights(self) -> np.ndarray:
        """Quadrature weight ``h_k B_j`` of every collocation point (normalised time), (N d,)."""
        return (np.diff(self.tau)[:, None] * self.B[None, :]).ravel()

    maps_duals = True

    def dual_from(self, old: PhaseDiscretization, lam_g: dict[str, np.ndarray],
                  lam_x: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Multipliers for this mesh from those of the same phase on another mesh.

        A multiplier of a row imposed at a collocation point (a path constraint, a bound
        of a state or control there) is a density times the point's quadrature weight
        ``h_k B_j``, that of a collocation defect the costate times ``B_j``: the densities
        are interpolated linearly in normalised time and multiplied by the new weights.
        The continuity rows' carry the
        costate at the mesh points, interpolated as they are; the bounds of the mesh-point
        states get none (the collocation point that ends each interval carries the same
        bound); rows that do not depend on the mesh (boundary, time) keep theirs.

        Parameters
        ----------
        old : CollocationPhase
            The discretisation the multipliers belong to (same phase, any mesh or degree).
        lam_g : dict
            Its constraint multipliers by block name, flat (the user's units).
        lam_x : ndarray
            Its block of the bound multipliers.

        Returns
        -------
        tuple
            ``(lam_g by block name, lam_x block)`` for this mesh.
        """
        if not isinstance(old, CollocationPhase):
            raise TypeError("multipliers map between collocation meshes only")
        nx, nu = self.cp.nx, self.cp.nu
        quad = (old.weights(), self.weights())
        nodal = (np.tile(old.B, old.N), np.tile(self.B, self.N))

        def density(values: np.ndarray, k: int, w: tuple = quad) -> np.ndarray:
            """Per-point multipliers (old mesh) -> per-point multipliers (this mesh)."""
            out = np.zeros((self.tau_c.size, k))
            if k == 0:  # a phase without controls
                return out
            rows = values.reshape(-1, k) / w[0][:, None]
            for i in range(k):
                out[:, i] = np.interp(self.tau_c, old.tau_c, rows[:, i])
            return out * w[1][:, None]

        out = dict(lam_g)
        # a defect row sum_r C_rj Z_r - h f has no 1/h: its multiplier is B_j times the
        # costate (O(1) in h), where a row or bound at a point carries h B_j times a density
        out["collocation"] = density(lam_g["collocation"], nx, nodal).ravel()
        if "path" in lam_g:
            out["path"] = density(lam_g["path"], self.cp.npath).ravel()
        cont = lam_g["continuity"].reshape(-1, nx)
        out["continuity"] = np.column_stack([np.interp(self.tau[1:], old.tau[1:], cont[:, i])
                                             for i in range(nx)]).ravel()
        lx = np.zeros(self.size())
        if self.nT:
            lx[0] = lam_x[0]
        if self.nt0:
            lx[self.it0] = lam_x[old.it0]
        lx[self.iU] = density(lam_x[old.iU], nu).ravel()
        lx[self.iZ] = density(lam_x[old.iZ], nx).ravel()
        return out, lx
