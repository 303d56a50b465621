"""The per-arc table of a transcription or a refinement: samples, checks, second order.

:func:`transcription_table` reads a transcription's samples (shooting: the midpoints of
the intervals, where the piecewise-constant control and the average of the two node
costates agree to second order; collocation: the collocation points, where
``H_u = 0`` is the NLP's own stationarity), the arcs structure detection finds, and
checks each arc (:mod:`ocp.certificate.arc_conditions`, :mod:`ocp.certificate.state_arcs`).
When every arc is interior, the Jacobi test looks for a conjugate point
(:mod:`ocp.certificate.second_order`). :func:`refined_table` does the same on a
refinement's adjoint sweep (whose costate satisfies the costate equation by
construction).

Tolerances derive from the solution's own accuracy: a residual fails only beyond the
tolerance *and* :data:`~ocp.certificate.checks.ERROR_MARGIN` times ``error``, the
solution's measured error (on a transcription: the larger of H's deviation from a
constant, relative to its scale, and the mesh's error estimate; on a refinement:
its integration and sweep errors).
"""

from __future__ import annotations

import math

import numpy as np

from ..structure.arcs import ArcStructure, TranscribedSolution, known_values
from ..transcriptions.gridview import is_collocation, mesh_level
from ..transcriptions.solution import along
from .arc_conditions import ArcSamples, check_arcs, refined_arcs, transcription_arcs
from .arc_record import FAILS, UNCERTAIN, ArcCheck
from .costates import costates_from_multipliers, pmp_functions
from .second_order import jacobi_test
from .state_arcs import check_state_arcs


def transcription_samples_for_arcs(sol: TranscribedSolution, tol: float,
                                   error: float) -> ArcSamples:
    """The samples the per-arc checks read on a transcription.

    Parameters
    ----------
    sol : TranscribedSolution
    tol : float
        Allowed relative residual.
    error : float
        A floor for the solution's relative error, raised to H's measured deviation
        from a constant and to the mesh's error estimate (``sol.mesh_error``).
    """
    pr = sol.problem
    values = known_values(sol)
    pv = np.array([values[k] for k in pr.param_names], dtype=float)
    fns = pmp_functions(pr)
    t, lam = costates_from_multipliers(sol)
    mesh = np.asarray(mesh_level(sol).t, dtype=float)
    margin = 1.5 * float(np.max(np.diff(mesh)))
    if is_collocation(sol):
        x, u = np.asarray(sol.x[1:]), np.asarray(sol.u)
        hx = along(fns.Hx, x, u, lam, pv)[0]
        pairs = (t[:-1], t[1:], lam[:-1], lam[1:], 0.5 * (hx[:-1] + hx[1:]))
    else:
        # shooting: lam at t_1..t_N; interval k (t_k, t_k+1), k = 1..N-1, has control u_k
        tn, xn = np.asarray(sol.t), np.asarray(sol.x)
        t, x = 0.5 * (tn[1:-1] + tn[2:]), 0.5 * (xn[1:-1] + xn[2:])
        u, lm = np.asarray(sol.u)[1:], 0.5 * (lam[:-1] + lam[1:])
        hx = along(fns.Hx, x, u, lm, pv)[0]
        pairs = (tn[1:-1], tn[2:], lam[:-1], lam[1:], hx)
        lam = lm
    # the solution's own accuracy: H's deviation from a constant, relative to its scale
    H = along(fns.H, x, u, lam, pv)[0].ravel()
    xdot = along(pr.dynamics_function(), x, u, pv)[0]
    scale = float(np.max(np.sum(np.abs(lam * xdot), axis=1), initial=0.0)) or 1.0
    mesh_error = float(getattr(sol, "mesh_error", math.nan) or math.nan)
    error = max(error, float(np.ptp(H)) / scale if len(H) else 0.0,
                mesh_error if math.isfinite(mesh_error) else 0.0)
    return ArcSamples(pr, values, t, x, u, lam, pairs, margin, tol, error, mesh)


def transcription_table(sol: TranscribedSolution, structure: ArcStructure, tol: float,
                        error: float) -> list[ArcCheck]:
    """The per-arc table of a transcription.

    Parameters
    ----------
    sol : TranscribedSolution
    structure : ArcStructure
        Its detected structure.
    tol, error : float
        See :func:`transcription_samples_for_arcs`.

    Returns
    -------
    list of ArcCheck
    """
    pr = sol.problem
    arcs = transcription_arcs(pr, structure)
    s = transcription_samples_for_arcs(sol, tol, error)
    check_arcs(arcs, s)
    check_state_arcs(arcs, s)
    if arcs and all(a.kind == "interior" for a in arcs):
        nu = np.asarray(sol.multipliers.get("terminal", np.zeros(0)), dtype=float).ravel()
        res = jacobi_test(pr, s.pv, s.t, s.x, s.u, s.lam, np.asarray(sol.x[-1], dtype=float),
                          nu, s.margin)
        for a in arcs:
            record_jacobi(a, res)
    return arcs


def record_jacobi(arc: ArcCheck, res: object) -> None:
    """Put the Jacobi test's outcome into an interior arc's row.

    Parameters
    ----------
    arc : ArcCheck
    res : JacobiResult
    """
    if not res.tested:  # type: ignore[attr-defined]
        arc.notes.append(f"conjugate-point test not run: {res.reason}")  # type: ignore
        return
    smin = float(res.min_singular)  # type: ignore[attr-defined]
    arc.residuals["Jacobi min sigma(dX)"] = smin
    if res.conjugate_point is not None:  # type: ignore[attr-defined]
        arc.mark(FAILS, f"conjugate point at t = {res.conjugate_point:.4g}: the extremal "  # type: ignore
                 "is no minimum (second-order condition)")
    elif smin < 1e-6:
        arc.mark(UNCERTAIN, f"the Jacobi field is nearly singular (sigma_min {smin:.1e}): "
                 "a conjugate point may be near")
    else:
        S0 = res.S0  # type: ignore[attr-defined]
        arc.notes.append("no conjugate point: the Riccati matrix exists on the horizon "
                         f"(S(t0) = {np.array2string(np.atleast_2d(S0), precision=6)})")


def refined_table(ref: object, t: np.ndarray, x: np.ndarray, u: np.ndarray, lam: np.ndarray,
                  tol: float, error: float) -> list[ArcCheck]:
    """The per-arc table of a refinement, on its adjoint sweep's samples.

    Parameters
    ----------
    ref : RefinedSwitching
    t, x, u, lam : ndarray
        The sweep's samples on the checked part.
    tol, error : float
        Allowed relative residual, and the sweep's measured error.

    Returns
    -------
    list of ArcCheck
        Arcs before ``t[0]`` (a constrained part) are left out.
    """
    pr = ref.problem  # type: ignore[attr-defined]
    values = {**ref.params, **getattr(ref, "variables", {})}  # type: ignore[attr-defined]
    arcs = [a for a in refined_arcs(ref) if a.end > float(t[0]) + 1e-12]
    s = ArcSamples(pr, values, t, x, u, lam, None, 1e-9 * max(1.0, float(t[-1])), tol,
                   error if math.isfinite(error) else 0.0)
    check_arcs(arcs, s)
    check_state_arcs(arcs, s)
    return arcs


__all__ = ["record_jacobi", "refined_table", "transcription_samples_for_arcs",
           "transcription_table"]
