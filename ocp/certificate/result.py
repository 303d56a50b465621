"""The PMP certificate record: :class:`PMPCertificate`, built from figures or refused.

:func:`build_certificate` assembles it from the :class:`~ocp.certificate.checks.Figures` of
the checked samples; :func:`refusal` and :func:`not_applicable` give the "not
applicable" certificate of a solution that is no converged, verified optimum
(nothing is checked then). Verdicts and conventions: :mod:`ocp.certificate.certify`.
"""


from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..structure.arcs import ArcStructure, SolutionLike
from ..structure.costate_copies import copy_of
from .arc_record import ArcCheck
from .chattering import ChatteringResult
from .checks import (
    CERTIFIED,
    INCONCLUSIVE,
    NOT_APPLICABLE,
    NOT_BANG_BANG,
    OTHER_CANDIDATE,
    UNVERIFIED,
    Figures,
)


@dataclass
class PMPCertificate:
    """Figures of the PMP check and a verdict.

    Attributes
    ----------
    verdict : str
        ``"bang-bang certified"``, ``"not bang-bang"``, ``"inconclusive"``,
        ``"chattering suspected"`` or ``"not applicable: ..."`` (see :func:`certify`).
    reasons : list of str
        Why (every failed, uncertain or unverifiable check).
    H_expected : float or None
        The constant H must equal (None when T is fixed: any constant). Where the free
        final time sits at a bound, H need only be a constant on one side of it (below at
        the upper bound, above at the lower: the bound's multiplier takes the rest).
    H_max_abs, H_variation : float
        ``max |H - H_expected|`` (or ``max |H - mean H|`` when fixed T; with T at a
        bound, the larger of that and the constant's excess over the allowed side) and
        ``max H - min H``, both divided by ``H_scale``.
    H_scale : float
        ``max_t sum_i |lambda_i xdot_i|``, the size of the terms that must cancel.
    sigma_sign_agreement : float
        Fraction of the time where some ``|sigma_j|`` is clearly non-zero on
        which ``u_j`` sits at the bound its sign selects (worst control).
    switch_sigma_gap : float
        Largest time between a switch of some control and the nearest sign
        change of its switching function.
    singular_intervals, state_constraint_active_intervals : list of (t0, t1)
    costate_estimates_gap : float
        Largest difference between the two costate estimates on the checked
        part, relative to the largest costate (NaN without a refined solution).
    source : str
        Where the costates came from.
    numerical_error : dict
        The certificate's own error estimates, on the scales of the figures
        they affect: ``H``, ``sigma``, ``switch``, ``costate``, ``state``.
    checked_from : float
        Start of the checked part of the horizon (after the last constrained time).
    per_control : dict
        Per control: ``sigma_sign_agreement`` and ``switch_sigma_gap``.
    elapsed : float
        Seconds the certificate took.
    chattering : ChatteringResult or None
        Switches accumulating at a point (:func:`detect_chattering`), if found.
    arcs : list of ArcCheck
        The per-arc table: each arc's kind, span, the residuals of its conditions,
        their tolerances and errors, its order (singular, state boundary) and status
        (:mod:`ocp.certificate.arc_record`).
    final_time_at_bound : int
        +1 or -1 when the free final time sits at its upper or lower bound: H is then held
        to the side of ``H_expected`` the bound allows, not to its value; 0 otherwise.
    t, lam, H, sigma, u : arrays for plotting (``sigma``/``u`` 1-D for one control).
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
    t: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    lam: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    H: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    sigma: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    u: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    numerical_error: dict[str, float] = field(default_factory=dict)
    checked_from: float = 0.0
    per_control: dict[str, dict[str, float]] = field(default_factory=dict)
    elapsed: float = 0.0
    chattering: ChatteringResult | None = None
    arcs: list[ArcCheck] = field(default_factory=list)
    final_time_at_bound: int = 0

    @property
    def certified(self) -> bool:
        """True when the verdict is "bang-bang certified" or "certified (...)"."""
        return self.verdict == CERTIFIED or self.verdict.startswith("certified (")

    @property
    def applicable(self) -> bool:
        """False when the solution was refused (not converged, or not verified)."""
        return not self.verdict.startswith("not applicable")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (non-finite numbers become None)."""
        def f(x: Any) -> float | None:
            return float(x) if x is not None and math.isfinite(x) else None

        return {"verdict": self.verdict, "reasons": self.reasons,
                "H_expected": f(self.H_expected) if self.H_expected is not None else None,
                "H_max_abs": f(self.H_max_abs), "H_variation": f(self.H_variation),
                "H_scale": f(self.H_scale), "sigma_sign_agreement": f(self.sigma_sign_agreement),
                "switch_sigma_gap": f(self.switch_sigma_gap),
                "singular_intervals": [list(map(float, i)) for i in self.singular_intervals],
                "state_constraint_active_intervals": [
                    list(map(float, i)) for i in self.state_constraint_active_intervals],
                "costate_estimates_gap": f(self.costate_estimates_gap), "source": self.source,
                "numerical_error": {k: f(v) for k, v in self.numerical_error.items()},
                "checked_from": float(self.checked_from),
                "per_control": {c: {k: f(v) for k, v in d.items()}
                                for c, d in self.per_control.items()},
                "elapsed_s": float(self.elapsed),
                "chattering": self.chattering.to_dict() if self.chattering else None,
                "arcs": [a.to_dict() for a in self.arcs],
                "final_time_at_bound": int(self.final_time_at_bound)}


def build_certificate(verdict: str, reasons: list[str], H_exp: float | None, fig: Figures,
                      active: list[tuple[float, float]], gap_lam: float, source: str,
                      t: np.ndarray, lam: np.ndarray, u: np.ndarray, err: dict[str, float],
                      checked_from: float) -> PMPCertificate:
    """The certificate of checked samples: their figures, verdict and provenance.

    Parameters
    ----------
    verdict : str
    reasons : list of str
    H_exp : float or None
        The value H must equal (None when T is fixed).
    fig : Figures
        The figures of the checked samples (:func:`ocp.certificate.checks.figures`).
    active : list of (float, float)
        State-constrained intervals.
    gap_lam : float
        Relative gap between the two costate estimates (NaN without a refined solution).
    source : str
        Where the costates came from.
    t, lam, u : ndarray
        Sample times, costates and controls (kept for plotting; one control: 1-D).
    err : dict of str to float
        The certificate's own numerical error estimates.
    checked_from : float
        Start of the checked part of the horizon.

    Returns
    -------
    PMPCertificate
    """
    single = u.ndim == 2 and u.shape[1] == 1
    per = {k: {"sigma_sign_agreement": fig.agreement[k], "switch_sigma_gap": fig.gap[k]}
           for k in fig.agreement}
    return PMPCertificate(
        verdict, reasons, H_exp, fig.H_max_abs, fig.H_var, fig.H_scale,
        min(fig.agreement.values(), default=1.0), max(fig.gap.values(), default=0.0),
        fig.singular, active, gap_lam, source, t, lam, fig.H,
        fig.sigma[:, 0] if single else fig.sigma, u[:, 0] if single else u, err,
        checked_from, per, final_time_at_bound=fig.T_side)


def refusal(sol: SolutionLike | None, refined: Any = None) -> PMPCertificate | None:
    """The "not applicable" certificate of a solution that is no converged, verified optimum.

    Parameters
    ----------
    sol : Solution or None
        A transcribed solution: refused when ``success`` is False (:data:`NOT_APPLICABLE`)
        or, certified alone (no ``refined``), when ``verified`` is False (:data:`UNVERIFIED`).
    refined : RefinedSwitching or RefinedPhases, optional
        Refused when its ``success`` is False (the iterate of a failed refinement), or
        when it is not a refinement of ``sol`` (another problem, other parameter
        values, or started from a transcription with another objective).

    Returns
    -------
    PMPCertificate or None
        None when nothing is refused.
    """
    if sol is not None and getattr(sol, "success", True) is False:
        return not_applicable(NOT_APPLICABLE, [
            f"the transcription's solve did not converge (Ipopt status "
            f"{getattr(sol, 'status', '?')}): its iterate is no optimum, nothing is checked"])
    if refined is not None and getattr(refined, "success", True) is False:
        return not_applicable(NOT_APPLICABLE, [
            f"the switching refinement did not converge (status "
            f"{getattr(refined, 'status', '?')}): its iterate is no optimum, nothing is "
            "checked"])
    other = _other_candidate(sol, refined)
    if other:
        return not_applicable(OTHER_CANDIDATE, [
            f"the refinement is not this solution's ({other}): a verdict would be about "
            "another candidate, nothing is checked"])
    if refined is None and sol is not None and getattr(sol, "verified", None) is False:
        # (with a refinement, the candidate is the refined solution: the transcription
        # only started it, and its violation between nodes is the grid's)
        viol = getattr(sol, "path_violation", math.nan)
        return not_applicable(UNVERIFIED, [
            f"the transcription violates its path constraints between nodes (by {viol:.2e}, "
            f"{sorted(getattr(sol, 'violations', {}))}): not a verified solution, nothing is "
            "checked"])
    return None


def _signature(pr: Any) -> tuple:
    """What makes two problem objects the same problem (one built twice by the same code
    is): names, variables, dynamics, running cost, bounds and path constraints, phase by
    phase."""
    if pr is None:
        return ()
    if hasattr(pr, "phases"):
        return tuple(_signature(ph) for ph in pr.phases)
    return (pr.name, tuple(pr.state_names), tuple(pr.control_names), tuple(pr.param_names),
            str(pr.rhs), str(pr.lagrange), str(pr.state_bounds), str(pr.control_limits),
            str([(c.name, c.expr, c.lower, c.upper) for c in pr.structure_path]))


def _other_candidate(sol: Any, refined: Any) -> str:
    """Why ``refined`` is not a refinement of ``sol`` ("" when it may be): another problem,
    other parameter values, or started from a transcription with another objective."""
    if sol is None or refined is None:
        return ""
    # a refinement with decision variables ran on a problem derived from sol's (origin)
    mine = getattr(refined, "origin", None) or getattr(refined, "problem", None)
    mine = getattr(copy_of(mine), "origin", mine) if mine is not None else None  # (copies)
    if _signature(mine) != _signature(getattr(sol, "problem", None)):
        return "it belongs to another problem"
    a, b = getattr(sol, "params", None) or {}, getattr(refined, "params", None) or {}
    differ = sorted(k for k in set(a) | set(b) if k not in a or k not in b
                    or abs(float(a[k]) - float(b[k])) > 1e-12 * max(1.0, abs(float(a[k]))))
    if differ:
        return f"other values of {', '.join(differ)}"
    Jt, J = getattr(refined, "transcribed_objective", math.nan), getattr(sol, "objective", math.nan)
    if math.isfinite(Jt) and math.isfinite(J) and abs(Jt - J) > 1e-9 * max(1.0, abs(J)):
        return f"it was started from a transcription with objective {Jt:.10g}, not {J:.10g}"
    return ""


def not_applicable(verdict: str, reasons: list[str],
                   cls: type[PMPCertificate] = PMPCertificate) -> PMPCertificate:
    """A certificate with a "not applicable" verdict and no figures (all NaN).

    Parameters
    ----------
    verdict : str
        :data:`NOT_APPLICABLE`, :data:`UNVERIFIED` or :data:`OTHER_CANDIDATE`.
    reasons : list of str
    cls : type
        :class:`PMPCertificate` or a subclass whose extra fields have defaults.
    """
    nan = math.nan
    return cls(verdict, reasons, None, nan, nan, nan, nan, nan, [], [], nan,
               "none (refused)")


def interior_arcs(structure: ArcStructure) -> list[tuple[str, float, float]]:
    """``(control, start, end)`` of every interior arc of the structure.

    Parameters
    ----------
    structure : ArcStructure
    """
    return [(s.control, a.start, a.end) for s in structure.per_control for a in s.arcs
            if a.kind == "interior"]


def hold_to_structure(cert: PMPCertificate, structure: ArcStructure) -> None:
    """Never certify what structure detection doubts: an interior arc (singular, free or
    unresolved by the grid) makes a "bang-bang certified" verdict "inconclusive".

    Parameters
    ----------
    cert : PMPCertificate
        Changed in place (verdict and reasons).
    structure : ArcStructure
        The structure detected on the candidate's transcription.
    """
    interior = interior_arcs(structure)
    if not interior and structure.refinable:
        return
    spans = ", ".join(f"[{a:.6g}, {b:.6g}] ({c})" for c, a, b in interior) or "some control"
    reason = (f"structure detection finds an interior arc on {spans}: a singular, free or "
              "unresolved arc (refine_switching refuses it), never certified bang-bang")
    if cert.verdict == CERTIFIED:
        cert.verdict = INCONCLUSIVE
    if cert.verdict != NOT_BANG_BANG:  # a refutation stands on its own checks
        cert.reasons = [*cert.reasons, reason]
