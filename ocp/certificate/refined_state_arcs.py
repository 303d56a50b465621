"""Boundary arcs of state constraints on a refined solution: multipliers and junction jumps.

The refinement gives the arc's exact junctions ``t1 < t2`` and the costate on both sides
where an interior run borders it (its costate copy, :mod:`ocp.structure.costate_copies`)
or where the adjoint sweep from ``T`` reaches it. Across the arc the costate is rebuilt by
*indirect adjoining* (Bryson, Denham and Dreyfus 1963; Hartl, Sethi and Vickson 1995,
sec. 4): with ``c`` of order ``p`` (held at its upper limit; a lower limit is ``-c``),
``H~ = H + nu c^(p)``, the boundary control ``u_j`` makes ``H~_u = 0``, so
``nu = -H_u / dc^(p)/du_j``, and ``lambda~' = -H~_x`` is integrated backward from
``lambda~(t2) = lambda(t2+)`` (continuous at the exit). The direct-adjoining costate is
``lambda = lambda~ + sum_k a_k grad c^(k)`` with ``a_(p-1) = nu``, ``a_(k-1) = -a_k'``, so
its measure has the density ``mu = -a_0'`` on the arc and the jumps ``eta1 = pi_0 -
a_0(t1+)`` at the entry, ``eta2 = a_0(t2-)`` at the exit, where ``lambda(t1-) -
lambda~(t1+) = sum_k pi_k grad c^(k)``. The minimum principle (direct adjoining) asks:

* the entry jump of ``lambda~`` in the span of ``grad c^(k)``, ``k < p``, with
  ``pi_k = a_k(t1+)`` for ``k >= 1`` (the direct costate jumps along ``grad c`` only);
* ``a_k(t2-) = 0`` for ``k >= 1`` (the same at the exit);
* ``eta1 >= 0``, ``eta2 >= 0`` and ``mu >= 0`` (``a_0`` non-increasing on the arc).

The transcription's own multipliers of the constraint (its path rows, where the
constraint is one: :func:`transcription_measure`) add up to the total measure
``eta1 + int mu + eta2 = pi_0``: a second, independent reading of it.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.arcs import TranscribedSolution
from ..structure.constraint_kinds import STATE, constraint_kind
from ..structure.costate_copies import copy_of
from ..structure.flows import path_constraint
from ..transcriptions.gridview import is_collocation, mesh_indices
from ..transcriptions.solution import along
from .arc_conditions import ArcSamples, check_arcs, refined_arcs
from .arc_record import FAILS, UNCERTAIN, ArcCheck
from .costates import pmp_functions
from .state_arcs import constraint_order

TOUCH = 1e-4
"""A refined boundary arc no longer than this fraction of the horizon, whose conditions fail,
is uncertain, not refuted: it cannot be told from a touch point."""


def boundary_spans(ref: object) -> list[tuple[int, int, str, str]]:
    """``(first, last, constraint, side)`` interval indices of each state boundary arc.

    Parameters
    ----------
    ref : RefinedSwitching
    """
    out: list[tuple[int, int, str, str]] = []
    pr = ref.problem  # type: ignore[attr-defined]
    for k, modes in enumerate(ref.interval_modes):  # type: ignore[attr-defined]
        held = [m for m in modes if m.kind == "boundary" and m.constraint is not None
                and constraint_kind(pr, m.constraint) == STATE]
        if not held:
            continue
        m = held[0]
        if out and out[-1][1] == k - 1 and out[-1][2] == m.constraint:
            out[-1] = (out[-1][0], k, m.constraint, str(m.side))
        else:
            out.append((k, k, m.constraint, str(m.side)))
    return out


def _indirect(org: OptimalControlProblem, name: str, side: str, j: int) -> ca.Function:
    """``(x, u, lam, p) -> (H~_x, nu, [c^(k)]_k, [grad c^(k)]_k)`` of the arc."""
    c = path_constraint(org, name).expr * (1.0 if side == "upper" else -1.0)
    p = constraint_order(org, name) or 0
    ders = [c]
    for _ in range(p):
        ders.append(ca.jtimes(ders[-1], org.x, org.rhs))
    lam = ca.SX.sym("lam", org.nx)
    H = ca.SX(org.lagrange) + ca.dot(lam, org.rhs)
    cp = ders[p]
    nu = -ca.jacobian(H, org.u[j]) / ca.jacobian(cp, org.u[j])
    Hx = ca.gradient(H, org.x) + nu * ca.gradient(cp, org.x)
    grads = ca.horzcat(*[ca.gradient(d, org.x) for d in ders[:p]])
    return ca.Function("indirect", [org.x, org.u, lam, org.p], [Hx, nu, grads])


def _sweep(fn: ca.Function, t: np.ndarray, x: np.ndarray, u: np.ndarray, lam_end: np.ndarray,
           pv: np.ndarray, stride: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``lambda~`` backward over every ``stride``-th sample (Heun's rule on the linear
    equation), ``nu`` there, and the samples' indices."""
    idx = np.r_[np.arange(0, len(t) - 1, stride), len(t) - 1]
    lam = np.empty((len(idx), len(lam_end)))
    lam[-1] = lam_end
    for i in range(len(idx) - 1, 0, -1):
        a, b = idx[i - 1], idx[i]
        h = t[b] - t[a]
        fb = np.array(fn(x[b], u[b], lam[i], pv)[0], dtype=float).ravel()
        fa = np.array(fn(x[a], u[a], lam[i] + h * fb, pv)[0], dtype=float).ravel()
        lam[i - 1] = lam[i] + 0.5 * h * (fa + fb)
    nu = np.array([float(fn(x[k], u[k], lam[i], pv)[1]) for i, k in enumerate(idx)])
    return lam, nu, idx


def _derivatives(t: np.ndarray, nu: np.ndarray, p: int) -> tuple[np.ndarray, np.ndarray]:
    """``a_k`` (k = 0..p-1) at both ends of the arc and ``a_0`` along it, from a polynomial
    fit of ``nu`` (degree p + 2, or the samples' count)."""
    s = (t - t[0]) / max(t[-1] - t[0], 1e-300)
    coef = np.polynomial.polynomial.polyfit(s, nu, min(p + 2, len(t) - 1))
    ends = np.zeros((2, p))
    a0 = nu.copy()
    for k in range(p - 1, -1, -1):
        d = np.polynomial.polynomial.polyder(coef, p - 1 - k) / max(t[-1] - t[0], 1e-300) ** (
            p - 1 - k) * (-1) ** (p - 1 - k)
        ends[:, k] = np.polynomial.polynomial.polyval([0.0, 1.0], d)
        if k == 0:
            a0 = np.polynomial.polynomial.polyval(s, d)
    return ends, a0


def check_refined_boundary(arc: ArcCheck, org: OptimalControlProblem, j: int,
                           t: np.ndarray, x: np.ndarray, u: np.ndarray, pv: np.ndarray,
                           before: np.ndarray | None, after: np.ndarray | None,
                           tol: float, error: float) -> None:
    """Fill a refined state boundary arc's row (in place): see the module docstring.

    Parameters
    ----------
    arc : ArcCheck
        The row (``control`` is the constraint's name, ``side`` its limit).
    org : OptimalControlProblem
        The problem (without costate copies).
    j : int
        The boundary control's index.
    t, x, u : ndarray
        Samples of the arc (states of ``org``).
    pv : ndarray
    before, after : ndarray or None
        ``lambda(t1-)`` and ``lambda(t2+)`` (None: not known there).
    tol, error : float
        Allowed relative residual and the refinement's error.
    """
    p = constraint_order(org, arc.control) or 0
    arc.order = p
    c = path_constraint(org, arc.control)
    lim = c.upper if arc.side == "upper" else c.lower
    val, lv = along(ca.Function("c", [org.x, org.p], [c.expr, lim]), x, pv)
    arc.judge("on the constraint |c - limit|", float(np.max(np.abs(val - lv)))
              / max(1.0, float(np.max(np.abs(lv)))), tol, error, "held on the refined arc")
    if after is None or before is None or p < 1:
        arc.mark(UNCERTAIN, "the costate beside the refined arc is not known (no interior run "
                 "or swept part borders it), or the constraint has no order: its multipliers "
                 "were not checked")
        return
    fn = _indirect(org, arc.control, str(arc.side), j)
    lam, nu, _ = _sweep(fn, t, x, u, after, pv, 1)
    lam2, nu2, idx2 = _sweep(fn, t, x, u, after, pv, 2)  # half the samples: the error
    size = max(float(np.max(np.abs(np.r_[before, after]))), 1e-300)
    err = max(error, float(np.max(np.abs(lam[0] - lam2[0]))) / size)
    err_nu = float(np.max(np.abs(nu[idx2] - nu2)))
    ends, a0 = _derivatives(t, nu, p)
    G = np.array(fn(x[0], u[0], lam[0], pv)[2], dtype=float).reshape(org.nx, p)
    pi, *_ = np.linalg.lstsq(G, before - lam[0], rcond=None)
    perp = before - lam[0] - G @ pi
    gnorm = np.linalg.norm(G, axis=0)
    Ge = np.array(fn(x[-1], u[-1], lam[-1], pv)[2], dtype=float).reshape(org.nx, p)
    arc.judge("entry jump across span grad c^(k)", float(np.max(np.abs(perp))) / size, tol, err,
              "lambda~ jumps at the entry along grad c, ..., grad c^(p-1)")
    if p > 1:
        arc.judge("entry jump across grad c^(k>=1)", float(np.max(np.abs(
            (pi[1:] - ends[0, 1:]) * gnorm[1:]))) / size, tol, err,
                  "the direct costate jumps along grad c only")
        arc.judge("exit a_k, k >= 1", float(np.max(np.abs(ends[1, 1:] * np.linalg.norm(
            Ge, axis=0)[1:]))) / size, tol, err, "no jump across grad c^(k>=1) at the exit")
    eta1, eta2 = float(pi[0] - ends[0, 0]), float(ends[1, 0])
    rise = float(np.max(a0 - np.minimum.accumulate(a0)))  # a_0 must not increase: mu >= 0
    arc.residuals.update({"entry jump eta": eta1, "exit jump eta": eta2,
                          "total measure pi_0": float(pi[0]), "nu min": float(np.min(nu))})
    g0 = float(gnorm[0])
    for what, v in (("entry jump eta >= 0", -eta1), ("exit jump eta >= 0", -eta2),
                    ("density mu >= 0 (a_0 non-increasing)", rise)):
        arc.judge(what, max(0.0, v) * g0 / size, tol, err + err_nu * g0 / size,
                  "the constraint's multiplier is a non-negative measure")


def transcription_measure(sol: TranscribedSolution, name: str, side: str,
                          span: tuple[float, float], margin: float) -> float:
    """The transcription's multipliers of path constraint ``name`` summed over ``span`` (and
    ``margin`` either side): its total measure there; NaN when they are not at hand (a
    state bound's multipliers are bound multipliers of the NLP's variables).

    Parameters
    ----------
    sol : TranscribedSolution
    name : str
    side : str
        The limit held (the multipliers of a lower limit are negative in CasADi's sign).
    span : (float, float)
    margin : float
    """
    pr = sol.problem
    rows = [i for i, c in enumerate(pr.path) for _ in range(c.expr.numel())]
    names = [pr.path[i].name for i in rows]
    mult = sol.multipliers.get("path")
    if mult is None or name not in names:
        return math.nan
    col = names.index(name)
    m = np.asarray(mult, dtype=float).reshape(-1, len(names))[:, col]
    # (a row's multiplier: the measure at its point; collocation has no row at t0)
    t = np.asarray(sol.t[1:] if is_collocation(sol) else sol.t, dtype=float)
    sel = (t >= span[0] - margin) & (t <= span[1] + margin)
    total = float(np.sum(m[sel])) + inner_measure(sol, name, span, margin)
    return total * (1.0 if side == "upper" else -1.0)


def inner_measure(sol: TranscribedSolution, name: str, span: tuple[float, float],
                  margin: float) -> float:
    """The part of the measure of ``name`` held by its rows between the points
    (``inner_constraints``: Bernstein control points of the flagged intervals), over the
    intervals whose start lies in ``span`` (and ``margin`` either side); 0 without them."""
    disc, inner = getattr(sol, "discretization", None), sol.multipliers.get("path_inner")
    if inner is None or disc is None or np.size(inner) == 0:
        return 0.0
    if not is_collocation(sol):  # shooting: every row of check at the integrator's steps
        names = list(disc.cp.check_names)
        if name not in names:
            return 0.0
        lam = np.asarray(inner, dtype=float).reshape(disc.N, -1, len(names))
        starts = np.asarray(sol.t, dtype=float)[:disc.N]
        sel = (starts >= span[0] - margin) & (starts <= span[1] + margin)
        return float(np.sum(lam[sel, :, names.index(name)]))
    if getattr(disc, "Gin", None) is None:
        return 0.0
    rows = disc.checked_rows()
    names = [disc.cp.check_names[r] for r in rows]
    if name not in names:
        return 0.0
    idx = np.flatnonzero(disc.inner)
    lam = np.asarray(inner, dtype=float).reshape(idx.size, disc.inner_theta.size, len(rows))
    starts = np.asarray(sol.t, dtype=float)[mesh_indices(sol)][idx]
    sel = (starts >= span[0] - margin) & (starts <= span[1] + margin)
    return float(np.sum(lam[sel, :, names.index(name)]))


def refined_boundary_rows(ref: object, tsol: TranscribedSolution, sweep: tuple | None,
                          tol: float, error: float, margin: float,
                          points: int = 400) -> list[ArcCheck]:
    """The rows of every state boundary arc of a refined solution.

    Parameters
    ----------
    ref : RefinedSwitching
    tsol : TranscribedSolution
        Its transcription (the constraint's multipliers, a second reading).
    sweep : (t, lam) or None
        The adjoint sweep's samples after the last constrained time.
    tol, error : float
    margin : float
        The transcription's junction margin (its multipliers summed that far out).
    points : int
        Samples per arc.
    """
    pr = ref.problem  # type: ignore[attr-defined]
    lay = copy_of(pr)
    org = lay.origin if lay is not None else pr
    edges = np.r_[0.0, np.cumsum(ref.durations)]  # type: ignore[attr-defined]
    Z = ref.junctions()  # type: ignore[attr-defined]
    modes = ref.interval_modes  # type: ignore[attr-defined]
    pv = ref.pv  # type: ignore[attr-defined]
    rows = []
    for first, last, name, side in boundary_spans(ref):
        t1, t2 = float(edges[first]), float(edges[last + 1])
        arc = ArcCheck("state boundary", name, t1, t2, side=side)
        j = next(i for i, m in enumerate(modes[first]) if m.constraint == name)

        def copy_at(k: int, z: np.ndarray) -> np.ndarray | None:
            runs = [m.run for m in modes[k] if m.kind == "interior"] if 0 <= k < len(modes) \
                else []
            return z[lay.rows(runs[0])] if lay is not None and runs else None

        before = copy_at(first - 1, Z[first])
        after = copy_at(last + 1, Z[last + 1])
        if after is None and sweep is not None and len(sweep[0]) and sweep[0][0] <= t2 + 1e-9:
            after = sweep[1][int(np.argmin(np.abs(sweep[0] - t2)))][:org.nx]
        c = path_constraint(org, name).expr
        if before is None or after is None or ca.depends_on(c, ca.vertcat(org.t, org.t0,
                                                                         org.T)):
            continue  # no costate beside it (bang arcs are not swept): its span stays active
        t, x, u, k = ref.samples(points, focus=(first, last))  # type: ignore[attr-defined]
        sel = (k >= first) & (k <= last)
        check_refined_boundary(arc, org, j, t[sel], x[sel][:, :org.nx], u[sel], pv, before,
                               after, tol, error)
        total = transcription_measure(tsol, name, side, (t1, t2), margin)
        if math.isfinite(total) and "total measure pi_0" in arc.residuals:
            pi0 = arc.residuals["total measure pi_0"]
            arc.residuals["transcription's measure"] = total
            if total < 0 or abs(total - pi0) > 0.1 * max(abs(pi0), 1e-300):
                arc.mark(UNCERTAIN, f"the transcription's multipliers of {name!r} add up to "
                         f"{total:.4g}, the refined arc's measure is {pi0:.4g}")
        elif not math.isfinite(total):
            arc.notes.append("the transcription's multipliers of the constraint are not at "
                             "hand (a state bound's are the NLP's bound multipliers)")
        if arc.status == FAILS and t2 - t1 <= TOUCH * float(edges[-1]):
            # a boundary arc this short is a touch point's neighbourhood (Bryson-Denham at
            # l = 1/6: a 5e-6 arc, its conditions off by about its length): a touch point's
            # conditions are not a boundary arc's, so neither holds it to them nor refutes
            arc.status = UNCERTAIN
            arc.notes.append(f"the arc is {t2 - t1:.2g} long ({(t2 - t1) / edges[-1]:.1e} of "
                             "the horizon): it cannot be told from a touch point, whose "
                             "conditions are not checked")
        elif arc.status == FAILS:
            arc.notes.append("a multiplier of the state constraint has the wrong sign")
        rows.append(arc)
    return rows


def copy_rows(ref: object, before: float, H_after: float, tol: float, error: float,
              n: int) -> list[ArcCheck]:
    """Rows of the interior arcs that end by ``before`` (no swept costate there), checked
    with their run's costate copy; H there must equal ``H_after`` (H is continuous at the
    junctions of a state constraint of an autonomous problem).

    Parameters
    ----------
    ref : RefinedSwitching
    before : float
        The last constrained time (the sweep starts there).
    H_after : float
        H on the swept part (NaN: not compared).
    tol, error : float
    n : int
        About how many samples along ``ref``.
    """
    pr = ref.problem  # type: ignore[attr-defined]
    lay = copy_of(pr)
    if lay is None:
        return []
    t, x, u, k = ref.samples(n)  # type: ignore[attr-defined]
    modes = ref.interval_modes  # type: ignore[attr-defined]
    rows = [a for a in refined_arcs(ref) if a.kind == "interior" and a.end <= before + 1e-12]
    out = []
    inner = [kk for kk, ms in enumerate(modes) if any(m.kind == "interior" for m in ms)]
    for arc in rows:  # (by interval: a junction's sample belongs to both of its intervals)
        sel = (t >= arc.start) & (t <= arc.end) & np.isin(k, inner)
        runs = {m.run for kk in np.unique(k[sel]) for m in modes[int(kk)] if m.kind == "interior"}
        if len(runs) != 1:
            continue
        lam = np.zeros((int(sel.sum()), pr.nx))
        lam[:, :lay.nx] = x[sel][:, lay.rows(runs.pop())]
        values = {**ref.params, **getattr(ref, "variables", {})}  # type: ignore[attr-defined]
        s = ArcSamples(pr, values, t[sel], x[sel], u[sel], lam, None, 0.0, tol, error)
        check_arcs([arc], s)
        H = along(pmp_functions(pr).H, x[sel], u[sel], lam, s.pv)[0].ravel()
        if math.isfinite(H_after):
            scale = max(float(np.max(np.abs(lam[:, :lay.nx] * x[sel][:, :lay.nx]))), 1.0)
            arc.judge("H equal to its value after the constraint",
                      float(np.max(np.abs(H - H_after))) / scale, tol, error,
                      "H constant across the junctions (the costate copy of the run)")
        arc.notes.append("checked with the costate copy of its run (refined as states)")
        out.append(arc)
    return out


__all__ = ["boundary_spans", "check_refined_boundary", "copy_rows", "refined_boundary_rows",
           "transcription_measure"]
