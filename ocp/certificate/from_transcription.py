"""The PMP certificate of a transcription alone (no refined solution).

Samples are the transcription's nodes (multiple shooting) or collocation points,
costates its continuity / Radau-defect multipliers (:func:`transcription_samples`),
which carry the grid's error: a would-be refutation is re-checked on a grid twice
as fine (:func:`finer_transcription`) and reported only if it persists there.
State-constrained spans are left out of the checks, and on a collocation grid
H is not scored at the points of mesh intervals next to a switch whose control
is not at one bound (the state polynomial cannot follow the kink).
"""


from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..structure.arcs import (
    SolutionLike,
    TranscribedSolution,
    active_path_constraints,
    control_bounds_at,
    detect_arcs,
    known_values,
    transcribed,
)
from ..structure.constraint_kinds import MIXED, STATE
from ..transcriptions.gridview import grid_spacing, is_collocation, mesh_level
from ..transcriptions.solution import Solution
from .arc_record import ArcCheck
from .arc_verdict import covered
from .checks import (
    INCONCLUSIVE,
    NOT_BANG_BANG,
    Figures,
    H_deviation,
    Tolerances,
    figures,
    intervals_of,
    judge,
    verdict_of,
)
from .costates import costates_from_multipliers, final_time_condition, terminal_costate
from .result import PMPCertificate, build_certificate


def transcription_samples(sol: TranscribedSolution) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray]:
    """Times t_1..t_N, states, controls and multiplier costates: at the nodes with the
    control after each node (multiple shooting), or at every collocation point with its
    collocated control (collocation).

    Parameters
    ----------
    sol : TranscribedSolution

    Returns
    -------
    t, x, u, lam : ndarray
    """
    t, lam = costates_from_multipliers(sol)
    u = np.asarray(sol.u) if is_collocation(sol) else np.vstack([sol.u[1:], sol.u[-1:]])
    return t, sol.x[1:], u, lam


def _constrained_transcription(sol: TranscribedSolution) -> list[tuple[float, float]]:
    """Intervals where a path constraint is active in a transcription: nodes at a limit
    (to 1e-6) over at least one interval, and the boundary arcs :func:`detect_arcs`
    finds (which bridge the zig-zag of a transcription along a constraint)."""
    # control-only constraints shape the control set: they are no state constraint
    # (a state constraint at a limit no admissible control could cross is not held there)
    act = active_path_constraints(sol, 1e-6, kinds=(STATE, MIXED), crossable=True)
    act_nodes = act.any(axis=1) if act.size else np.zeros(sol.N + 1, dtype=bool)
    spans = intervals_of(sol.t, np.asarray(act_nodes), _shortest_interval(sol) - 1e-12)
    for name in sol.problem.control_names:
        spans += [(a.start, a.end) for a in detect_arcs(sol, name).arcs if a.kind == "boundary"]
    merged: list[tuple[float, float]] = []
    for a, b in sorted(spans):
        if merged and a <= merged[-1][1] + 1e-12:
            merged[-1] = (merged[-1][0], max(b, merged[-1][1]))
        else:
            merged.append((float(a), float(b)))
    return merged


def _shortest_interval(sol: TranscribedSolution) -> float:
    """A run of active points shorter than this is a touch, not an arc: one shooting
    interval, or the shortest collocation mesh interval (its d + 1 points)."""
    if is_collocation(sol):
        return float(np.min(np.diff(mesh_level(sol).t)))
    return grid_spacing(sol)


def _transcription_figures(sol: TranscribedSolution, tol: Tolerances
                           ) -> tuple[Figures, float | None, list, np.ndarray]:
    pr = sol.problem
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    t, x, u, lam = transcription_samples(sol)
    H_exp = None
    pinned, side = final_time_condition(pr, float(sol.T), float(sol.t0))
    if pinned:
        nu = sol.multipliers.get("terminal", np.zeros(0))
        _, H_exp = terminal_costate(pr, sol.x[-1], sol.T, pv, nu)
    active = _constrained_transcription(sol)
    constrained = np.zeros(len(t), dtype=bool)
    for a, b in active:
        constrained |= (t >= a) & (t <= b)
    switches = {}
    for name in pr.control_names:
        st = detect_arcs(sol, name)
        switches[name] = [a.end for a, b in zip(st.arcs[:-1], st.arcs[1:], strict=True)
                          if a.kind in ("max", "min") and b.kind in ("max", "min")]
    fig = figures(pr, known_values(sol), t, x, u, lam, H_exp, constrained, switches, tol.sigma,
                  np.zeros(pr.nu), 1e-3, tol.singular, interior_check=True, T_side=side)
    if is_collocation(sol):
        _rescore_H(fig, ~constrained & ~_kinked_points(sol, switches), H_exp)
    return fig, H_exp, active, t


def _kinked_points(sol: TranscribedSolution, switches: dict[str, list[float]]) -> np.ndarray:
    """Collocation points of the mesh intervals at and next to a switch of some control
    whose control is not at one bound at all their points: there the state polynomial
    cannot follow the kink of the state, and H (which needs the state) carries an error
    of the order of the interval, however fine the mesh; (N d,) bool."""
    pr = sol.problem
    mesh = mesh_level(sol).t
    N, d = len(mesh) - 1, len(sol.t[1:]) // max(len(mesh) - 1, 1)
    out = np.zeros(len(sol.t) - 1, dtype=bool)
    for j, name in enumerate(pr.control_names):
        lo, hi = control_bounds_at(pr, name, known_values(sol))
        room = 1e-3 * max(1.0, hi - lo) if np.isfinite(hi - lo) else 0.0
        U = np.asarray(sol.u)[:, j].reshape(N, d)
        one_bound = np.all(np.abs(U - hi) <= room, axis=1) | np.all(np.abs(U - lo) <= room,
                                                                    axis=1)
        for ts in switches.get(name, []):
            k = int(np.clip(np.searchsorted(mesh, ts, side="right") - 1, 0, N - 1))
            for i in range(max(k - 1, 0), min(k + 2, N)):
                if not one_bound[i]:
                    out[i * d:(i + 1) * d] = True
    return out


def _rescore_H(fig: Figures, keep: np.ndarray, H_exp: float | None) -> None:
    """``H_max_abs`` and ``H_variation`` of ``fig`` over the samples ``keep`` only."""
    if not keep.any():
        return
    H = fig.H[keep]
    fig.H_max_abs = H_deviation(H, H_exp, fig.T_side) / fig.H_scale
    fig.H_var = float(np.ptp(H)) / fig.H_scale


def finer_transcription(sol: SolutionLike, factor: int = 2) -> Solution | None:
    """Re-solve ``sol``'s problem on a grid ``factor`` times finer, started from ``sol``.

    Parameters
    ----------
    sol : Solution
        A multiple-shooting or collocation solution.
    factor : int
        How many times more nodes (shooting) or mesh intervals (collocation: each
        interval split into ``factor`` equal ones).

    Returns
    -------
    Solution or None
        None when the transcription cannot be rebuilt or the solve fails.
    """
    tsol = transcribed(sol)
    from ..transcriptions.transcription import Collocation, MultipleShooting

    tr = getattr(tsol, "transcription", None)
    if isinstance(tr, Collocation) and len(tr.meshes) == 1:
        return _finer_collocation(tsol, tr, factor)
    if not isinstance(tr, MultipleShooting):
        return None
    try:
        N = factor * tsol.N
        fine = MultipleShooting(tsol.problem, nodes=N, integrator=tr.integrator,
                                substeps=tr.substeps, ipopt_options=tr.ipopt_options)
        s = np.linspace(0.0, 1.0, N + 1)
        X = np.column_stack([np.interp(s, tsol.t / tsol.T, tsol.x[:, i])
                             for i in range(tsol.problem.nx)])
        U = tsol.u[np.minimum((s[:-1] * tsol.N + 1e-9).astype(int), tsol.N - 1)]
        return fine.solve(tsol.params, guess=fine.initial_guess(T=tsol.T, x=X, u=U))
    except Exception:  # any failure: the refutation stays unverified
        return None


def _finer_collocation(sol: TranscribedSolution, tr: Any, factor: int) -> Solution | None:
    """``sol`` re-solved on its mesh with every interval split into ``factor``, started from
    its polynomials (None when the solve fails)."""
    m = np.asarray(tr.meshes[0], dtype=float)
    s = np.linspace(0.0, 1.0, factor + 1)[:-1]
    fine = np.r_[(m[:-1, None] + np.diff(m)[:, None] * s[None, :]).ravel(), 1.0]
    try:
        return tr.with_mesh([fine]).solve(sol.params, guess=sol)
    except Exception:  # any failure: the refutation stays unverified
        return None


def _persistent(coarse: Figures, fine: Figures, tol: Tolerances,
                tol_fine: Tolerances) -> list[str]:
    """The violations of ``coarse`` that a grid twice as fine does not shrink."""
    out = []
    if coarse.H_max_abs > tol.H and fine.H_max_abs > max(tol_fine.H, 0.75 * coarse.H_max_abs):
        out.append(f"H deviates by {coarse.H_max_abs:.2e} of its scale, and by "
                   f"{fine.H_max_abs:.2e} on a grid twice as fine")
    for k, frac in coarse.agreement.items():
        f2 = fine.agreement.get(k, 1.0)
        if frac < 0.99 and f2 < 0.99 and 1 - f2 > 0.75 * (1 - frac):
            out.append(f"{k} sits at the bound sign(sigma) selects only {frac:.1%} of the time "
                       f"({f2:.1%} on a grid twice as fine)")
    for k, g in coarse.gap.items():
        g2 = fine.gap.get(k, 0.0)
        if g > tol.switch and g2 > max(tol_fine.switch, 0.75 * g):
            out.append(f"a switch of {k} is {g:.2e} from a sign change of its sigma "
                       f"({g2:.2e} on a grid twice as fine)")
    for a, b in coarse.singular:
        overlap = sum(max(0.0, min(b, d) - max(a, c)) for c, d in fine.singular)
        if overlap >= 0.75 * (b - a):  # a grid artefact halves with the grid
            what = "a singular arc" if coarse.linear else "an interior arc"
            out.append(f"sigma vanishes on [{a:.4g}, {b:.4g}], and still on a grid twice as "
                       f"fine: {what}")
    return out


def _leave_to_table(fig: Figures, active: list, arcs: list[ArcCheck], margin: float) -> list:
    """Leave the spans that rows of the per-arc table check to the table: runs of vanishing
    sigma on interior or singular arcs, and state-constrained spans on state boundary arcs.
    Returns the active spans left. A span may stick out of its rows by ``margin`` at each
    end (the shortest singular interval the certificate reports). A run that holds an
    interior or singular row of any status is the table's too: sigma is small beside a
    singular arc (it leaves zero as a power of the distance to the junction), and on a
    transcription alone a failing row gives "inconclusive" (the control on a singular arc
    carries the grid's error), never the global checks' refutation."""
    free = [r for r in arcs if r.kind in ("interior", "singular")]
    fig.singular = [r for r in fig.singular if not covered(arcs, r, margin=margin)
                    and not any(min(r[1], a.end) > max(r[0], a.start) for a in free)]
    for name in fig.agreement:
        mine = [r for r in arcs if r.control == name or r.kind == "state boundary"]
        if mine and all(r.kind in ("interior", "singular", "state boundary") for r in mine):
            # no bang arc: H_u = 0 is the table's check, not a bound sign(sigma) selects
            fig.agreement[name] = 1.0
    return [a for a in active if not covered(arcs, a, kinds=("state boundary",), margin=margin)]


def certify_transcription(sol: TranscribedSolution, tol: Tolerances, verify: bool,
                          default_switch: bool, arcs: list[ArcCheck] | None = None
                          ) -> PMPCertificate:
    """The certificate of a transcription alone; a would-be refutation is re-checked on a
    grid twice as fine and reported only if it persists there.

    Parameters
    ----------
    sol : TranscribedSolution
    tol : Tolerances
    verify : bool
        Allow the re-check on a finer grid (without it a refutation is "inconclusive").
    default_switch : bool
        ``tol.switch`` is the default (1.5 h): halved with the grid on the re-check.
    arcs : list of ArcCheck, optional
        The per-arc table: the spans its rows check are left to it.

    Returns
    -------
    PMPCertificate
    """
    fig, H_exp, active, t = _transcription_figures(sol, tol)
    left = _leave_to_table(fig, active, arcs or [], tol.singular)
    definite, uncertain = judge(fig, tol, {}, H_exp is not None)
    src = ("transcription (costates from collocation multipliers / Radau weights)"
           if is_collocation(sol) else "transcription (costates from continuity multipliers)")
    _, _, u, lam = transcription_samples(sol)
    if not definite:
        verdict, reasons = verdict_of([], uncertain, left, 0.0, sol.T)
        return build_certificate(verdict, reasons, H_exp, fig, active, math.nan, src, t, lam, u,
                                 {}, 0.0)
    found = finer_transcription(sol) if verify else None
    if found is None:
        why = "not re-checked" if not verify else "the finer grid could not be solved"
        return build_certificate(INCONCLUSIVE, [*definite, f"unverified on a finer grid ({why}): "
                                                "the transcription's own error may cause it"],
                                 H_exp, fig, active, math.nan, src, t, lam, u, {}, 0.0)
    fine = transcribed(found)
    tol_f = Tolerances(tol.H, tol.sigma, tol.switch / 2 if default_switch else tol.switch,
                       tol.singular / 2)
    fig2, H2, active2, t2 = _transcription_figures(fine, tol_f)
    left2 = _leave_to_table(fig2, active2, arcs or [], tol_f.singular)
    persistent = _persistent(fig, fig2, tol, tol_f)
    src2 = f"{src}; re-checked on {fine.N} nodes"
    _, _, u2, lam2 = transcription_samples(fine)
    if persistent:
        return build_certificate(NOT_BANG_BANG, persistent, H_exp, fig, active, math.nan, src2, t,
                                 lam, u, {}, 0.0)
    d2, u2_reasons = judge(fig2, tol_f, {}, H2 is not None)
    note = [f"on {sol.N} nodes: {r}; it shrinks on {fine.N} nodes (the grid's error)"
            for r in definite]
    if d2:
        return build_certificate(INCONCLUSIVE, note + d2, H2, fig2, active2, math.nan, src2, t2,
                                 lam2, u2, {}, 0.0)
    verdict, reasons = verdict_of([], u2_reasons, left2, 0.0, fine.T)
    return build_certificate(verdict, note + reasons, H2, fig2, active2, math.nan, src2, t2, lam2,
                             u2, {}, 0.0)
