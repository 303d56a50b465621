"""The second-order (Jacobi) test of an interior extremal: no conjugate point.

Along an extremal whose controls are all interior (``H_u = 0``, ``H_uu`` positive
definite) on the whole horizon, the accessory problem's Hamiltonian system (the
Jacobi equation) with ``du = -H_uu^-1 (H_ux dx + f_u^T dlam)`` is

    dx'   =  (A - B H_uu^-1 H_ux) dx - B H_uu^-1 B^T dlam
    dlam' = -(H_xx - H_xu H_uu^-1 H_ux) dx - (A - B H_uu^-1 H_ux)^T dlam,

integrated backward from the terminal Lagrangian subspace (``dx`` tangent to the
terminal constraints ``G(x(T)) = 0`` with ``dlam = (phi + nu^T G)_xx dx``, and ``dx = 0``
with ``dlam`` along ``G_x^T``). With the initial state fixed, there is no conjugate
point on ``[t0, T)`` iff ``dX(t)`` stays nonsingular: then the Riccati matrix
``S = dLam dX^-1`` exists on the whole horizon (for a free final state, the Riccati
equation's solution from ``S(T) = phi_xx``), the strengthened Legendre--Clebsch
condition holds and the extremal is a strict local minimum (weak). Coefficients are
read at the samples and interpolated linearly in time; the integration is
scipy's DOP853 at a tight tolerance, so the test's own error is the samples'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.solution import along


@dataclass
class JacobiResult:
    """The outcome of the conjugate-point test.

    Attributes
    ----------
    tested : bool
        False when the test does not apply (``reason`` says why).
    conjugate_point : float or None
        The first time (backward from T) where ``dX`` becomes singular, if any.
    min_singular : float
        Smallest ``sigma_min(dX) / |Z|`` over ``[t0, T - margin]`` (normalised).
    S0 : ndarray or None
        The Riccati matrix ``dLam dX^-1`` at ``t0``.
    reason : str
    """

    tested: bool
    conjugate_point: float | None = None
    min_singular: float = math.nan
    S0: np.ndarray | None = None
    reason: str = ""


def applicable(pr: OptimalControlProblem) -> str:
    """Why the Jacobi test does not apply to ``pr`` ("" when it does).

    Parameters
    ----------
    pr : OptimalControlProblem
    """
    if pr.time_free:
        return "free final time (the test here is for a fixed horizon)"
    G0 = [c for c in pr.initial if ca.depends_on(c.expr, pr.x)]
    if not G0 or ca.jacobian(ca.vertcat(*[c.expr for c in G0]), pr.x).size1() < pr.nx:
        return "the initial state is not fixed (focal points are not tested)"
    if any(not ca.SX(c.lower - c.upper).is_zero() for c in pr.terminal):
        return "inequality terminal constraints"
    return ""


def _terminal_basis(pr: OptimalControlProblem, xT: np.ndarray, pv: np.ndarray,
                    nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``dX(T)``, ``dLam(T)`` (nx, nx) spanning the terminal Lagrangian subspace."""
    n = pr.nx
    G = ca.vertcat(*[c.expr for c in pr.terminal]) if pr.terminal else ca.SX(0, 1)
    nus = ca.SX.sym("nu", G.numel())
    phi = ca.SX(pr.mayer) + (ca.dot(nus, G) if G.numel() else 0)
    fn = ca.Function("tb", [pr.x, pr.p, nus], [ca.densify(ca.hessian(phi, pr.x)[0]),
                                                ca.densify(ca.jacobian(G, pr.x))])
    P, Gx = (np.array(v, dtype=float) for v in fn(xT, pv, nu if len(nu) else np.zeros(0)))
    Gx = Gx.reshape(-1, n)
    r = np.linalg.matrix_rank(Gx) if Gx.size else 0
    _, _, Vt = np.linalg.svd(Gx) if Gx.size else (None, None, np.eye(n))
    N = Vt[r:].T  # tangent directions
    dX = np.c_[N, np.zeros((n, r))]
    dL = np.c_[P @ N, Vt[:r].T if r else np.zeros((n, 0))]
    return dX, dL


def jacobi_test(pr: OptimalControlProblem, pv: np.ndarray, t: np.ndarray, x: np.ndarray,
                u: np.ndarray, lam: np.ndarray, xT: np.ndarray, nu: np.ndarray,
                margin: float) -> JacobiResult:
    """Integrate the Jacobi equation backward and look for a conjugate point.

    Parameters
    ----------
    pr : OptimalControlProblem
    pv : ndarray
        Parameter values.
    t, x, u, lam : ndarray
        Samples of the extremal (increasing times).
    xT : ndarray
        Final state.
    nu : ndarray
        Terminal multipliers (CasADi's signs, as :func:`ocp.certificate.costates.terminal_costate`).
    margin : float
        ``dX`` is judged on ``[t0, T - margin]`` (it is singular at T when the final
        state is constrained).

    Returns
    -------
    JacobiResult
    """
    from scipy.integrate import solve_ivp

    why = applicable(pr)
    if why:
        return JacobiResult(False, reason=why)
    n, m = pr.nx, pr.nu
    lam_s = ca.SX.sym("lam", n)
    H = ca.SX(pr.lagrange) + ca.dot(lam_s, pr.rhs)
    z = ca.vertcat(pr.x, pr.u)
    Hzz = ca.hessian(H, z)[0]
    fn = ca.Function("jacobi", [pr.x, pr.u, lam_s, pr.p],
                     [ca.densify(ca.jacobian(pr.rhs, pr.x)), ca.densify(ca.jacobian(pr.rhs, pr.u)),
                      ca.densify(Hzz)])
    A, B, Hz = along(fn, x, u, lam, pv)
    k = len(t)
    A, B, Hz = A.reshape(k, n, n, order="F"), B.reshape(k, n, m, order="F"), \
        Hz.reshape(k, n + m, n + m, order="F")
    Hxx, Hxu, Huu = Hz[:, :n, :n], Hz[:, :n, n:], Hz[:, n:, n:]
    if np.min(np.linalg.eigvalsh(Huu)) <= 0:
        return JacobiResult(False, reason="H_uu is not positive definite on the horizon")
    Ki = np.linalg.inv(Huu)
    Ac = A - B @ Ki @ np.swapaxes(Hxu, 1, 2)
    M = np.zeros((k, 2 * n, 2 * n))
    M[:, :n, :n] = Ac
    M[:, :n, n:] = -B @ Ki @ np.swapaxes(B, 1, 2)
    M[:, n:, :n] = -(Hxx - Hxu @ Ki @ np.swapaxes(Hxu, 1, 2))
    M[:, n:, n:] = -np.swapaxes(Ac, 1, 2)
    flat = M.reshape(k, -1)

    def rhs(tt: float, y: np.ndarray) -> np.ndarray:
        Mt = np.array([np.interp(tt, t, flat[:, i]) for i in range(flat.shape[1])])
        return (Mt.reshape(2 * n, 2 * n) @ y.reshape(2 * n, n)).ravel()

    dX, dL = _terminal_basis(pr, xT, pv, nu)
    T = float(t[-1])
    grid = t[t <= T - margin][::-1]
    if len(grid) < 2:
        return JacobiResult(False, reason="the horizon is too short for the test")
    sol = solve_ivp(rhs, (T, float(grid[-1])), np.r_[dX, dL].ravel(), method="DOP853",
                    t_eval=grid, rtol=1e-10, atol=1e-12)
    if not sol.success:
        return JacobiResult(False, reason=f"the Jacobi equation's integration failed: "
                            f"{sol.message}")
    Z = sol.y.T.reshape(-1, 2 * n, n)
    norms = np.linalg.norm(Z, axis=1)
    Xn = Z[:, :n, :] / np.maximum(norms[:, None, :], 1e-300)
    smin = np.linalg.svd(Xn, compute_uv=False)[:, -1]
    dets = np.linalg.det(Xn)
    flips = np.flatnonzero(np.sign(dets[1:]) != np.sign(dets[:-1]))
    cp = float(sol.t[flips[0] + 1]) if len(flips) else None
    S0 = Z[-1, n:, :] @ np.linalg.inv(Z[-1, :n, :]) if not len(flips) else None
    return JacobiResult(True, cp, float(np.min(smin)), S0)


__all__ = ["JacobiResult", "applicable", "jacobi_test"]
