"""Pontryagin certificate: Hamiltonian, switching functions, verdict with measured accuracy.

Conventions (stated once, used everywhere here): the *minimum* principle,
``H = L + lambda^T (f(x) + g(x) u)``, and the optimal control minimises H.
For a control-affine problem the switching function of control j is
``sigma_j = dL/du_j + lambda^T g_j(x)``: ``u_j = upper`` where ``sigma_j < 0``
and ``u_j = lower`` where ``sigma_j > 0``. The paper writes the maximum
principle; its costate is ``-lambda``.

Costates come from :mod:`ocp.certificate.costates`: the transcription's continuity
multipliers, or the adjoint integrated backward jointly with the state along
the refined arcs (exact on affine arcs; RK8 at two step counts otherwise, so
the certificate knows its own numerical error).

For an autonomous problem H is constant; with free final time it equals
``-d(phi + nu^T G_T)/dT`` (0 when the terminal cost and constraints do not
involve T; -1 for minimum time posed as ``phi = T``). ``H_max_abs`` and
``H_variation`` are normalised by ``H_scale = max_t sum_i |lambda_i xdot_i|``
(the size of the terms that must cancel).

What a verdict means. ``"bang-bang certified"``: the minimum principle's
*necessary* conditions hold along this candidate, which structure detection
sees as bang (and boundary) arcs only and which shows no chattering. It is a
local statement: the candidate is a bang-bang extremal, not necessarily the
global optimum (a problem with several extremals needs several starts).
``"not bang-bang"``: this candidate fails the conditions (beyond tolerance and
numerical error). ``"inconclusive"``: nothing refutes, but a violation lies
inside the error band, a state constraint is active, or structure detection
finds an interior (singular, free or unresolved) arc, which is never
certified. ``"chattering suspected"``: switch intervals shrink geometrically
toward a point and a finer grid resolves more of them (:mod:`ocp.certificate.chattering`);
no finite switching structure is certified. ``"not applicable: ..."``: the
solution (or its refinement) did not converge or is not verified, and nothing
is checked.

A check fails only by more than its tolerance *and* more
than ten times the certificate's own estimated numerical error; a violation
inside that error band gives "inconclusive", never a refutation. From a
transcription alone, whose costates carry the grid's error, a would-be
refutation is re-checked on a grid twice as fine and reported only if it
persists there. Where a state constraint is active (a boundary arc, or a
constraint touching its limit) the unconstrained costate does not hold
before it: the checks then cover the part after the last constrained time,
and the verdict is at best "inconclusive: state constraint active on ...".

Where the parts live (dependencies run one way, down this list):

* :mod:`ocp.certificate.checks` -- the checks on one set of samples (H, sigma, sign
  agreement, switch gap, singular runs, coupled controls), tolerances, judgement
  and verdict;
* :mod:`ocp.certificate.result` -- :class:`PMPCertificate`, its assembly, and the
  refusal of what is no converged, verified optimum;
* :mod:`ocp.certificate.from_refined` -- the certificate of a refined solution (constrained
  intervals, adjoint sweep, costate gap);
* :mod:`ocp.certificate.from_transcription` -- the certificate of a transcription alone
  (samples, constrained intervals, the re-check on a finer grid);
* :mod:`ocp.certificate.phases` -- the certificate of a multi-phase solution, phase by phase;
* this module -- :func:`certify`, the public entry (held to the detected structure,
  chattering looked for), :func:`detect_chattering`, :func:`plot_certificate`, and
  the names above re-exported.
"""

from __future__ import annotations

import math
import time
from typing import Any

import casadi as ca

from ..definition.errors import ProblemDefinitionError
from ..definition.symbols import finite_number, positive_int, positive_number

# `name as name`: a re-export (ocp.certificate.certify keeps every public name it had before
# the split)
from ..structure.arcs import ArcStructure, SolutionLike, detect_structure, transcribed
from ..transcriptions.gridview import grid_spacing
from .arc_table import transcription_table
from .arc_verdict import NOT_EXTREMAL as NOT_EXTREMAL
from .arc_verdict import junction_margin, settle
from .chattering import ChatteringResult as ChatteringResult
from .chattering import detect_chattering as chattering_of
from .checks import CERTIFIED as CERTIFIED
from .checks import CHATTERING as CHATTERING
from .checks import ERROR_MARGIN as ERROR_MARGIN
from .checks import INCONCLUSIVE as INCONCLUSIVE
from .checks import NOT_APPLICABLE as NOT_APPLICABLE
from .checks import NOT_BANG_BANG as NOT_BANG_BANG
from .checks import OTHER_CANDIDATE as OTHER_CANDIDATE
from .checks import UNVERIFIED as UNVERIFIED
from .checks import Tolerances
from .checks import intervals_of as intervals_of
from .checks import sign_changes as sign_changes
from .checks import switch_gap as switch_gap
from .costates import adjoint_along_refined as adjoint_along_refined
from .costates import costates_from_multipliers as costates_from_multipliers
from .costates import pmp_functions
from .from_refined import certify_refined
from .from_refined import effective_bounds as effective_bounds
from .from_refined import is_mixed as is_mixed
from .from_refined import path_activity_along as path_activity_along
from .from_transcription import certify_transcription, transcription_samples
from .from_transcription import finer_transcription as finer_transcription
from .result import PMPCertificate as PMPCertificate
from .result import not_applicable as not_applicable
from .result import refusal as refusal

__all__ = ["CERTIFIED", "CHATTERING", "ChatteringResult", "INCONCLUSIVE", "NOT_APPLICABLE",
           "NOT_BANG_BANG", "PMPCertificate", "UNVERIFIED", "adjoint_along_refined", "certify",
           "costates_from_multipliers", "detect_chattering", "plot_certificate"]


def certify(sol: SolutionLike, refined: Any = None, *,
            tol_H: float | None = None, tol_sigma: float | None = None,
            tol_switch: float | None = None, min_singular: float | None = None,
            n: int = 2000, verify: bool = True, structure: ArcStructure | None = None,
            chattering: bool = True, max_nodes: int = 1000) -> PMPCertificate:
    """Check Pontryagin's necessary conditions for bang-bang structure along a candidate.

    What a verdict means:

    * ``"bang-bang certified"``: along *this candidate* the minimum principle's
      necessary conditions hold to the stated tolerances (H constant, or equal
      to its free-T value; every control at the bound ``sign(sigma)`` selects;
      switches at sign changes of sigma; no singular interval), structure
      detection finds only bang (and boundary) arcs, and no chattering is
      seen. It is a local statement: the candidate is an extremal, not
      necessarily the global optimum (another extremal may be better: several
      starts find them);
    * ``"not bang-bang"``: this candidate *fails* the conditions beyond their
      tolerance and the certificate's own numerical error (from a transcription
      alone, also on a grid twice as fine): e.g. a singular arc, or a control
      off the bound sigma selects;
    * ``"inconclusive"``: nothing refutes, but something prevents the
      certificate: a violation inside the error band, a state constraint
      active, or an interior (singular, free or unresolved) arc that structure
      detection finds (``"structure detection finds an interior arc on
      [a, b] ..."``), which is never certified bang-bang;
    * ``"chattering suspected"`` (:data:`CHATTERING`): switch intervals shrink
      geometrically toward a point ``t*`` and a finer grid resolves more of
      them (:func:`detect_chattering`, reported in ``cert.chattering``): a
      control that chatters switches infinitely often, so no finite bang-bang
      structure is certified. It takes precedence over the other verdicts (the
      checks' own reasons follow it);
    * ``"not applicable: the solve did not converge"`` (:data:`NOT_APPLICABLE`):
      ``sol.success`` is False (e.g. the iterate of an
      :class:`~ocp.definition.errors.InfeasibleError`), or ``refined`` is the iterate of a
      failed refinement; the reasons give Ipopt's status. ``"not applicable:
      the solution is not verified"`` (:data:`UNVERIFIED`): ``sol.verified`` is
      False (a path constraint violated between nodes) and there is no
      ``refined`` (which would be the candidate then). ``"not applicable: the
      refinement is another candidate's"`` (:data:`OTHER_CANDIDATE`): ``refined``
      refined another problem, other parameter values or another transcription.
      Nothing is checked then: a certificate of a point that is not a converged
      optimum would mean nothing.

    Parameters
    ----------
    sol : Solution
        The transcribed solution (its multipliers give the first costate
        estimate, and its nodes the state-constraint activity).
    refined : RefinedSwitching or RefinedPhases, optional
        The refined solution; when given, H and sigma are evaluated on it with
        the adjoint-integrated costate, and the two estimates compared. A
        multi-phase solution needs its :class:`~ocp.structure.phase_refinement.RefinedPhases`
        and gets a :class:`~ocp.certificate.phases.PhasesCertificate` (phase by phase, with
        the junction conditions checked).
    tol_H : float, optional
        Allowed ``H_max_abs`` (relative to ``H_scale``): default 1e-6 on a
        refined solution, 1e-2 on the transcription alone.
    tol_sigma : float, optional
        ``|sigma_j| <= tol_sigma * max|sigma_j|`` counts as zero: default 1e-6
        refined, 1e-2 transcribed.
    tol_switch : float, optional
        Allowed switch/sign-change gap (default: 1e-6 T refined, 1.5 h otherwise).
    min_singular : float, optional
        Shortest interval of ``sigma ~ 0`` reported as singular (default 2 h).
    n : int
        About how many samples along a refined solution.
    verify : bool
        Transcription alone: re-check a would-be refutation on a grid twice as
        fine (a new transcription, solved from this one); without it such a
        result is only "inconclusive". Also allows the re-solve that confirms
        chattering.
    structure : ArcStructure, optional
        The arc structure to hold the verdict to (default: :func:`detect_structure`
        of ``sol``); with ``refined`` from a structure of your own, pass that one
        (its modes must be the refinement's, else ``ValueError``). An interior arc in
        it forbids "bang-bang certified".
    chattering : bool
        Look for chattering (:func:`detect_chattering`).
    max_nodes : int
        Largest grid the chattering confirmation may solve.

    Returns
    -------
    PMPCertificate
    """
    for name, v in (("tol_H", tol_H), ("tol_sigma", tol_sigma), ("tol_switch", tol_switch)):
        if v is not None:  # (a tolerance of 0 or below, or NaN, decides nothing it should)
            positive_number(v, f"certify({name})")
    if min_singular is not None and finite_number(min_singular, "certify(min_singular)") < 0:
        raise ProblemDefinitionError(f"certify(min_singular) must be >= 0, got {min_singular}")
    n = positive_int(n, "certify(n)", minimum=10)  # (0 samples checked nothing, certified)
    if getattr(sol, "is_multiphase", False) or type(refined).__name__ == "RefinedPhases":
        from ..structure.phase_refinement import RefinedPhases
        from .phases import PhasesCertificate, certify_phases

        if not isinstance(refined, RefinedPhases):
            refused = refusal(sol, refined)
            if refused is not None:  # a failed solve: refused, whatever else is missing
                return not_applicable(refused.verdict, refused.reasons, PhasesCertificate)
            raise ValueError("a multi-phase solution is certified with its refinement: "
                             "certify(sol, ocp.structure.phase_refinement.refine_phases(sol))")
        # (certify_phases refuses a failed solve or refinement, or another candidate's)
        return certify_phases(sol, refined, tol_H=tol_H, tol_sigma=tol_sigma,  # type: ignore
                              tol_switch=tol_switch, min_singular=min_singular, n=n)
    refused = refusal(sol, refined)
    if refused is not None:
        return refused
    if structure is not None and (refined is None or tuple(structure.modes) != tuple(
            getattr(refined, "modes", ()))):
        # a structure of one's own replaces the detected one only as the structure that
        # was refined: anything else could talk the certificate out of a doubt
        raise ValueError("structure= is the structure the refinement solved: pass it with "
                         "that refinement (refined=...), or leave it out")
    tsol = transcribed(sol)
    t0 = time.process_time()
    pr = tsol.problem
    # raises early on problems that are not control-affine (a refinement with decision
    # variables ran on a derived problem, where they are constant states)
    pmp_functions(refined.problem if refined is not None else pr)
    h = grid_spacing(tsol)
    tol = Tolerances(H=tol_H if tol_H is not None else (1e-6 if refined else 1e-2),
                     sigma=tol_sigma if tol_sigma is not None else (1e-6 if refined else 1e-2),
                     switch=math.nan, singular=2 * h if min_singular is None else min_singular)
    st = detect_structure(tsol) if structure is None else structure
    if refined is not None:
        tol.switch = 1e-6 * refined.T if tol_switch is None else tol_switch
        cert = certify_refined(tsol, refined, tol, n)
    else:
        tol.switch = 1.5 * h if tol_switch is None else tol_switch
        arcs = transcription_table(tsol, st, tol.sigma, 0.0)
        cert = certify_transcription(tsol, tol, verify, tol_switch is None, arcs)
        cert.arcs = arcs
    settle(cert, st, refuting=refined is not None, margin=junction_margin(tsol))
    in_dynamics = pr.nv and ca.depends_on(ca.vertcat(pr.rhs, pr.lagrange), pr.v)
    if chattering and in_dynamics:
        # the transcription's switching functions need the variables' values in f: read
        # on the refinement only (where they are constant states)
        cert.reasons.append("chattering not looked for: decision variables in the dynamics")
    elif chattering:
        found = detect_chattering(tsol, resolve=verify, max_nodes=max_nodes)
        if found is not None:
            cert.chattering = found
            cert.reasons = [found.reason, *cert.reasons]
            cert.verdict = CHATTERING
    cert.elapsed = time.process_time() - t0
    return cert


def detect_chattering(sol: SolutionLike, *, resolve: bool = True,
                      max_nodes: int = 1000) -> ChatteringResult | None:
    """Switches whose intervals shrink geometrically toward a point (chattering).

    Reads the sign changes of the switching functions of a transcription (costates
    from its multipliers) and, with ``resolve``, confirms a suspicion by a re-solve
    on a grid fine enough to resolve the next predicted switch
    (:func:`finer_transcription`): the run must gain switches. See
    :mod:`ocp.certificate.chattering`.

    Parameters
    ----------
    sol : Solution
        A converged transcribed solution.
    resolve : bool
        Allow the confirming re-solve (without it, only runs of at least
        :data:`ocp.certificate.chattering.MIN_RUN_UNCONFIRMED` shrinking intervals count).
    max_nodes : int
        Largest grid the confirmation may solve.

    Returns
    -------
    ChatteringResult or None
        ``t_star``, ``ratio``, ``switch_times``, ``counts`` (nodes -> switches in the
        run); None when no chattering is seen.
    """
    return chattering_of(sol, resolve=finer_transcription if resolve else None,
                         max_nodes=max_nodes, samples=transcription_samples)


def plot_certificate(cert: PMPCertificate, title: str | None = None):
    """H, sigma and u against time on three axes, state-constrained spans shaded.

    Parameters
    ----------
    cert : PMPCertificate
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(7, 6.5))
    a1.plot(cert.t, cert.H / cert.H_scale)
    a1.set_ylabel(r"$H / H_{scale}$")
    a2.plot(cert.t, cert.sigma)
    a2.axhline(0, color="0.4", lw=0.7)
    a2.set_ylabel(r"switching function $\sigma = \lambda^T g$")
    a3.step(cert.t, cert.u, where="post")
    a3.set_ylabel("control $u$")
    a3.set_xlabel(r"time $\tau$")
    for a in (a1, a2, a3):
        a.grid(alpha=0.3)
        for lo, hi in cert.state_constraint_active_intervals:
            a.axvspan(lo, hi, color="0.85", lw=0)
        for row in cert.arcs:  # the per-arc table: non-bang arcs shaded, failing ones red
            if row.kind != "bang":
                a.axvspan(row.start, row.end, alpha=0.12, lw=0,
                          color="tab:red" if row.status != "holds" else "tab:blue")
    a1.set_title(title or f"PMP certificate: {cert.verdict} "
                 f"(max|H| {cert.H_max_abs:.1e}, switch gap {cert.switch_sigma_gap:.1e})",
                 fontsize=9)
    fig.tight_layout()
    return fig
