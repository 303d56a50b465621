"""The per-arc table of a PMP certificate: each arc checked by the conditions of its type.

Arcs come from structure detection on a transcription (:func:`transcription_arcs`) or
from the modes of a refinement (:func:`refined_arcs`); samples (times, states,
controls, costates) from the transcription's multipliers or the refinement's adjoint
sweep. Per arc type (minimum principle, ``sigma_j = dH/du_j``):

* **bang** -- the control sits at the bound ``sign(sigma_j)`` selects;
* **control boundary** (a mixed or control-only constraint held) -- checked by the
  global checks (:mod:`ocp.certificate.checks`, the control set at each sample);
* **interior** (H strictly convex in ``u_j``) -- stationarity ``H_u = 0`` (residual
  relative to the size of its terms) and Legendre--Clebsch ``H_uu >= 0``;
* **singular** (H linear in ``u_j``, :mod:`ocp.structure.singular`) -- ``sigma`` and its
  derivatives up to ``2k - 1`` vanish, the control is the singular control
  ``-a / b`` of the derivatives (residual against the solution's control), Kelley's
  condition ``(-1)^k b >= 0``, and the order ``k`` is reported;
* **state boundary** -- :mod:`ocp.certificate.state_arcs`;
* every arc off a state constraint, on a transcription: the costate equation
  ``lambda' = -H_x`` in integral form between consecutive samples.

Margins: on a transcription a junction is known to a grid interval, so the samples
within ``margin`` of it are not judged.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.arcs import ArcStructure, control_bounds_at
from ..structure.constraint_kinds import STATE, constraint_kind
from ..structure.singular import singular_algebra
from ..transcriptions.solution import along
from .arc_record import FAILS, UNCERTAIN, ArcCheck
from .costates import pmp_functions


@dataclass
class ArcSamples:
    """What the per-arc checks read: samples of an extremal and how accurate they are.

    Attributes
    ----------
    problem : OptimalControlProblem
    values : dict
        Parameter (and decision variable) values by name.
    t, x, u, lam : ndarray
        Samples at which the pointwise conditions are checked.
    pairs : tuple of ndarray or None
        ``(ta, tb, la, lb, hx)``: consecutive costate samples and ``H_x`` integrated
        between them by the transcription's own rule (for the costate equation); None
        when the costate was integrated from that equation (a refinement).
    margin : float
        Samples this close to a junction are not judged (without ``mesh``).
    tol : float
        Allowed relative residual.
    error : float
        The samples' own relative error (the solution's accuracy).
    mesh : ndarray, optional
        The transcription's grid (shooting nodes or collocation mesh), when the samples
        come from one.
    """

    problem: OptimalControlProblem
    values: dict
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    lam: np.ndarray
    pairs: tuple[np.ndarray, ...] | None
    margin: float
    tol: float
    error: float
    mesh: np.ndarray | None = None

    def margin_at(self, t_j: float, factor: float = 1.0) -> float:
        """How far from a junction at ``t_j`` samples are not judged: ``factor * margin``
        (1.5 the longest mesh interval: a junction is known to a grid interval).

        Parameters
        ----------
        t_j : float
        factor : float
        """
        # (the longest mesh interval anywhere: a detected junction can be that far off)
        return factor * self.margin

    @property
    def pv(self) -> np.ndarray:
        """Parameter values in the problem's order."""
        return np.array([self.values[k] for k in self.problem.param_names], dtype=float)


def classify(pr: OptimalControlProblem, kind: str, control: str,
             constraint: str | None) -> tuple[str, str]:
    """The table's kind of a detected arc, and what it belongs to (control or constraint).

    Parameters
    ----------
    pr : OptimalControlProblem
    kind : str
        The structure's kind (``max``, ``min``, ``vertex``, ``boundary``, ``interior``,
        ``singular``).
    control : str
    constraint : str or None
        The held constraint of a boundary arc.
    """
    if kind in ("max", "min"):
        return "bang", control
    if kind == "vertex":
        return "control boundary", control
    if kind == "boundary":
        if constraint is not None and constraint_kind(pr, constraint) == STATE:
            return "state boundary", constraint
        return "control boundary", control
    j = pr.control_names.index(control)
    Huu = ca.hessian(ca.SX(pr.lagrange), pr.u[j])[0]
    return ("singular" if Huu.is_zero() else "interior"), control


def _spans(pr: OptimalControlProblem,
           arcs: list[tuple[str, str, float, float, str | None, str | None]]) -> list[ArcCheck]:
    out: list[ArcCheck] = []
    for kind, control, a, b, con, side in arcs:
        k, owner = classify(pr, kind, control, con)
        if k == "state boundary" and any(o.kind == k and o.control == owner and
                                         min(b, o.end) > max(a, o.start) for o in out):
            continue  # the same boundary arc seen from another control
        out.append(ArcCheck(k, owner, float(a), float(b),
                            side=side if k == "state boundary" else None))
    return sorted(out, key=lambda c: (c.start, c.control))


def transcription_arcs(pr: OptimalControlProblem, structure: ArcStructure) -> list[ArcCheck]:
    """Empty table rows for the arcs structure detection finds.

    Parameters
    ----------
    pr : OptimalControlProblem
    structure : ArcStructure
        From :func:`~ocp.structure.arcs.detect_structure`.
    """
    return _spans(pr, [(a.kind, s.control, a.start, a.end, a.constraint, a.side)
                       for s in structure.per_control for a in s.arcs])


def refined_arcs(ref: object) -> list[ArcCheck]:
    """Empty table rows for the arcs of a refinement (consecutive equal modes merged).

    Parameters
    ----------
    ref : RefinedSwitching
    """
    pr = ref.problem  # type: ignore[attr-defined]
    edges = np.r_[0.0, np.cumsum(ref.durations)]  # type: ignore[attr-defined]
    found = []
    for j, name in enumerate(pr.control_names):
        run = None
        for k, modes in enumerate(ref.interval_modes):  # type: ignore[attr-defined]
            m = modes[j]
            if run is not None and run[0] == m:
                run[2] = edges[k + 1]
                continue
            if run is not None:
                found.append((run[0].kind, name, run[1], run[2], run[0].constraint,
                              run[0].side))
            run = [m, edges[k], edges[k + 1]]
        if run is not None:
            found.append((run[0].kind, name, run[1], run[2], run[0].constraint,
                              run[0].side))
    return _spans(pr, found)


def inside_arc(s: ArcSamples, arc: ArcCheck, t: np.ndarray, factor: float = 1.0) -> np.ndarray:
    """Samples inside the arc, ``factor`` margins away from its junctions (not from the
    horizon's ends, which are no junctions).

    Parameters
    ----------
    s : ArcSamples
    arc : ArcCheck
    t : ndarray
        The times to select from.
    factor : float
        Margins (:meth:`ArcSamples.margin_at`) kept from each junction.
    """
    t0, T = float(np.min(s.t)), float(np.max(s.t))
    first = arc.start <= 1e-12 or arc.start <= t0 - 1e-12
    last = arc.end >= T - 1e-12 and arc.end >= float(np.max(t)) - 1e-12
    lo = arc.start + (0.0 if first else s.margin_at(arc.start, factor))
    hi = arc.end - (0.0 if last else s.margin_at(arc.end, factor))
    return (t >= lo - 1e-12) & (t <= hi + 1e-12)


def check_arcs(arcs: list[ArcCheck], s: ArcSamples) -> None:
    """Fill each row of the table with the conditions of its type (in place).

    Parameters
    ----------
    arcs : list of ArcCheck
    s : ArcSamples
    """
    pr, pv = s.problem, s.pv
    fns = pmp_functions(pr)
    sigma = along(fns.sigma, s.x, s.u, s.lam, pv)[0]
    terms = along(fns.sigma_terms, s.x, s.u, s.lam, pv)[0]
    for arc in arcs:
        sel = inside_arc(s, arc, s.t)
        if arc.kind == "state boundary":
            continue  # ocp.certificate.state_arcs
        if sel.sum() < 2:
            if arc.kind == "bang":  # the global checks cover bang arcs
                arc.notes.append("too short for its own row: the global checks cover it")
            else:
                arc.mark(UNCERTAIN, "too few samples inside the arc to check it")
            continue
        j = pr.control_names.index(arc.control)
        scale = max(float(np.max(terms[sel, j])), 1e-300)
        if arc.kind == "bang":
            _bang(arc, s, sel, j, sigma[:, j])
        elif arc.kind == "interior":
            arc.judge("stationarity |H_u|", float(np.max(np.abs(sigma[sel, j]))) / scale,
                      s.tol, s.error, "H_u = 0 on an interior arc, relative to its terms")
            Huu = along(fns.Huu, s.x[sel], pv)[0].reshape(-1, pr.nu, pr.nu)[:, j, j]
            big = max(float(np.max(np.abs(Huu))), 1e-300)
            arc.judge("Legendre-Clebsch -min H_uu", max(0.0, -float(np.min(Huu))) / big, s.tol,
                      s.error, "H_uu >= 0")
            arc.residuals["min H_uu"] = float(np.min(Huu))
        elif arc.kind == "singular":
            _singular(arc, s, sel, j, scale)
        if s.pairs is not None:
            _costate_equation(arc, s)


def _bang(arc: ArcCheck, s: ArcSamples, sel: np.ndarray, j: int, sig: np.ndarray) -> None:
    lo, hi = control_bounds_at(s.problem, arc.control, s.values)
    band = s.tol * max(float(np.max(np.abs(sig))), 1e-300)
    clear = sel & (np.abs(sig) > band)
    want = np.where(sig < 0, hi, lo)
    rng = max(1.0, hi - lo) if np.isfinite(hi - lo) else 1.0
    ok = np.abs(s.u[:, j] - want) <= 1e-3 * rng
    frac = float(np.mean(ok[clear])) if clear.any() else 1.0
    arc.judge("off the bound sign(sigma) selects", 1.0 - frac, 0.01, 0.0,
              "fraction of the arc where sigma is clearly non-zero")


def _singular(arc: ArcCheck, s: ArcSamples, sel: np.ndarray, j: int, scale: float) -> None:
    pr, pv = s.problem, s.pv
    alg = singular_algebra(pr, arc.control)
    if alg.order is None:
        arc.mark(UNCERTAIN, f"no singular order: {alg.reason}")
        return
    arc.order = alg.order
    fn = alg.functions(pr)
    d, law, kel = along(fn, s.x, s.u, s.lam, pv)
    x, lam = s.x[sel], s.lam[sel]
    for i in range(d.shape[1]):
        # the size of the terms of sigma^(i): its gradient times the state and costate
        g = ca.Function("g", [pr.x, pr.u, alg.lam, pr.p], [ca.jacobian(alg.derivatives[i],
                                                                     ca.vertcat(pr.x, alg.lam))])
        G = along(g, x, s.u[sel], lam, pv)[0]
        size = float(np.max(np.sum(np.abs(G * np.c_[x, lam]), axis=1)))
        sc = max(size, float(np.max(np.abs(d[:, i]))), scale if i == 0 else 0.0, 1e-300)
        arc.judge(f"sigma^({i})" if i else "sigma", float(np.max(np.abs(d[sel, i]))) / sc,
                  s.tol, s.error, f"d^{i} sigma/dt^{i} = 0 on a singular arc")
    lo, hi = control_bounds_at(pr, arc.control, s.values)
    rng = hi - lo if np.isfinite(hi - lo) else max(1.0, float(np.max(np.abs(s.u[:, j]))))
    arc.judge("singular control |u - u_s|", float(np.max(np.abs(s.u[sel, j] - law[sel, 0])))
              / rng, s.tol, s.error, "the control against the singular control -a/b of "
              f"d^{2 * alg.order} sigma/dt^{2 * alg.order} = a + b u")
    k = kel[sel, 0]
    big = max(float(np.max(np.abs(k))), 1e-300)
    arc.residuals["Kelley (-1)^k b min"] = float(np.min(k))
    if float(np.min(k)) < -s.tol * big:
        arc.mark(FAILS if float(np.max(k)) < 0 else UNCERTAIN,
                 f"Kelley's condition (-1)^{alg.order} b >= 0 fails: min {np.min(k):.3g}")
    elif float(np.min(k)) <= s.tol * big:
        arc.mark(UNCERTAIN, "Kelley's coefficient (-1)^k b vanishes on the arc: the "
                 "generalised Legendre-Clebsch condition is degenerate, not decided")


def _costate_equation(arc: ArcCheck, s: ArcSamples) -> None:
    """``lambda(t_b) - lambda(t_a) + int H_x`` accumulated over the arc, relative to the
    costate's size there."""
    assert s.pairs is not None
    ta, tb, la, lb, hx = s.pairs
    sel = inside_arc(s, arc, ta) & inside_arc(s, arc, tb)
    if sel.sum() < 2:
        return
    step = lb[sel] - la[sel] + hx[sel] * (tb[sel] - ta[sel])[:, None]
    resid = np.abs(np.cumsum(step, axis=0))
    # relative to the costate's size over the horizon (it may vanish on a singular arc)
    size = max(float(np.max(np.abs(np.r_[la, lb]))),
               float(np.max(np.sum(np.abs(hx) * (tb - ta)[:, None], axis=0))), 1e-300)
    arc.judge("costate equation", float(np.max(resid)) / size, s.tol, s.error,
              "lambda' = -H_x, integrated over the arc")


__all__ = ["ArcSamples", "check_arcs", "classify", "inside_arc", "refined_arcs",
           "transcription_arcs"]
