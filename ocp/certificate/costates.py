"""Costates for the Pontryagin certificate, two independent ways, with measured accuracy.

Conventions: the *minimum* principle, ``H = L + lambda^T f(x, u)``; for a
control-affine problem the switching function of control j is
``sigma_j = dH/du_j = dL/du_j + lambda^T g_j(x)``, and the optimal control sits
at its upper bound where ``sigma_j < 0``, at its lower bound where
``sigma_j > 0``.

1. :func:`costates_from_multipliers`: the transcription's continuity
   multipliers. CasADi's NLP Lagrangian is ``J + lam_g^T g + lam_x^T w``; the
   continuity constraint of interval k is ``F(X_k, U_k) - X_{k+1} = 0`` with
   multiplier ``mu_k``; stationarity in ``X_{k+1}`` is the discrete adjoint, so
   ``lambda(t_{k+1}) = mu_k`` to the discretisation's order.
2. :func:`adjoint_sweep`: the adjoint ``lambda' = -H_x`` integrated backward
   *jointly with the state* along the refined arcs, from the transversality
   condition ``lambda(T) = grad_x (phi + nu^T G_T)`` (``nu``: the refinement's
   terminal multipliers). Exact (matrix exponential of the joint linear
   system) on arcs whose dynamics are affine in the state and whose running
   cost is affine in the state; fixed-step RK8 otherwise, run twice (``n``
   and ``2n`` steps) so its error is *measured*, not assumed.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.arcs import SolutionLike, transcribed
from ..structure.flows import ArcDynamics, Mode, expm, is_affine, rk8_step_function
from ..structure.refinement import arc_dynamics
from ..structure.switching import RefinedSwitching
from ..transcriptions.gridview import collocation_costates, is_collocation
from ..transcriptions.solution import along

_FN_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass
class PMPFunctions:
    """``H``, ``sigma = dH/du`` (nu,), ``H_x`` (nx,) as functions of ``(x, u, lam, p)``.

    ``linear`` says whether H is linear in u (then sigma is the switching function
    and does not depend on u); otherwise H is quadratic in u with Hessian ``Huu(x, p)``
    (a running cost such as ``u^2 / 2``), and sigma is evaluated at the actual control.

    Attributes
    ----------
    H, sigma, Hx : casadi.Function
        Hamiltonian, ``dH/du`` and ``H_x`` of ``(x, u, lam, p)``.
    linear : bool
        H is linear in u.
    Huu : casadi.Function
        ``d2H/du2`` of ``(x, p)`` (zero when linear).
    sigma_terms : casadi.Function
        The size of the terms sigma is made of.
    """

    H: ca.Function
    sigma: ca.Function
    Hx: ca.Function
    linear: bool
    Huu: ca.Function
    sigma_terms: ca.Function
    """``|dL/du_j| + sum_i |lam_i g_ij|``: the size of the terms sigma_j is made of."""


def pmp_functions(pr: OptimalControlProblem) -> PMPFunctions:
    """Hamiltonian, switching functions and ``H_x`` of a control-affine problem (cached).

    The running cost may be quadratic in u (H convex in u is checked by the
    certificate along the samples): the minimum condition is then the KKT
    condition of ``min_u H`` over the bounds, checked with ``sigma = dH/du``.

    Parameters
    ----------
    pr : OptimalControlProblem
        A control-affine problem.

    Raises
    ------
    ValueError
        If the dynamics are not affine in the controls, the running cost is
        neither affine nor quadratic in them, or either depends on time or on a
        decision variable.
    """
    if pr in _FN_CACHE:
        return _FN_CACHE[pr]
    if not pr.is_control_affine():
        raise ValueError("the dynamics are not control-affine: H is not linear in u")
    Luu = ca.hessian(pr.lagrange, pr.u)[0]
    if ca.depends_on(Luu, pr.u):
        raise ValueError("the running cost is neither affine nor quadratic in u")
    lam = ca.SX.sym("lam", pr.nx)
    H = pr.lagrange + ca.dot(lam, pr.rhs)
    args = [pr.x, pr.u, lam, pr.p]
    known = {str(s) for a in args for s in ca.symvar(a)}
    free = sorted({str(s) for s in ca.symvar(H)} - known)
    if free:
        # time (or a decision variable) in f or L: H is no longer constant along an
        # extremal, and the checks below are those of an autonomous problem
        raise ValueError(f"the dynamics or running cost depend on {', '.join(free)} (time or "
                         "decision variables): the certificate covers autonomous problems "
                         "with parameters only")
    out = PMPFunctions(ca.Function("H", args, [H]),
                       ca.Function("sigma", args, [ca.jacobian(H, pr.u).T]),
                       ca.Function("Hx", args, [ca.gradient(H, pr.x)]),
                       not ca.depends_on(ca.jacobian(pr.lagrange, pr.u), pr.u),
                       ca.Function("Huu", [pr.x, pr.p], [ca.densify(Luu)]),
                       ca.Function("terms", args, [
                           ca.fabs(ca.jacobian(pr.lagrange, pr.u)).T
                           + ca.mtimes(ca.fabs(ca.jacobian(pr.rhs, pr.u)).T, ca.fabs(lam))]))
    _FN_CACHE[pr] = out
    return out


def costates_from_multipliers(sol: SolutionLike) -> tuple[np.ndarray, np.ndarray]:
    """Costates from the transcription's multipliers, at the points after the first.

    Multiple shooting: node times ``t_1..t_N`` and ``lambda(t_{k+1}) = mu_k`` (see
    the module doc). Collocation: every collocation point (``sol.t[1:]``) and
    ``lambda = -mu / B`` from the defect multipliers ``mu`` and the Radau
    quadrature weights ``B`` (:func:`ocp.transcriptions.gridview.collocation_costates`).

    Parameters
    ----------
    sol : Solution
        A single-phase transcribed solution (or one phase).

    Returns
    -------
    t, lam : ndarray (m,), (m, nx)
    """
    tsol = transcribed(sol)
    if is_collocation(tsol):
        return np.asarray(tsol.t[1:], dtype=float), collocation_costates(tsol)
    return tsol.t[1:], tsol.multipliers["continuity"].copy()


def terminal_costate(pr: OptimalControlProblem, xT: np.ndarray, T: float, pv: np.ndarray,
                     nu: np.ndarray) -> tuple[np.ndarray, float]:
    """The transversality conditions.

    Parameters
    ----------
    pr : OptimalControlProblem
    xT : ndarray
        Final state.
    T : float
        Final time.
    pv : ndarray
        Parameter values.
    nu : ndarray
        Multipliers of the terminal constraints (CasADi's signs).

    Returns
    -------
    (ndarray, float)
        ``lambda(T) = grad_x(phi + nu^T G_T)`` and ``-d(phi + nu^T G_T)/dT``, the
        value of H that a free final time demands.
    """
    G = ca.vertcat(*[c.expr for c in pr.terminal]) if pr.terminal else ca.SX(0, 1)
    nu_s = ca.SX.sym("nu", G.numel())
    aug = pr.mayer + (ca.dot(nu_s, G) if G.numel() else 0)
    fn = ca.Function("tc", [pr.x, pr.T, pr.p, nu_s],
                     [ca.gradient(aug, pr.x), ca.gradient(aug, pr.T)])
    lamT, dT = fn(xT, T, pv, nu if len(nu) else np.zeros(0))
    return np.array(lamT, dtype=float).ravel(), -float(dT)


def final_time_condition(pr: OptimalControlProblem, T: float, t0: float) -> tuple[bool, int]:
    """Whether free-T transversality fixes H's value, and on which bound T sits.

    With T free in its bounds, ``H(T) = -d(phi + nu^T G_T)/dT``. Where T sits at a bound the
    bound's multiplier enters and the equality becomes an inequality: at the upper bound
    ``H <= -d(...)/dT`` (a later end must not pay), at the lower ``H >= -d(...)/dT``. T
    fixed by the initial time and a fixed duration, or moving only with a free initial time
    (a fixed duration), leaves H's value free (an autonomous problem's H is then only
    constant).

    Parameters
    ----------
    pr : OptimalControlProblem
    T, t0 : float
        The solution's final and initial times.

    Returns
    -------
    pinned : bool
        H is held to (or on one side of) its free-T value.
    side : int
        +1: T at its upper bound (``H <=`` that value); -1: at its lower (``>=``); 0: inside.
    """
    if not pr.time_free:
        return False, 0
    if pr.duration is not None and pr.duration[0] == pr.duration[1]:
        return False, 0  # T moves only with t0 (or not at all)

    def near(a: float, b: float) -> bool:
        return math.isfinite(b) and abs(a - b) <= 1e-7 * max(1.0, abs(b))

    lo, hi = pr.T_bounds
    sides = {s for s, hit in ((1, near(T, hi)), (-1, near(T, lo))) if hit}
    if pr.duration is not None:
        dlo, dhi = pr.duration
        sides |= {s for s, hit in ((1, near(T - t0, dhi)), (-1, near(T - t0, dlo))) if hit}
    if len(sides) > 1:
        return False, 0  # held from both sides: T cannot move at all
    return True, sides.pop() if sides else 0


# ------------------------------------------------------------- joint adjoint
class _JointArc:
    """Joint state-costate dynamics of one (bang) arc mode: ``y = [x, lam]``."""

    def __init__(self, dyn: ArcDynamics) -> None:
        pr = dyn.problem
        lam = ca.SX.sym("lam", pr.nx)
        H = ca.SX(dyn.problem.lagrange) + ca.dot(lam, pr.rhs)
        if dyn.held and all(dyn.orders[c] == 0 for c in dyn.held):
            # a boundary arc of mixed constraints c(x, u) (relative degree 0): the adjoint
            # with the constraint's multiplier, lam' = -H_x - nu c_x with nu = -H_u / c_u,
            # is the closed-loop one, -d/dx H(x, u(x), lam)
            Hx = ca.gradient(ca.substitute(H, pr.u, dyn.u), pr.x)
        else:
            # open-loop adjoint: u held at the arc's value (bang arcs)
            Hx = ca.substitute(ca.gradient(H, pr.x), pr.u, dyn.u)
        y = ca.vertcat(pr.x, lam)
        ydot = ca.vertcat(dyn.rhs, -Hx)
        self.exact = dyn.exact and is_affine(ydot, y)
        self.f = ca.Function("Y", [y, pr.p], [ydot])
        self.step = rk8_step_function(self.f, 2 * pr.nx, pr.np)
        if self.exact:
            self.Ab = ca.Function("Ab", [pr.p], [ca.jacobian(ydot, y),
                                                 ca.substitute(ydot, y, ca.DM.zeros(2 * pr.nx))])
        self._acc: dict[int, ca.Function] = {}

    def backward(self, y_end: np.ndarray, tau: float, pv: np.ndarray, points: int,
                 steps: int) -> np.ndarray:
        """``y`` at ``points + 1`` equally spaced times from the arc start to its end,
        integrated backward from ``y_end``; (points+1, 2 nx)."""
        if self.exact:
            A, b = (np.array(v, dtype=float) for v in self.Ab(pv))
            n = len(y_end)
            M = np.zeros((n + 1, n + 1))
            M[:n, :n] = A
            M[:n, n] = b.ravel()
            E = expm(-M * (tau / points))
            out = np.empty((points + 1, n))
            z = np.r_[y_end, 1.0]
            out[-1] = y_end
            for j in range(points - 1, -1, -1):
                z = E @ z
                out[j] = z[:n]
            return out
        per = max(1, -(-steps // points))
        total = per * points
        if total not in self._acc:
            self._acc[total] = self.step.mapaccum(total)
        Y = np.array(self._acc[total](y_end, -tau / total, pv), dtype=float).T
        Y = np.vstack([np.asarray(y_end, dtype=float)[None, :], Y])[::per]
        return Y[::-1]


_JOINT_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _joint(pr: OptimalControlProblem, modes: tuple[Mode, ...]) -> _JointArc:
    per = _JOINT_CACHE.setdefault(pr, {})
    if modes not in per:
        per[modes] = _JointArc(arc_dynamics(pr, modes))
    return per[modes]


@dataclass
class AdjointSweep:
    """States and costates along refined arcs, sampled, with measured accuracy.

    Attributes
    ----------
    t, x, u, lam : arrays (m,), (m, nx), (m, nu), (m, nx)
        Samples from ``t_start`` to ``T`` (junction times appear twice).
    interval : ndarray of int (m,)
        Which refined interval each sample belongs to.
    H_expected : float or None
        The constant H must equal (None when T is fixed), or, with ``T_side``, the side
        of which it must lie.
    t_start : float
        Where the backward sweep stopped (0, or the end of the last constrained arc).
    error_lam : float
        ``max |lam_n - lam_2n| / max |lam|`` (0 when every arc is exact).
    error_x : float
        Largest mismatch between the backward-integrated state and the
        refinement's forward state at the arcs' starts, relative.
    steps : list of int
        RK8 steps per arc of the finer run (0 for exact arcs).
    coarse : AdjointSweep or None
        The coarser run the accuracy was measured against.
    T_side : int
        +1 or -1 when T sits at its upper or lower bound (:func:`final_time_condition`).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    lam: np.ndarray
    interval: np.ndarray
    H_expected: float | None
    t_start: float
    error_lam: float = 0.0
    error_x: float = 0.0
    steps: list[int] = field(default_factory=list)
    coarse: AdjointSweep | None = field(default=None, repr=False)
    T_side: int = 0


def _sweep(ref: RefinedSwitching, first: int, points: int, factor: int) -> AdjointSweep:
    """One backward sweep over intervals ``first..K-1`` with ``factor`` x the refinement's steps."""
    pr = ref.problem
    pv = ref.pv
    Z = ref.junctions()
    modes = ref.interval_modes
    xT, T = Z[-1][:pr.nx], float(np.sum(ref.durations))
    if ref.terminal_costate is not None:  # a phase of a multi-phase problem
        lamT, H_given = ref.terminal_costate
        lamT = np.asarray(lamT, dtype=float)
    else:
        lamT, H_given = terminal_costate(pr, xT, T, pv, ref.terminal_multipliers)
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    y = np.r_[xT, lamT]
    parts: list[tuple] = []
    err_x, steps = 0.0, []
    for k in range(len(ref.durations) - 1, first - 1, -1):
        tau = float(ref.durations[k])
        ja = _joint(pr, modes[k])
        q = max(8, int(np.ceil(points * tau / max(T, 1e-300))))
        n = 0 if ja.exact else factor * max(ref.rk8_steps(k), q)
        Y = ja.backward(y, tau, pv, q, n) if tau > 0 else np.tile(y, (2, 1))
        xs = Y[:, :pr.nx]
        err_x = max(err_x, float(np.max(np.abs(xs[0] - Z[k][:pr.nx]))
                                 / max(1.0, float(np.max(np.abs(Z[k][:pr.nx]))))))
        U = along(arc_dynamics(pr, modes[k]).u_fn, xs, pv)[0]
        ts = edges[k] + np.linspace(0.0, tau, len(Y))
        parts.append((ts, xs, U, Y[:, pr.nx:], np.full(len(Y), k)))
        steps.append(n)
        y = Y[0]
    parts.reverse()
    steps.reverse()
    cat = [np.concatenate([p[i] for p in parts]) for i in range(5)]
    # (a phase's end is the multi-phase problem's; the refinement's time starts at 0)
    pinned, side = (pr.time_free, 0) if ref.terminal_costate is not None else \
        final_time_condition(pr, T, 0.0)
    return AdjointSweep(cat[0], cat[1], cat[2], cat[3], cat[4].astype(int),
                        H_given if pinned else None, float(edges[first]), 0.0, err_x,
                        steps, T_side=side)


def adjoint_sweep(ref: RefinedSwitching, t_start: float = 0.0, points: int = 2000) -> AdjointSweep:
    """Costates along a refined solution, with the error measured.

    The sweep runs with twice and four times the refinement's RK8 steps on
    non-affine arcs (exact arcs once); the finer run is returned, and the
    difference of the two (an over-estimate of the finer run's error) is
    ``error_lam``.

    Parameters
    ----------
    ref : RefinedSwitching
    t_start : float
        The sweep runs from ``T`` back to the start of the interval containing
        ``t_start`` (before it a state constraint may make the costate jump).
    points : int
        About how many samples over the whole horizon.

    Returns
    -------
    AdjointSweep
    """
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    first = int(np.clip(np.searchsorted(edges, t_start, side="right") - 1, 0,
                        len(ref.durations) - 1))
    fine = _sweep(ref, first, points, 4)
    if all(_joint(ref.problem, m).exact for m in ref.interval_modes[first:]):
        return fine
    coarse = _sweep(ref, first, points, 2)
    scale = max(float(np.max(np.abs(fine.lam))), 1e-300)
    fine.error_lam = float(np.max(np.abs(fine.lam - coarse.lam))) / scale
    fine.coarse = coarse
    return fine


def adjoint_along_refined(ref: RefinedSwitching, n: int = 2000) -> tuple[Any, ...]:
    """Costate by backward integration of the adjoint along the refined arcs.

    Kept for compatibility: the sweep covers the whole horizon, which is right
    only when no state constraint is active (see :func:`adjoint_sweep`).

    Parameters
    ----------
    ref : RefinedSwitching
    n : int
        About how many samples.

    Returns
    -------
    t, x, u, lam, H_expected
        ``t`` (m,), ``x`` (m, nx), ``u`` (m,) (single control) or (m, nu),
        ``lam`` (m, nx), and the value H must have (None for fixed T).
    """
    s = adjoint_sweep(ref, 0.0, n)
    u = s.u[:, 0] if s.u.shape[1] == 1 else s.u
    return s.t, s.x, u, s.lam, s.H_expected
