"""Boundary arcs of state constraints: order, multiplier sign, costate jumps at junctions.

Direct adjoining (Hartl, Sethi & Vickson 1995): with a state constraint ``c(x) <= upper``
(``lower <= c(x)``) held on ``[t1, t2]``, the costate obeys ``d lambda = -H_x dt - s grad c
d eta`` with ``s = +1`` (``-1`` for a lower limit) and a measure ``eta`` that is
non-decreasing: on the arc's interior its density ``mu >= 0``, and at a junction the
costate may jump, ``lambda(t+) - lambda(t-) = -s eta_j grad c`` with ``eta_j >= 0``.
The control minimises H over the control set (the constraint does not enter that
minimisation): where it is inside its bounds, ``H_u = 0``. A transcription's
multiplier costates are these costates (the path rows' or bounds' multipliers
enter the adjoint equations at the nodes), so the certificate reads:

* the constraint's **order** ``p``: how often ``c`` is differentiated along the dynamics
  before a control appears (:func:`constraint_order`);
* **on the constraint**: ``|c - limit|`` on the arc;
* **the boundary control**: the control against the law ``d^p c/dt^p = 0`` (one control);
* **stationarity**: ``H_u = 0`` where the control is inside its bounds;
* **the multiplier's sign**: ``mu >= 0`` on the arc (from the costate equation in
  integral form: ``-s (Delta lambda + int H_x) . grad c / |grad c|^2``, non-decreasing),
  and ``eta_j >= 0`` at each junction, the jump measured between the costates
  extrapolated from both sides (linear extrapolation: exact where the costate is
  affine next to the junction), whose part across ``grad c`` must vanish.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.constraint_kinds import MAX_RELATIVE_DEGREE
from ..structure.flows import Mode, path_constraint
from ..structure.refinement import arc_dynamics
from ..transcriptions.solution import along
from .arc_conditions import ArcSamples, inside_arc
from .arc_record import FAILS, UNCERTAIN, ArcCheck
from .costates import pmp_functions


def constraint_order(pr: OptimalControlProblem, name: str) -> int | None:
    """The order of state constraint ``name`` (None above :data:`MAX_RELATIVE_DEGREE`).

    Parameters
    ----------
    pr : OptimalControlProblem
    name : str
    """
    d = path_constraint(pr, name).expr
    for p in range(MAX_RELATIVE_DEGREE + 1):
        if ca.depends_on(d, pr.u):
            return p
        d = ca.jtimes(d, pr.x, pr.rhs)
    return None


def check_state_arcs(arcs: list[ArcCheck], s: ArcSamples) -> None:
    """Fill the rows of the state boundary arcs (in place).

    Parameters
    ----------
    arcs : list of ArcCheck
        The table; only its ``"state boundary"`` rows are filled.
    s : ArcSamples
    """
    pr, pv = s.problem, s.pv
    for arc in arcs:
        if arc.kind != "state boundary":
            continue
        c = path_constraint(pr, arc.control)
        if ca.depends_on(ca.vertcat(c.expr, c.lower, c.upper), ca.vertcat(pr.t, pr.t0, pr.T)):
            arc.mark(UNCERTAIN, "a time-varying state constraint: its boundary arc's "
                     "conditions are not checked")
            continue
        arc.order = constraint_order(pr, arc.control)
        sign = 1.0 if arc.side == "upper" else -1.0
        fn = ca.Function("c", [pr.x, pr.p], [c.expr, ca.gradient(c.expr, pr.x),
                                             c.upper if arc.side == "upper" else c.lower])
        # a transcription zig-zags next to a boundary arc of order p over about p grid
        # intervals: its inside is judged (p + 1) margins from the junctions
        sel = inside_arc(s, arc, s.t, _factor(s, arc))
        if sel.sum() >= 2:
            val, _, lim = along(fn, s.x[sel], pv)
            scale = max(1.0, float(np.max(np.abs(lim))))
            arc.judge("on the constraint |c - limit|", float(np.max(np.abs(val - lim))) / scale,
                      s.tol, s.error, "the constraint held at its limit on the arc")
            _on_arc(arc, s, sel)
        else:
            arc.mark(UNCERTAIN, "too few samples inside the boundary arc to check it")
        if s.pairs is not None:
            _density(arc, s, fn, sign)
            for t_j, what in ((arc.start, "entry"), (arc.end, "exit")):
                if s.t[0] + s.margin_at(t_j) < t_j < float(np.max(s.t)) - s.margin_at(t_j):
                    _jump(arc, s, fn, sign, t_j, what)


def _factor(s: ArcSamples, arc: ArcCheck) -> float:
    """Margins kept from the junctions inside a boundary arc: a transcription zig-zags
    next to a boundary arc of order p over about p grid intervals, so p + 1 margins, but
    never more than leaves half the arc."""
    room = 0.25 * (arc.end - arc.start) / max(s.margin, 1e-300)
    return max(1.0, min(1.0 + (arc.order or 0), room))


def _on_arc(arc: ArcCheck, s: ArcSamples, sel: np.ndarray) -> None:
    """The boundary control law (one control) and ``H_u = 0`` where the control is free."""
    pr, pv = s.problem, s.pv
    fns = pmp_functions(pr)
    sig = along(fns.sigma, s.x[sel], s.u[sel], s.lam[sel], pv)[0]
    # the terms' size over the horizon: on the arc they may all vanish (u = 0, lambda = 0)
    terms = along(fns.sigma_terms, s.x, s.u, s.lam, pv)[0]
    for j, name in enumerate(pr.control_names):
        lo, hi = (float(ca.DM(b)) if ca.SX(b).is_constant() else np.nan
                  for b in pr.control_limits[name])
        room = 1e-3 * (hi - lo) if np.isfinite(hi - lo) else 0.0
        free = ~((s.u[sel, j] <= lo + room) | (s.u[sel, j] >= hi - room))
        if free.any():
            arc.judge(f"stationarity |H_u| ({name})", float(np.max(np.abs(sig[free, j])))
                      / max(float(np.max(terms[:, j])), 1e-300), s.tol, s.error,
                      "H_u = 0 where the control is inside its bounds")
    if pr.nu != 1:
        arc.notes.append("boundary control law not checked (several controls)")
        return
    law = arc_dynamics(pr, (Mode("boundary", arc.control, arc.side),)).u_fn
    ub = along(law, s.x[sel], pv)[0][:, 0]
    size = max(1.0, float(np.max(np.abs(s.u[:, 0]))))
    arc.judge("boundary control |u - u_b|", float(np.max(np.abs(s.u[sel, 0] - ub))) / size,
              s.tol, s.error, f"the control against the law d^{arc.order} c/dt^{arc.order} = 0")


def _density(arc: ArcCheck, s: ArcSamples, fn: ca.Function, sign: float) -> None:
    """``mu >= 0`` on the arc, and the costate equation across ``grad c``."""
    assert s.pairs is not None
    ta, tb, la, lb, hx = s.pairs
    k = _factor(s, arc)
    sel = inside_arc(s, arc, ta, k) & inside_arc(s, arc, tb, k)
    if sel.sum() < 2:
        return
    xm = np.array([np.interp(0.5 * (ta[sel] + tb[sel]), s.t, s.x[:, i])
                   for i in range(s.x.shape[1])]).T
    grad = along(fn, xm, s.pv)[1]
    step = lb[sel] - la[sel] + hx[sel] * (tb[sel] - ta[sel])[:, None]
    g2 = np.maximum(np.sum(grad**2, axis=1), 1e-300)
    eta = -sign * np.sum(step * grad, axis=1) / g2
    perp = step + sign * eta[:, None] * grad
    size = max(float(np.max(np.abs(np.r_[la, lb]))), 1e-300)
    arc.judge("costate equation across grad c", float(np.max(np.abs(np.cumsum(perp, axis=0))))
              / size, s.tol, s.error, "lambda' = -H_x - s mu grad c on the arc")
    arc.residuals["multiplier mu dt min"] = float(np.min(eta))
    arc.residuals["multiplier mu dt max"] = float(np.max(eta))
    if float(np.min(eta)) * np.sqrt(float(np.max(g2))) < -max(s.tol, 10 * s.error) * size:
        arc.mark(FAILS, f"the constraint's multiplier is negative on the arc "
                 f"(mu dt down to {np.min(eta):.3g}): the constraint pushes the wrong way")


def _side_line(s: ArcSamples, t_j: float, before: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """The costate beside a junction as a line ``a + b t`` through the two nearest samples
    on one side, ``margin`` away from the detected junction ``t_j``."""
    t, m = s.t, s.margin_at(t_j)
    idx = np.flatnonzero(t <= t_j - m) if before else np.flatnonzero(t >= t_j + m)
    if len(idx) < 2:
        return None
    i, k = (idx[-2], idx[-1]) if before else (idx[0], idx[1])
    if t[k] == t[i]:
        return s.lam[k], np.zeros_like(s.lam[k])
    b = (s.lam[k] - s.lam[i]) / (t[k] - t[i])
    return s.lam[i] - b * t[i], b


def _jump(arc: ArcCheck, s: ArcSamples, fn: ca.Function, sign: float, t_j: float,
          what: str) -> None:
    """``lambda(t+) - lambda(t-) = -s eta grad c`` with ``eta >= 0`` at a junction.

    The junction is known to a grid interval: it is placed where the two sides' costate
    lines agree across ``grad c`` (within twice the margin of the detected time), and
    the jump is measured there.
    """
    left, right = _side_line(s, t_j, True), _side_line(s, t_j, False)
    if left is None or right is None:
        arc.notes.append(f"{what} jump not measured: too few samples beside the junction")
        return
    xj = np.array([np.interp(t_j, s.t, s.x[:, i]) for i in range(s.x.shape[1])])
    grad = np.array(fn(xj, s.pv)[1], dtype=float).ravel()
    g2 = max(float(grad @ grad), 1e-300)
    a, b = right[0] - left[0], right[1] - left[1]
    pa, pb = a - (a @ grad) / g2 * grad, b - (b @ grad) / g2 * grad
    if float(pb @ pb) > 0:
        m = s.margin_at(t_j)
        t_j = float(np.clip(-(pa @ pb) / float(pb @ pb), t_j - 2 * m, t_j + 2 * m))
    d = a + b * t_j
    eta = -sign * float(d @ grad) / g2
    size = max(float(np.max(np.abs(s.lam))), 1e-300)
    perp = float(np.max(np.abs(d + sign * eta * grad)))
    arc.residuals[f"{what} time"] = t_j
    arc.residuals[f"{what} jump eta"] = eta
    arc.judge(f"{what} jump across grad c", perp / size, s.tol, s.error,
              "the costate's jump at a junction is along grad c")
    # the junction is known to a grid interval: the costate lines beside it, ``margin``
    # away on each side, may count the arc's density over those 2 margins as a jump
    share = arc.residuals.get("multiplier mu dt max", 0.0) * 2 * s.margin_at(t_j) / max(
        float(np.max(np.diff(s.pairs[0] if s.pairs is not None else s.t))), 1e-300)
    bound = max(s.tol * size, 10 * s.error * size, max(share, 0.0) * float(np.sqrt(g2)))
    if eta * float(np.sqrt(g2)) < -bound:
        arc.mark(FAILS, f"the costate jumps the wrong way at the {what} (eta {eta:.3g} < 0)")
    elif eta < 0:  # why a negative estimate is no sign violation
        arc.notes.append(
            f"{what} jump eta {eta:.2g} < 0 within the numerical error, {bound / size:.1e} of "
            f"the costate's size {size:.3g}: the larger of the tolerance {s.tol:g}, 10 x the "
            f"solution's error {s.error:.1e}, and the arc's density over the "
            f"{2 * s.margin_at(t_j):.2g} beside the junction ({share:.2g}), which is known to "
            "a grid interval and which the costate lines beside it may count as a jump")


__all__ = ["check_state_arcs", "constraint_order"]
