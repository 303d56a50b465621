"""Pontryagin certificate: costates, Hamiltonian and switching function.

Conventions (stated once, used everywhere here)
-----------------------------------------------
We use the *minimum* principle: ``H = L + lambda^T (f(x) + g(x) u)``, and the
optimal control minimises H. For a control-affine problem the switching
function is ``sigma = lambda^T g(x)`` (plus ``dL/du`` if L were affine in u), so
``u = upper`` where ``sigma < 0`` and ``u = lower`` where ``sigma > 0``. The
paper writes the maximum principle; its costate is ``-lambda``.

Costates, two independent ways:

1. **From the transcription's multipliers.** CasADi's NLP Lagrangian is
   ``J + lam_g^T g + lam_x^T w``; the continuity constraint of interval k is
   ``F(X_k, U_k) - X_{k+1} = 0`` with multiplier ``mu_k``. Stationarity in
   ``X_{k+1}`` gives the discrete adjoint ``mu_k = F_x^T mu_{k+1}`` and, at the
   last node, ``mu_{N-1} = grad phi + G_T^T nu``. Hence
   ``lambda(t_{k+1}) = mu_k`` (accurate to the discretisation order).
2. **By integrating the adjoint** ``lambda' = -H_x`` backward along the
   (refined, exact) trajectory from the transversality condition
   ``lambda(T) = grad_x (phi + nu^T G_T)``, with ``nu`` the terminal-constraint
   multipliers of the refinement NLP. For dynamics affine in the state each
   arc is exact (matrix exponential).

For an autonomous problem H is constant; with free final time it equals
``-d(phi + nu^T G_T)/dT`` (0 when the terminal cost and constraints do not
involve T; -1 for minimum time posed as ``phi = T``). ``H_max_abs`` and
``H_variation`` are normalised by ``H_scale = max_t sum_i |lambda_i xdot_i|``
(the size of the terms that must cancel).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg

from .problem import OptimalControlProblem
from .solution import Solution, along
from .switching import RefinedSwitching, detect_arcs
from .switching import active_path_constraints as _active_path_constraints


def _affine_parts(pr, u_value, pv, with_quadrature):
    z = pr.x
    Jf = ca.Function('J', [z, pr.u, pr.p], [ca.jacobian(pr.rhs, z), pr.rhs])
    n = z.numel()
    A, b = (np.array(v, dtype=float) for v in Jf(np.zeros(n), u_value, pv))
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = b.ravel()
    return M


CERTIFIED = "bang-bang certified"
NOT_BANG_BANG = "not bang-bang"
INCONCLUSIVE = "inconclusive"


@dataclass
class PMPCertificate:
    """Figures of the PMP check and a verdict.

    Attributes
    ----------
    verdict : str
        ``"bang-bang certified"``, ``"not bang-bang"`` or ``"inconclusive"``.
    reasons : list of str
        Why (every failed or unverifiable check).
    H_expected : float or None
        The constant H must equal (None when T is fixed: any constant).
    H_max_abs, H_variation : float
        ``max |H - H_expected|`` (or ``max |H - mean H|`` when fixed T) and
        ``max H - min H``, both divided by ``H_scale``.
    sigma_sign_agreement : float
        Fraction of the time where ``|sigma|`` is clearly non-zero on which u
        sits at the bound selected by ``sign(sigma)``.
    switch_sigma_gap : float
        Largest time between a switch of u and the nearest sign change of sigma.
    singular_intervals, state_constraint_active_intervals : list of (t0, t1)
    costate_estimates_gap : float
        Largest difference between the two costate estimates at the nodes,
        relative to the largest costate (NaN without a refined solution).
    t, lam, H, sigma, u : arrays for plotting.
    """

    verdict: str
    reasons: list[str]
    H_expected: float | None
    H_max_abs: float
    H_variation: float
    H_scale: float
    sigma_sign_agreement: float
    switch_sigma_gap: float
    singular_intervals: list[tuple[float, float]]
    state_constraint_active_intervals: list[tuple[float, float]]
    costate_estimates_gap: float
    source: str
    t: np.ndarray = field(repr=False, default=None)
    lam: np.ndarray = field(repr=False, default=None)
    H: np.ndarray = field(repr=False, default=None)
    sigma: np.ndarray = field(repr=False, default=None)
    u: np.ndarray = field(repr=False, default=None)

    @property
    def certified(self) -> bool:
        return self.verdict == CERTIFIED

    def to_dict(self) -> dict[str, Any]:
        def f(x):
            return float(x) if x is not None and math.isfinite(x) else None

        return {"verdict": self.verdict, "reasons": self.reasons,
                "H_expected": f(self.H_expected) if self.H_expected is not None else None,
                "H_max_abs": f(self.H_max_abs), "H_variation": f(self.H_variation),
                "H_scale": f(self.H_scale), "sigma_sign_agreement": f(self.sigma_sign_agreement),
                "switch_sigma_gap": f(self.switch_sigma_gap),
                "singular_intervals": [list(map(float, i)) for i in self.singular_intervals],
                "state_constraint_active_intervals": [
                    list(map(float, i)) for i in self.state_constraint_active_intervals],
                "costate_estimates_gap": f(self.costate_estimates_gap), "source": self.source}


# ------------------------------------------------------------------ pieces
def _functions(pr: OptimalControlProblem):
    if pr.nu != 1:
        raise ValueError("the PMP certificate supports problems with one control")
    if not pr.is_control_affine():
        raise ValueError("the dynamics are not control-affine: H is not linear in u")
    lam = ca.SX.sym("lam", pr.nx)
    g = ca.jacobian(pr.rhs, pr.u)
    if ca.depends_on(ca.jacobian(pr.lagrange, pr.u), pr.u):
        raise ValueError("the running cost is not affine in u: H is not linear in u")
    H = pr.lagrange + ca.dot(lam, pr.rhs)
    sigma = ca.jacobian(H, pr.u)
    Hx = ca.jacobian(H, pr.x).T
    args = [pr.x, pr.u, lam, pr.p]
    return (ca.Function("H", args, [H]), ca.Function("sigma", args, [sigma]),
            ca.Function("Hx", args, [Hx]), ca.Function("g", [pr.x, pr.p], [g]))


def costates_from_multipliers(sol: Solution) -> tuple[np.ndarray, np.ndarray]:
    """Node times ``t_1..t_N`` and costates ``lambda(t_{k+1}) = mu_k`` (see module doc)."""
    return sol.t[1:], sol.multipliers["continuity"].copy()


def _terminal_costate(pr: OptimalControlProblem, xT, T, pv, nu) -> tuple[np.ndarray, float]:
    """``lambda(T) = grad_x(phi + nu^T G_T)`` and the H value free T demands."""
    G = ca.vertcat(*[c.expr for c in pr.terminal]) if pr.terminal else ca.SX(0, 1)
    nu_s = ca.SX.sym("nu", G.numel())
    aug = pr.mayer + (ca.dot(nu_s, G) if G.numel() else 0)
    fn = ca.Function("tc", [pr.x, pr.T, pr.p, nu_s],
                     [ca.gradient(aug, pr.x), ca.gradient(aug, pr.T)])
    lamT, dT = fn(xT, T, pv, nu if len(nu) else np.zeros(0))
    return np.array(lamT, dtype=float).ravel(), -float(dT)


def _intervals(t: np.ndarray, mask: np.ndarray, min_len: float) -> list[tuple[float, float]]:
    out = []
    k = 0
    n = len(mask)
    while k < n:
        if mask[k]:
            j = k
            while j + 1 < n and mask[j + 1]:
                j += 1
            if t[j] - t[k] >= min_len:
                out.append((float(t[k]), float(t[j])))
            k = j + 1
        else:
            k += 1
    return out


def _sign_changes(t: np.ndarray, s: np.ndarray, tiny: float) -> np.ndarray:
    """Times where s changes sign, skipping samples with ``|s| <= tiny``
    (a crossing may land exactly on a sample), by linear interpolation."""
    nz = np.flatnonzero(np.abs(s) > tiny)
    a, b = nz[:-1], nz[1:]
    ch = np.sign(s[a]) != np.sign(s[b])
    a, b = a[ch], b[ch]
    return t[a] - s[a] * (t[b] - t[a]) / (s[b] - s[a])


# --------------------------------------------------------------- certificate
def adjoint_along_refined(ref: RefinedSwitching, n: int = 2000):
    """Costate by backward integration of the adjoint along the refined arcs.

    Returns ``t`` (m,), ``x`` (m, nx), ``u`` (m,), ``lam`` (m, nx), ``H_expected``.
    """
    pr = ref.problem
    pv = np.array([ref.params[k] for k in pr.param_names])
    t, x, u = ref.sample(n)
    nu = np.zeros(0)
    if "terminal" in ref.blocks:
        nu = np.concatenate([ref.lam_g[s] for s in ref.blocks["terminal"]])
    lamT, H_exp = _terminal_costate(pr, ref.xT, ref.T, pv, nu)
    if not pr.time_free:
        H_exp = None
    _, _, Hx, _ = _functions(pr)
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    lam = np.empty_like(x)
    has_L = not (isinstance(pr.lagrange, ca.SX) and pr.lagrange.is_zero())
    exact = pr.is_affine_in_state() and not has_L
    lam_end = lamT
    for k in range(len(ref.durations) - 1, -1, -1):
        a, b = edges[k], edges[k + 1]
        sel = (t >= a) & (t <= b) if k == 0 else (t > a) & (t <= b)
        if exact:
            M = _affine_parts(pr, ref.values[k], pv, False)
            A = M[:-1, :-1]
            for i in np.flatnonzero(sel):
                lam[i] = scipy.linalg.expm(A.T * (b - t[i])) @ lam_end
            lam_end = scipy.linalg.expm(A.T * (b - a)) @ lam_end
        else:
            from scipy.integrate import solve_ivp

            ts = t[(t >= a) & (t <= b)]
            xs = x[(t >= a) & (t <= b)]

            def rhs(tt, ll, ts=ts, xs=xs, uk=ref.values[k]):
                xx = np.array([np.interp(tt, ts, xs[:, j]) for j in range(pr.nx)])
                return -np.array(Hx(xx, uk, ll, pv)).ravel()

            if b > a:
                r = solve_ivp(rhs, (b, a), lam_end, rtol=1e-11, atol=1e-13, dense_output=True,
                              method="DOP853")
                for i in np.flatnonzero(sel):
                    lam[i] = r.sol(t[i])
                lam_end = r.y[:, -1]
    return t, x, u, lam, H_exp


def certify(sol: Solution, refined: RefinedSwitching | None = None, *,
            tol_H: float | None = None, tol_sigma: float | None = None,
            tol_switch: float | None = None, min_singular: float | None = None,
            n: int = 2000) -> PMPCertificate:
    """Check Pontryagin's conditions for bang-bang structure.

    Parameters
    ----------
    sol : Solution
        The transcribed solution (its multipliers give the first costate estimate,
        and its nodes the state-constraint activity).
    refined : RefinedSwitching, optional
        The refined solution; when given, H and sigma are evaluated on it with the
        adjoint-integrated costate (exact arcs), and the two estimates compared.
    tol_H : float, optional
        Allowed ``H_max_abs`` (relative to ``H_scale``): default 1e-6 on a
        refined solution, 1e-2 on the transcription alone (its costates carry
        the grid error).
    tol_sigma : float, optional
        ``|sigma| <= tol_sigma * max|sigma|`` counts as zero: default 1e-6
        refined, 1e-2 transcribed.
    tol_switch : float, optional
        Allowed switch/sign-change gap (default: 1e-6 T refined, 1.5 h otherwise).
    min_singular : float, optional
        Shortest interval of ``sigma ~ 0`` reported as singular (default 2 h).
    """
    pr = sol.problem
    Hf, sigf, _, _ = _functions(pr)
    pv = np.array([sol.params[k] for k in pr.param_names])
    h = sol.T / sol.N
    reasons: list[str] = []
    exact = refined is not None
    tol_H = (1e-6 if exact else 1e-2) if tol_H is None else tol_H
    tol_sigma = (1e-6 if exact else 1e-2) if tol_sigma is None else tol_sigma
    if refined is not None:
        t, x, u, lam, H_exp = adjoint_along_refined(refined, n)
        source = "refined (adjoint integrated along exact arcs)"
        tol_switch = 1e-6 * refined.T if tol_switch is None else tol_switch
    else:
        t, lam = costates_from_multipliers(sol)
        x = sol.x[1:]
        u = np.r_[sol.u[1:, 0], sol.u[-1, 0]]
        H_exp = None
        if pr.time_free:
            nu = sol.multipliers.get("terminal", np.zeros(0))
            _, H_exp = _terminal_costate(pr, sol.x[-1], sol.T, pv, nu)
        source = "transcription (costates from continuity multipliers)"
        tol_switch = 1.5 * h if tol_switch is None else tol_switch
    min_singular = 2 * h if min_singular is None else min_singular

    uc = np.asarray(u, dtype=float)[:, None]
    H = along(Hf, x, uc, lam, pv)[0].ravel()
    sigma = along(sigf, x, uc, lam, pv)[0].ravel()
    xdot = along(pr.dynamics_function(), x, uc, pv)[0]
    H_scale = float(np.max(np.sum(np.abs(lam * xdot), axis=1))) or 1.0
    ref_H = H_exp if H_exp is not None else float(np.mean(H))
    H_max_abs = float(np.max(np.abs(H - ref_H))) / H_scale
    H_var = float(np.ptp(H)) / H_scale
    if H_max_abs > tol_H:
        what = "its free-T value" if H_exp is not None else "a constant"
        reasons.append(f"H deviates from {what} by {H_max_abs:.2e} of its scale (> {tol_H:g})")

    if refined is not None:
        act_t = _path_activity(pr, t, x, u, pv, 1e-7)
        active = _intervals(t, act_t, 1e-12)
        min_len = 2 * (t[-1] - t[0]) / len(t)
    else:
        act = _active_path_constraints(sol, 1e-6)
        act_nodes = act.any(axis=1) if act.size else np.zeros(sol.N + 1, bool)
        active = _intervals(sol.t, act_nodes, 1e-12)
        act_t = act_nodes[1:]
        min_len = h - 1e-12
    # a constraint touching at a point (v_f(T) = 0 at the end) is not a constrained arc
    active = [(a, b) for a, b in active if b - a >= min_len]

    constrained = np.zeros(len(t), dtype=bool)
    for a_, b_ in active:
        constrained |= (t >= a_) & (t <= b_)

    # sign agreement: u = upper where sigma < 0, lower where sigma > 0
    lo, hi = _bounds(pr, sol.params)
    s_scale = float(np.max(np.abs(sigma))) or 1.0
    # on a state-constrained arc sigma may vanish and u be interior: judged apart
    clear = (np.abs(sigma) > tol_sigma * s_scale) & ~constrained
    want = np.where(sigma < 0, hi, lo)
    # the transcription reaches its bounds only to Ipopt's tolerance
    agree = np.abs(u - want) <= (1e-9 if exact else 1e-3) * max(1.0, hi - lo)
    dt = np.gradient(t)
    frac = float(np.sum(dt[clear & agree]) / max(np.sum(dt[clear]), 1e-300))
    if frac < 0.99:
        reasons.append(f"u sits at the bound selected by sign(sigma) only {frac:.1%} of the time")

    # switches of u against sign changes of sigma
    if refined is not None:
        sw = np.asarray(refined.switch_times)
    else:
        sw = np.asarray(detect_arcs(sol).switch_times)
    zc = _sign_changes(t, sigma, 1e-14 * s_scale)
    gap = 0.0
    for ts in sw:
        gap = max(gap, float(np.min(np.abs(zc - ts))) if len(zc) else math.inf)
    if gap > tol_switch:
        reasons.append(f"a switch of u is {gap:.2e} away from the nearest sign change of sigma")

    singular = _intervals(t, ~clear & ~constrained, min_singular)
    if singular:
        reasons.append(f"sigma vanishes on {len(singular)} interval(s): a singular arc")

    gap_lam = math.nan
    if refined is not None:
        t_tr, lam_tr = costates_from_multipliers(sol)
        # common horizon, without the transcription's last interval (where its
        # final time, and any constrained tail, differ from the refined ones)
        keep = t_tr <= min(refined.T, sol.T) - h
        lam_i = np.column_stack([np.interp(t_tr[keep], t, lam[:, j]) for j in range(pr.nx)])
        gap_lam = float(np.max(np.abs(lam_i - lam_tr[keep]))
                        / max(np.max(np.abs(lam)), 1e-300))

    if singular:
        verdict = NOT_BANG_BANG
    elif frac < 0.99 or gap > tol_switch or H_max_abs > tol_H:
        verdict = NOT_BANG_BANG
    elif active:
        verdict = INCONCLUSIVE
        reasons.append(f"state constraint active on {len(active)} interval(s): the bang-bang "
                       "argument does not apply there")
    else:
        verdict = CERTIFIED
    return PMPCertificate(verdict, reasons, H_exp, H_max_abs, H_var, H_scale, frac, gap,
                          singular, active, gap_lam, source, t, lam, H, sigma, u)


def _path_activity(pr, t, x, u, pv, tol) -> np.ndarray:
    """Boolean (len(t),): some path constraint is at a bound at that sample."""
    if not pr.path:
        return np.zeros(len(t), dtype=bool)
    fn = ca.Function("hp", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in pr.path]),
                                                 ca.vertcat(*[c.lower for c in pr.path]),
                                                 ca.vertcat(*[c.upper for c in pr.path])])
    v, lo, hi = along(fn, x, np.asarray(u, dtype=float)[:, None], pv)
    sc = tol * np.maximum(1.0, np.abs(v))
    return np.any((np.abs(v - lo) <= sc) | (np.abs(v - hi) <= sc), axis=1)


def _bounds(pr, params) -> tuple[float, float]:
    from .switching import control_bounds_at

    return control_bounds_at(pr, pr.control_names[0], params)


def plot_certificate(cert: PMPCertificate, title: str | None = None):
    """H, sigma and u against time on three axes."""
    import matplotlib.pyplot as plt

    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(7, 6.5))
    a1.plot(cert.t, cert.H / cert.H_scale)
    a1.set_ylabel(r"$H / H_{scale}$")
    a2.plot(cert.t, cert.sigma, color="C1")
    a2.axhline(0, color="0.4", lw=0.7)
    a2.set_ylabel(r"switching function $\sigma = \lambda^T g$")
    a3.step(cert.t, cert.u, where="post", color="C2")
    a3.set_ylabel("control $u$")
    a3.set_xlabel(r"time $\tau$")
    for a in (a1, a2, a3):
        a.grid(alpha=0.3)
    a1.set_title(title or f"PMP certificate: {cert.verdict} "
                 f"(max|H| {cert.H_max_abs:.1e}, switch gap {cert.switch_sigma_gap:.1e})",
                 fontsize=9)
    fig.tight_layout()
    return fig
