"""The Pontryagin certificate of a multi-phase solution, phase by phase.

Each phase of a :class:`~ocp.structure.phase_refinement.RefinedPhases` carries the
transversality conditions of the whole problem at its end (``lambda_i(T_i) =
dB/dxT_i`` and the value H must have, from the multipliers of the end-point and
linkage constraints; see :meth:`PhaseSwitchingNLP.transversality`). The single-
phase certificate (:mod:`ocp.certificate.certify`: H constant and equal to its expected value,
u at the bound sign(sigma) selects, switches at sign changes of sigma, no
singular arc) is run on every phase with those conditions, and one more check
ties the phases together: the costate the adjoint sweep reaches at the start of
a phase must equal the one the multipliers give there, ``-dB/dx0_i`` (the
junction conditions). The verdict is the worst of the phases' (a refutation in
any phase refutes; any inconclusive phase makes the whole inconclusive).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..structure.arcs import detect_structure
from ..structure.phase_refinement import RefinedPhases, local_phase
from ..transcriptions.solution import Solution
from .arc_record import certified_verdict
from .arc_verdict import NOT_EXTREMAL, junction_margin, settle
from .checks import CERTIFIED, ERROR_MARGIN, INCONCLUSIVE, NOT_BANG_BANG, Tolerances
from .costates import adjoint_sweep
from .from_refined import certify_refined, constrained_refined
from .result import PMPCertificate, not_applicable, refusal

JUNCTION_TOL = 1e-6
"""Allowed relative gap between the swept and the multipliers' costate at a phase start."""


@dataclass
class PhasesCertificate(PMPCertificate):
    """A :class:`~ocp.certificate.certify.PMPCertificate` of a multi-phase solution.

    The figures are the worst over the phases; the arrays are joined in absolute
    time when every phase has the same states and controls.

    Attributes
    ----------
    verdict, reasons, H_expected, H_max_abs, H_variation, H_scale : as PMPCertificate
        The worst over the phases (reasons prefixed with the phase).
    sigma_sign_agreement, switch_sigma_gap, singular_intervals : as PMPCertificate
        Worst over the phases (intervals in absolute time).
    state_constraint_active_intervals, costate_estimates_gap, source : as PMPCertificate
        Joined over the phases.
    t, lam, H, sigma, u : ndarray
        Joined in absolute time (empty when the phases' states or controls differ).
    numerical_error, checked_from, per_control, elapsed : as PMPCertificate
        Worst errors, earliest checked time, per-control figures, seconds.
    chattering : None
        Not looked for phase by phase: a multi-phase certificate stands on a
        refinement, which a chattering structure (an interior arc) does not have.
    phases : list of PMPCertificate
        One per phase (in the phase's own time).
    phase_names : list of str
    junction_gaps : list of float
        Per phase: relative gap between the adjoint sweep's costate at the phase's
        start and the multipliers' (NaN where the sweep did not reach the start).
    """

    phases: list[PMPCertificate] = field(default_factory=list)
    phase_names: list[str] = field(default_factory=list)
    junction_gaps: list[float] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict: the combined figures and each phase's."""
        d = super().to_dict()
        d["phases"] = [{"name": n, **c.to_dict()} for n, c in zip(self.phase_names, self.phases,
                                                                  strict=True)]
        d["junction_gaps"] = [None if not math.isfinite(g) else float(g)
                              for g in self.junction_gaps]
        return d


def _junction_gap(r: Any, lam0: np.ndarray, n: int) -> tuple[float, float]:
    """Gap between the adjoint sweep's costate at the phase's start and ``lam0``, and the
    sweep's own error estimate (NaN when a state constraint is active in the phase)."""
    _, last = constrained_refined(r, n)
    if last > 0:  # a state constraint before: the costate may jump, no sweep to the start
        return math.nan, 0.0
    sw = adjoint_sweep(r, 0.0, n)
    lam = sw.lam[:, :len(lam0)]  # the phase's states (not the variables a flow problem has)
    scale = max(float(np.max(np.abs(lam))), float(np.max(np.abs(lam0))), 1e-300)
    return float(np.max(np.abs(lam[0] - lam0))) / scale, sw.error_lam + sw.error_x


class _NoTranscription:
    """Stands in for a phase's transcription when there is none (a structure re-solve):
    no multiplier costates to compare, shooting intervals of 1/1000 of the phase."""

    def __init__(self, T: float) -> None:
        self.t, self.T, self.N = np.zeros(1), T, 1000
        self.multipliers = {"continuity": np.zeros((0, 0))}


def certify_phases(sol: Solution | None, refined: RefinedPhases, *,
                   tol_H: float | None = None,
                   tol_sigma: float | None = None, tol_switch: float | None = None,
                   min_singular: float | None = None, n: int = 2000) -> PhasesCertificate:
    """Check Pontryagin's conditions on every phase of a refined multi-phase solution.

    Parameters
    ----------
    sol : Solution or None
        The transcribed multi-phase solution (for the multipliers' costates); None when
        the refinement did not come from a transcription (the estimates-gap is then NaN).
    refined : RefinedPhases
        Its refinement.
    tol_H, tol_sigma : float, optional
        As in :func:`ocp.certify` (default 1e-6 each).
    tol_switch : float, optional
        Allowed switch/sign-change gap (default ``1e-6 T``).
    min_singular : float, optional
        Shortest singular interval reported (default: two shooting intervals of the phase).
    n : int
        About how many samples per phase.

    Returns
    -------
    PhasesCertificate
        With the verdict "not applicable: ..." (and no figures) when ``sol`` did not
        converge or is not verified, or ``refined`` is a failed refinement's iterate.
    """
    refused = refusal(sol, refined)
    if refused is not None:
        out = not_applicable(refused.verdict, refused.reasons, PhasesCertificate)
        assert isinstance(out, PhasesCertificate)
        return out
    t_start = time.process_time()
    certs, gaps, reasons = [], [], []
    names = [r.problem.name for r in refined.phases]
    for i, r in enumerate(refined.phases):
        loc: Any = local_phase(sol, i) if sol is not None else _NoTranscription(r.T)
        h = loc.T / loc.N
        tol = Tolerances(H=1e-6 if tol_H is None else tol_H,
                         sigma=1e-6 if tol_sigma is None else tol_sigma,
                         switch=1e-6 * refined.T if tol_switch is None else tol_switch,
                         singular=2 * h if min_singular is None else min_singular)
        if r.problem.nu == 0:
            certs.append(_no_control(r))
        else:
            certs.append(certify_refined(loc, r, tol, n))
            if sol is not None:  # never certify what the phase's own structure doubts
                settle(certs[-1], detect_structure(loc), refuting=True,
                       margin=junction_margin(loc))
        gap, err = _junction_gap(r, refined.junction_costates[i], n)
        gaps.append(gap)
        if math.isfinite(gap) and gap > JUNCTION_TOL and gap > ERROR_MARGIN * err:
            reasons.append(f"phase {names[i]!r}: the adjoint sweep reaches the phase's start "
                           f"with a costate {gap:.2e} (relative) away from the junction "
                           "conditions of the multipliers")
    return _combine(certs, names, gaps, reasons, refined, time.process_time() - t_start)


def _no_control(r: Any) -> PMPCertificate:
    """A phase without controls: nothing to certify (H is still reported)."""
    z = np.zeros(0)
    return PMPCertificate(CERTIFIED, [], None, 0.0, 0.0, 1.0, 1.0, 0.0, [], [], math.nan,
                          "no control in this phase", z, z, z, z, z)


def _combine(certs: list[PMPCertificate], names: list[str], gaps: list[float],
             extra: list[str], refined: RefinedPhases, elapsed: float) -> PhasesCertificate:
    def rank(v: str) -> int:
        return 0 if v == CERTIFIED or v.startswith("certified (") else \
            {INCONCLUSIVE: 1, NOT_BANG_BANG: 2, NOT_EXTREMAL: 3}[v]

    verdict = max((c.verdict for c in certs), key=rank)
    if verdict.startswith("certified (") or verdict == CERTIFIED:
        verdict = certified_verdict([a for c in certs for a in c.arcs]) \
            if any(c.arcs for c in certs) else CERTIFIED
    reasons = [f"phase {n!r}: {r_}" for n, c in zip(names, certs, strict=True)
               for r_ in c.reasons]
    if extra:
        reasons += extra
        verdict = verdict if verdict in (NOT_BANG_BANG, NOT_EXTREMAL) else INCONCLUSIVE
    t0 = refined.t0
    shift = [[(a + t0[i], b + t0[i]) for a, b in c.state_constraint_active_intervals]
             for i, c in enumerate(certs)]
    sing = [[(a + t0[i], b + t0[i]) for a, b in c.singular_intervals]
            for i, c in enumerate(certs)]
    same = len({(c.lam.shape[1:] if c.lam.ndim == 2 else None) for c in certs if len(c.t)}) <= 1
    arrays: dict[str, Any] = {}
    if same and all(len(c.t) for c in certs):
        arrays = {"t": np.concatenate([c.t + t0[i] for i, c in enumerate(certs)]),
                  "lam": np.concatenate([c.lam for c in certs]),
                  "H": np.concatenate([c.H for c in certs]),
                  "sigma": np.concatenate([c.sigma for c in certs]),
                  "u": np.concatenate([c.u for c in certs])}
    err: dict[str, float] = {}
    for c in certs:
        for k, v in c.numerical_error.items():
            err[k] = max(err.get(k, 0.0), v)
    finite = [c.costate_estimates_gap for c in certs if math.isfinite(c.costate_estimates_gap)]
    return PhasesCertificate(
        verdict, reasons, None, max(c.H_max_abs for c in certs),
        max(c.H_variation for c in certs), max(c.H_scale for c in certs),
        min(c.sigma_sign_agreement for c in certs), max(c.switch_sigma_gap for c in certs),
        [s for x in sing for s in x], [s for x in shift for s in x],
        max(finite) if finite else math.nan,
        "refined phases (adjoint integrated along the exact arcs of every phase, from the "
        "transversality conditions of the multipliers)", **arrays, numerical_error=err,
        checked_from=float(min(c.checked_from + t0[i] for i, c in enumerate(certs))),
        elapsed=elapsed, phases=certs, phase_names=names, junction_gaps=gaps)


__all__ = ["JUNCTION_TOL", "PhasesCertificate", "certify_phases"]
