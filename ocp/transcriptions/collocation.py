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

import math
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
    locate,
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


HULL_PIECES = 2
"""The control points of ``inner_constraints`` are those of the state polynomial on this
many equal pieces of its interval (de Casteljau subdivision): the hull of a piece's
control points is ``HULL_PIECES**2`` times closer to the polynomial, so a bound held on
them costs that much less (measured: Bryson-Denham's refined optimum 1.4e-8 above 4
with the whole interval's control points, 1.0e-9 with two pieces)."""


def bernstein_points(d: int, pieces: int = HULL_PIECES) -> tuple[np.ndarray, np.ndarray]:
    """The Bernstein control points, inside an interval, of a degree-``d`` polynomial given
    at the nodes ``0, c_1, ..., c_d`` (the Radau points) and restricted to each of
    ``pieces`` equal pieces of the interval: their Greville abscissae and the weights ``W``
    with ``control point i = W[i] @ node values`` (the interval's ends, where the
    polynomial is its own control point, left out; ``pieces * d - 1`` points).

    A polynomial lies in the convex hull of its control points on each piece: a bound on
    the control points bounds it everywhere.

    Parameters
    ----------
    d : int
        The degree.
    pieces : int
        Pieces of the interval.
    """
    nodes = np.r_[0.0, radau_points(d)]
    grid = np.arange(d + 1) / d
    basis = np.array([[math.comb(d, i) * v**i * (1 - v) ** (d - i) for i in range(d + 1)]
                      for v in grid])  # Bernstein basis at equally spaced points
    to_bernstein = np.linalg.inv(basis)
    theta, rows = [], []
    for j in range(pieces):
        s = (j + grid) / pieces  # the piece's equally spaced points in the interval
        W = to_bernstein @ lagrange_basis(nodes, s)  # the piece's control points
        first = 1 if j == 0 else 0  # the interval's start; a piece's start is the last's end
        for i in range(first, d):  # a piece's end is the next one's start (or the end)
            theta.append(s[i])
            rows.append(W[i])
    return np.array(theta), np.array(rows)


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
    inner : ndarray of bool, optional
        The intervals where the checked rows (path constraints and state bounds, see
        :meth:`checked_rows`) are also imposed between the collocation points, at the
        :attr:`inner_theta` fractions (block ``path_inner``).
    """

    method = "collocation"

    def __init__(self, cp: CompiledPhase, times: PhaseTimes, mesh: np.ndarray,
                 degree: int, functions: dict | None = None,
                 inner: np.ndarray | None = None) -> None:
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
        self.inner_theta, self.inner_states = bernstein_points(degree)
        self.inner = np.zeros(N, bool) if inner is None else np.asarray(inner, bool)
        if self.inner.shape != (N,):
            raise ValueError(f"inner: {self.inner.shape[0]} flags for {N} intervals")
        self.Gin: ca.Function | None = None
        if self.inner.any() and self.checked_rows() and self.inner_theta.size:
            key = ("radau inner", cp, degree)
            if key not in functions:
                functions[key] = self._inner_function()
            self.Gin = functions[key]
        # normalised times of the collocation points, interval by interval
        self.tau_c = (self.tau[:-1, None] + np.diff(self.tau)[:, None] * self.c[None, :]).ravel()
        self.tau_points = np.concatenate([[0.0], self.tau_c])  # every point, normalised

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

    def _inner_function(self) -> ca.Function:
        """The checked rows between the points of one interval, at the Greville abscissae
        ``i / d`` (:func:`bernstein_points`): a row free of the controls at the state
        polynomial's Bernstein control points (a bound there holds along the whole
        polynomial for a row affine in the states, or convex below an upper bound), a row
        with controls on the polynomial, with :meth:`interpolate`'s control (unclipped:
        an NLP row cannot clip)."""
        cp, d, c1 = self.cp, self.d, float(self.c[0])
        rows = self.checked_rows()
        xk, Z = ca.SX.sym("xk", cp.nx), ca.SX.sym("Z", cp.nx, d)
        U, up = ca.SX.sym("U", cp.nu, d), ca.SX.sym("up", cp.nu)
        t, h, s = ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("s", cp.ns)
        theta = self.inner_theta
        bx = lagrange_basis(np.r_[0.0, self.c], theta)
        bu = lagrange_basis(self.c, theta) if d > 1 else np.ones((theta.size, 1))
        Zf = ca.horzcat(xk, Z)
        out = []
        for i, th in enumerate(theta):
            u = ca.mtimes(U, ca.DM(bu[i])) if th >= c1 else up + (th / c1) * (U[:, 0] - up)
            at_cp = cp.check(t + th * h, ca.mtimes(Zf, ca.DM(self.inner_states[i])), u, s)
            on_curve = cp.check(t + th * h, ca.mtimes(Zf, ca.DM(bx[i])), u, s)
            out.append(ca.vertcat(*[at_cp[r] if cp.check_u_free[r] else on_curve[r]
                                    for r in rows]))
        return ca.Function("Gin", [xk, Z, U, up, t, h, s], [ca.horzcat(*out)],
                           ["xk", "Z", "U", "up", "t", "h", "s"], ["c"])

    def _inner_rows(self, X: ca.MX, Z: ca.MX, U: ca.MX, tk: ca.MX, hk: ca.MX,
                    s: ca.MX) -> tuple[str, ca.MX, ca.SX, ca.SX]:
        """The block ``path_inner``: :meth:`_inner_function` on every flagged interval."""
        d, idx = self.d, np.flatnonzero(self.inner)
        n = idx.size
        cols = (idx[:, None] * d + np.arange(d)[None, :]).ravel().tolist()
        prev = np.where(idx > 0, idx * d - 1, 0).tolist()  # the previous interval's last
        Ui = U[:, cols] if self.cp.nu else ca.MX(0, n * d)
        Up = U[:, prev] if self.cp.nu else ca.MX(0, n)
        assert self.Gin is not None
        rows_in = self.Gin.map(n)(X[:, idx.tolist()], Z[:, cols], Ui, Up,
                                  tk[:, idx.tolist()], hk[:, idx.tolist()],
                                  ca.repmat(s, 1, n))
        rows = self.checked_rows()
        clo, chi = (self.cp.bounds(self.cp.phase.p)[i] for i in (6, 7))
        reps = n * self.inner_theta.size
        return ("path_inner", rows_in, ca.repmat(clo[rows], reps, 1),
                ca.repmat(chi[rows], reps, 1))

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
        if self.Gin is not None:
            cons.append(self._inner_rows(X, Z, U, tk, hk, s))
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
        Uk = data.raw["U"].reshape(self.N, self.d, -1)[k]
        u = np.einsum("nr,nri->ni", lagrange_basis(self.c, theta), Uk) if self.d > 1 \
            else Uk[:, 0, :]
        return self.states(data, k, theta), u

    def node_values(self, data: PhaseData) -> np.ndarray:
        """The state polynomials' values at every interval's nodes ``0, c_1, ..., c_d``,
        shape (N, d + 1, nx).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        """
        return np.concatenate([data.raw["X"][:self.N, None, :],
                               data.raw["Z"].reshape(self.N, self.d, -1)], axis=1)

    def states(self, data: PhaseData, k: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """The state polynomials of intervals ``k`` at the fractions ``theta``, (n, nx)
        (arguments as :meth:`local`'s)."""
        return np.einsum("nr,nri->ni", lagrange_basis(np.r_[0.0, self.c], theta),
                         self.node_values(data)[k])

    def resample(self, data: PhaseData, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The collocation polynomials (:meth:`local`) at times ``t``: a guess on another
        mesh takes the control's polynomial as the NLP represents it, extrapolated before
        the first collocation point (kept from before the interpolant of
        :meth:`interpolate`: refinement's rounds start where they started).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        t : ndarray
            Times.
        """
        return self.local(data, *locate(data.mesh, t))

    def control_only_rows(self) -> list[int]:
        """Rows of the check function on the controls and not on the states: checked and
        imposed at the collocation points only (see :mod:`ocp.transcriptions.verify`)."""
        cp = self.cp
        if cp.nu == 0:
            return []
        on_x = set(cp.check.jac_sparsity(0, 1).get_triplet()[0])
        return [i for i in range(cp.ncheck) if not cp.check_u_free[i] and i not in on_x]

    def pieces(self, data: PhaseData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.pieces`: with a
        checked row on the controls, every interval is cut at its first collocation point,
        where the control interpolant turns from a straight line into a polynomial."""
        if self.d == 1 or self.cp.nu == 0 or all(self.cp.check_u_free):
            return super().pieces(data)
        N, c1 = self.N, float(self.c[0])
        k = np.repeat(np.arange(N), 2)
        a = np.tile([0.0, c1], N)
        return k, a, np.tile([c1, 1.0], N)

    def interpolate(self, data: PhaseData, k: np.ndarray,
                    theta: np.ndarray, substeps: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """See :meth:`ocp.transcriptions.discretization.PhaseDiscretization.interpolate`.

        The states are the collocation polynomials. The control is the method's between
        its points, never extrapolated: on ``[c_1, 1]`` the Lagrange polynomial through the
        interval's values at its collocation points; before ``c_1``, the straight line from
        the previous interval's last point (the mesh point, where the control is that
        point's) to ``c_1`` -- on the first interval, the value at ``c_1``; held within the
        control's bounds at the solution's parameter values. ``sol.sample``, ``sol.at`` and
        the check between points (:mod:`ocp.transcriptions.extrema`) read this
        interpolant; a guess for another mesh and the mesh error estimate read
        :meth:`local`, the polynomials as the NLP holds them.
        """
        N, d = self.N, self.d
        k = np.asarray(k, dtype=int)
        theta = np.asarray(theta, dtype=float)
        x = self.states(data, k, theta)
        Uk = data.raw["U"].reshape(N, d, -1)
        u = np.empty((theta.size, Uk.shape[2]))
        if u.shape[1] == 0:
            return x, u
        inside = theta >= self.c[0]
        if d > 1:
            u[inside] = np.einsum("nr,nri->ni", lagrange_basis(self.c, theta[inside]),
                                  Uk[k[inside]])
        else:
            u[inside] = Uk[k[inside], 0, :]
        kb = k[~inside]
        first = Uk[kb, 0, :]
        left = np.where((kb > 0)[:, None], Uk[np.maximum(kb - 1, 0), d - 1, :], first)
        u[~inside] = left + (theta[~inside] / self.c[0])[:, None] * (first - left)
        ulo, uhi = self.control_bounds(data)
        return x, np.clip(u, ulo, uhi)

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
                  "path": (self.N * self.d, self.cp.npath),
                  "path_inner": (int(self.inner.sum()) * self.inner_theta.size,
                                 len(self.checked_rows()))}
        for k, shp in shapes.items():
            if k in out:
                out[k] = out[k].reshape(shp)
        return out

    def _inner_dual(self, old: CollocationPhase, lam: np.ndarray | None) -> np.ndarray:
        """Multipliers of the rows between the points from another mesh's: a flagged
        interval takes those of the interval holding its middle (a multiplier at a point
        of an interval scales with its length), zero where that one had none."""
        per = self.inner_theta.size * len(self.checked_rows())
        idx = np.flatnonzero(self.inner)
        out = np.zeros((idx.size, per))
        if lam is None or old.Gin is None or not idx.size:
            return out.ravel()
        k_old = segment_index(old.tau, 0.5 * (self.tau[idx] + self.tau[idx + 1]))
        pos = np.full(old.N, -1)
        pos[np.flatnonzero(old.inner)] = np.arange(int(old.inner.sum()))
        have = pos[k_old] >= 0
        ratio = np.diff(self.tau)[idx] / np.diff(old.tau)[k_old]
        out[have] = lam.reshape(-1, per)[pos[k_old[have]]] * ratio[have, None]
        return out.ravel()

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
        if self.Gin is not None:
            out["path_inner"] = self._inner_dual(old, lam_g.get("path_inner"))
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
