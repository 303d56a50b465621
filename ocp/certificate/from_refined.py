"""The PMP certificate of a refined solution (:class:`~ocp.structure.switching.RefinedSwitching`).

The costate is the adjoint integrated backward jointly with the state along the
refined arcs (:func:`ocp.certificate.costates.adjoint_sweep`: exact on affine arcs, RK8 at two
step counts otherwise, so the certificate knows its own numerical error). Where a
state constraint is active (a boundary arc, a constraint touching its limit, a
binding path multiplier) the costate may jump: the checks cover the part after
the last constrained time (:func:`constrained_refined`). Mixed constraints
``c(x, u)`` tighten the control bounds the minimum principle selects
(:func:`effective_bounds`). The costate from the transcription's multipliers is
compared with the swept one (``costate_estimates_gap``).
"""


from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.arcs import TranscribedSolution, no_control_crosses
from ..structure.switching import RefinedSwitching
from ..transcriptions.gridview import grid_spacing
from ..transcriptions.solution import along
from .arc_record import HOLDS, ArcCheck
from .arc_table import refined_table
from .arc_verdict import covered, junction_margin
from .checks import (
    ERROR_MARGIN,
    INCONCLUSIVE,
    Tolerances,
    figures,
    intervals_of,
    judge,
    verdict_of,
)
from .costates import adjoint_sweep, costates_from_multipliers, pmp_functions
from .refined_state_arcs import copy_rows, refined_boundary_rows
from .result import PMPCertificate, build_certificate, not_applicable


def is_mixed(pr: OptimalControlProblem, name: str | None) -> bool:
    """True when path constraint ``name`` involves a control (a mixed constraint
    ``c(x, u)``): held on a boundary arc it bounds the control, the costate does not jump.

    Parameters
    ----------
    pr : OptimalControlProblem
    name : str or None
        A path constraint's name (None: False).
    """
    return any(c.name == name and ca.depends_on(c.expr, pr.u) for c in pr.structure_path)


def effective_bounds(pr: OptimalControlProblem, x: np.ndarray,
                     pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Control bounds tightened by the mixed constraints, at each sample: (m, nu) each.

    A mixed constraint ``lo <= a(x) + b(x) u_j <= hi`` affine in one control ``u_j``
    bounds it to an interval; the minimum principle then selects the ends of the
    intersection. Constraints in several controls are not used here: linear
    control-only ones couple controls into a polytope, checked by
    :func:`ocp.certificate.checks.figures` (the Hamiltonian minimised over it, a linear programme).

    Parameters
    ----------
    pr : OptimalControlProblem
    x : ndarray (m, nx)
        States at the samples.
    pv : ndarray
        Parameter values.
    """
    m = len(x)
    los, his = np.empty((m, pr.nu)), np.empty((m, pr.nu))
    for j, name in enumerate(pr.control_names):
        # the control set at each sample: its limits may move with a state (a decision
        # variable refined as a constant state, ocp.structure.variables)
        lo, hi = pr.control_limits[name]
        lo_v, hi_v = along(ca.Function("b", [pr.x, pr.p], [lo, hi]), x, pv)
        los[:, j], his[:, j] = lo_v.ravel(), hi_v.ravel()
    for c in pr.structure_path:
        uses = [j for j in range(pr.nu) if ca.depends_on(c.expr, pr.u[j])]
        if len(uses) != 1 or ca.depends_on(ca.jacobian(c.expr, pr.u), pr.u):
            continue
        j = uses[0]
        a = ca.substitute(c.expr, pr.u, ca.DM.zeros(pr.nu))
        fn = ca.Function("ab", [pr.x, pr.p], [a, ca.jacobian(c.expr, pr.u[j]), c.lower,
                                              c.upper])
        av, bv, lc, hc = (v.ravel() for v in along(fn, x, pv))
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.stack([(lc - av) / bv, (hc - av) / bv])
        ok = np.abs(bv) > 1e-300
        los[ok, j] = np.maximum(los[ok, j], np.min(ends, axis=0)[ok])
        his[ok, j] = np.minimum(his[ok, j], np.max(ends, axis=0)[ok])
    return los, his


def path_activity_along(pr: OptimalControlProblem, x: np.ndarray, u: np.ndarray,
                        pv: np.ndarray, tol: float, state_only: bool = False,
                        bounds: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Where some path constraint is within ``tol * max(1, |value|)`` of a limit.

    Parameters
    ----------
    pr : OptimalControlProblem
    x, u : ndarray (m, nx), (m, nu)
        States and controls at the samples.
    pv : ndarray
        Parameter values.
    tol : float
    state_only : bool
        Leave out the mixed constraints (those involving a control).
    bounds : (ndarray, ndarray), optional
        The control set's box at the samples (:func:`effective_bounds`): a state
        constraint at a limit no admissible control could cross there does not count
        (:func:`ocp.certificate.checks.no_control_crosses`).

    Returns
    -------
    ndarray of bool (m,)
    """
    cons = [c for c in pr.structure_path if not (state_only and ca.depends_on(c.expr, pr.u))]
    if not cons:
        return np.zeros(len(x), dtype=bool)
    fn = ca.Function("hp", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in cons]),
                                                 ca.vertcat(*[c.lower for c in cons]),
                                                 ca.vertcat(*[c.upper for c in cons])])
    v, lo, hi = along(fn, x, u, pv)
    sc = tol * np.maximum(1.0, np.abs(v))
    at_lo, at_hi = np.abs(v - lo) <= sc, np.abs(v - hi) <= sc
    if bounds is not None:
        for i, c in enumerate(cons):
            if ca.depends_on(c.expr, pr.u):
                continue
            for side, at in (("lower", at_lo), ("upper", at_hi)):
                if at[:, i].any():
                    at[:, i] &= ~no_control_crosses(pr, c, side, x, *bounds, pv)
    return np.any(at_lo | at_hi, axis=1)


def _effective_switches(ref: RefinedSwitching, after: float) -> dict[str, list[float]]:
    """Switch times of every control after ``after``, ignoring zero-length intervals: the
    switches between two bang arcs (a junction with a singular arc is no sign change of
    sigma, which vanishes on that arc; its row in the per-arc table checks it)."""
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    tiny = 1e-10 * max(edges[-1], 1.0)
    out: dict[str, list[float]] = {}
    im = ref.interval_modes
    for j, name in enumerate(ref.controls):
        modes = [(im[k][j], edges[k + 1]) for k in range(len(ref.durations))
                 if ref.durations[k] > tiny]
        out[name] = [float(e) for (m, e), (m2, _) in zip(modes[:-1], modes[1:], strict=True)
                     if m != m2 and e > after + tiny and "singular" not in (m.kind, m2.kind)]
    return out


def constrained_refined(ref: RefinedSwitching, n: int) -> tuple[list[tuple[float, float]],
                                                                float]:
    """State-constrained intervals of a refined solution, and the last time the costate
    may jump (end of a boundary arc, or a path constraint binding at a sample).

    Parameters
    ----------
    ref : RefinedSwitching
    n : int
        About how many samples along it.

    Returns
    -------
    intervals : list of (float, float)
        Boundary arcs of state constraints and runs where one touches its limit.
    last : float
        The last time the costate may jump (0 when none).
    """
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    T = float(edges[-1])
    tiny = 1e-10 * max(T, 1.0)
    pr = ref.problem
    # boundary arcs of state constraints; a zero-length one is a touch point (the costate
    # may jump there too)
    bnd = [(float(edges[k]), float(edges[k + 1])) for k, ms in enumerate(ref.interval_modes)
           if any(m.kind == "boundary" and not is_mixed(pr, m.constraint) for m in ms)]
    last = max((b for _, b in bnd), default=0.0)
    t, x, u, _ = ref.samples(n)
    act = path_activity_along(pr, x, u, ref.pv, 1e-7, state_only=True,
                              bounds=effective_bounds(pr, x, ref.pv)) & (t > tiny) & \
        (t < T - tiny)
    dense = intervals_of(t, act, 2 * T / max(len(t), 1))
    # the constraint's measure lives where it is active: the costate may jump anywhere there,
    # not only at the path rows whose multipliers the refinement made non-zero (they are
    # degenerate where the constraint is redundant, m >= m_f with m(T) = m_f and m' <= 0)
    for _, b in dense:
        last = max(last, T if b >= T - 2 * T / max(len(t), 1) else b)
    if ref.nlp is not None and "path" in ref.blocks and len(ref.lam_g):
        rows = ref.blocks["path"]
        lam = np.abs(ref.lam_g[rows])
        binding = lam > 1e-8 * max(1.0, float(np.max(np.abs(ref.lam_g))))
        if binding.any():
            last = max(last, float(np.max(ref.nlp.row_times(ref.w)[rows][binding])))
    merged: list[tuple[float, float]] = []
    for a, b in sorted(bnd + dense):
        if merged and a <= merged[-1][1] + tiny:
            merged[-1] = (merged[-1][0], max(b, merged[-1][1]))
        else:
            merged.append((a, b))
    return merged, last


def certify_refined(sol: TranscribedSolution, ref: RefinedSwitching, tol: Tolerances,
                    n: int) -> PMPCertificate:
    """The certificate of a refined solution, checked after its last constrained time.

    Parameters
    ----------
    sol : TranscribedSolution
        The transcription it was refined from (its multipliers give the second costate
        estimate).
    ref : RefinedSwitching
    tol : Tolerances
    n : int
        About how many samples along ``ref``.

    Returns
    -------
    PMPCertificate
    """
    pr = ref.problem
    active, last = constrained_refined(ref, n)
    T = float(np.sum(ref.durations))
    tiny = 1e-10 * max(T, 1.0)
    if last >= T - tiny:  # constrained to the end: no unconstrained costate to sweep
        spans = ", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in active)
        cert = not_applicable(INCONCLUSIVE, [
            f"state constraint active on {spans}, up to the final time: the costate may jump "
            "anywhere there, so no part of the horizon is checked from the refinement"])
        cert.state_constraint_active_intervals, cert.checked_from = active, T
        return cert
    sw = adjoint_sweep(ref, last, n)
    keep = (sw.t >= last - tiny) & (ref.durations[sw.interval] > tiny)
    switches = _effective_switches(ref, last)
    values = {**ref.params, **ref.variables}  # the control set at the variables' values
    floor = np.zeros(pr.nu)
    args = (switches, tol.sigma)
    mixed = any(ca.depends_on(c.expr, pr.u) for c in pr.structure_path) or any(
        ca.depends_on(ca.vertcat(*pr.control_limits[n]), pr.x) for n in pr.control_names)
    eff = effective_bounds(pr, sw.x[keep], ref.pv) if mixed else None
    fig = figures(pr, values, sw.t[keep], sw.x[keep], sw.u[keep], sw.lam[keep],
                  sw.H_expected, np.zeros(int(keep.sum()), bool), *args, floor, 1e-9,
                  tol.singular, bounds=eff, T_side=sw.T_side)
    base = (ref.integration_error or 0.0) + sw.error_x
    err = {"H": base, "sigma": 0.0, "switch": 0.0, "costate": sw.error_lam, "state": sw.error_x}
    if sw.coarse is not None:
        c = sw.coarse
        cf = figures(pr, values, c.t[keep], c.x[keep], c.u[keep], c.lam[keep],
                     c.H_expected, np.zeros(int(keep.sum()), bool), *args, floor, 1e-9,
                     tol.singular, bounds=effective_bounds(pr, c.x[keep], ref.pv)
                     if mixed else None, T_side=c.T_side)
        err["H"] += float(np.max(np.abs(fig.H - cf.H), initial=0.0)) / fig.H_scale
        dsig = np.max(np.abs(fig.sigma - cf.sigma), axis=0, initial=0.0)
        # relative to the size of sigma's terms (sigma itself vanishes on interior arcs)
        terms = along(pmp_functions(pr).sigma_terms, sw.x[keep], sw.u[keep], sw.lam[keep],
                      ref.pv)[0]
        err["sigma"] = float(np.max(dsig / np.maximum(np.maximum(
            np.max(np.abs(fig.sigma), axis=0), np.max(terms, axis=0, initial=0.0)), 1e-300)))
        err["switch"] = max((abs(fig.gap[k] - cf.gap[k]) for k in fig.gap
                             if math.isfinite(fig.gap[k]) and math.isfinite(cf.gap[k])),
                            default=0.0)
        # samples inside the numerical error band of sigma are not judged
        fig = figures(pr, values, sw.t[keep], sw.x[keep], sw.u[keep], sw.lam[keep],
                      sw.H_expected, np.zeros(int(keep.sum()), bool), *args,
                      ERROR_MARGIN * dsig, 1e-9, tol.singular, bounds=eff, T_side=sw.T_side)
    arcs = refined_table(ref, sw.t[keep], sw.x[keep], sw.u[keep], sw.lam[keep], tol.sigma,
                         max(err["H"], err["costate"], err["sigma"]))
    fig.singular = [r for r in fig.singular if not covered(arcs, r, margin=tol.singular)]
    definite, uncertain = judge(fig, tol, err, sw.H_expected is not None)
    H_after = sw.H_expected if sw.H_expected is not None and not sw.T_side else \
        float(np.median(fig.H))
    arcs, left, start = constrained_rows(sol, ref, arcs, (sw.t[keep], sw.lam[keep]), H_after,
                                         tol, max(err["H"], err["costate"], err["sigma"]),
                                         active, last, n)
    verdict, reasons = verdict_of(definite, uncertain, left, start, T)
    gap_lam = _costate_gap(sol, ref, sw.t[keep], sw.lam[keep], last)
    src = "refined (adjoint integrated with the state along the refined arcs: " + (
        "exact arcs)" if ref.exact else f"RK8, error measured {sw.error_lam:.1e})")
    cert = build_certificate(verdict, reasons, sw.H_expected, fig, active, gap_lam, src,
                             sw.t[keep], sw.lam[keep], sw.u[keep], err, start)
    cert.arcs = arcs
    return cert


def constrained_rows(sol: TranscribedSolution, ref: RefinedSwitching, arcs: list[ArcCheck],
                     sweep: tuple[np.ndarray, np.ndarray], H_after: float, tol: Tolerances,
                     error: float, active: list[tuple[float, float]], last: float,
                     n: int) -> tuple[list[ArcCheck], list[tuple[float, float]], float]:
    """The rows of the part before the last constrained time: state boundary arcs (their
    multipliers and jumps, :mod:`ocp.certificate.refined_state_arcs`) and interior arcs
    with their costate copies; the active spans those boundary rows do not answer, and
    where the checked part starts (0 when holding rows cover all before ``last``).

    Parameters
    ----------
    sol : TranscribedSolution
    ref : RefinedSwitching
    arcs : list of ArcCheck
        The swept part's rows.
    sweep : (ndarray, ndarray)
        The sweep's times and costates.
    H_after : float
        H on the swept part.
    tol : Tolerances
    error : float
    active : list of (float, float)
        State-constrained spans.
    last : float
        The last constrained time.
    n : int
        About how many samples along ``ref``.
    """
    rows = refined_boundary_rows(ref, sol, sweep, tol.sigma, error, junction_margin(sol))
    rows += copy_rows(ref, last, H_after, tol.sigma, error, n)
    out = sorted(arcs + rows, key=lambda r: (r.start, r.control))
    left = [a for a in active if not covered(rows, a, kinds=("state boundary",),
                                             statuses=(HOLDS,), margin=tol.singular)]
    start = 0.0 if last > 0 and covered(out, (0.0, last), statuses=(HOLDS,)) else last
    return out, left, start


def _costate_gap(sol: TranscribedSolution, ref: RefinedSwitching, t: np.ndarray, lam: np.ndarray,
                 start: float) -> float:
    """Largest difference between the multiplier and the adjoint costates, relative."""
    t_tr, lam_tr = costates_from_multipliers(sol)
    t_tr = t_tr - float(getattr(sol, "t0", 0.0) or 0.0)  # the refinement's time starts at 0
    h = grid_spacing(sol)
    # common horizon, without the transcription's last interval (where its final
    # time, and any constrained tail, differ from the refined ones)
    end = float(sol.T) - float(getattr(sol, "t0", 0.0) or 0.0)
    sel = (t_tr <= min(float(np.sum(ref.durations)), end) - h) & (t_tr >= start + h)
    if not sel.any() or len(t) < 2:
        return math.nan
    order = np.argsort(t, kind="stable")
    # (a refinement with decision variables has them as the last states: not in sol)
    lam = lam[:, :lam_tr.shape[1]]
    lam_i = np.column_stack([np.interp(t_tr[sel], t[order], lam[order, j])
                             for j in range(lam.shape[1])])
    return float(np.max(np.abs(lam_i - lam_tr[sel])) / max(np.max(np.abs(lam)), 1e-300))
