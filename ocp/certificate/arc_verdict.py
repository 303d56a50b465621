"""The verdict of a certificate with its per-arc table.

The global checks (:mod:`ocp.certificate.checks`: H constant, bang arcs at the bound
``sign(sigma)`` selects, switches at sign changes) see a vanishing switching function
as a failure, and structure detection's interior arcs as a doubt. An arc of the table
whose own conditions hold (an interior arc's stationarity and Legendre--Clebsch, a
singular arc's derivatives, singular control and Kelley's condition, a state boundary
arc's multiplier and jumps) answers both: :func:`covered` lets the global checks leave
its span to the table, and :func:`settle` gives the verdict:

* a table row that fails refutes a refined candidate (``"not an extremal"``); on a
  transcription alone it makes the verdict "inconclusive" (structure detection may
  have misread the arc: a chattering control, a transition);
* a row that is uncertain makes it "inconclusive", naming the arc and the condition;
* an interior arc of the detected structure that holding rows do not cover, all of it
  but a junction margin at each end, makes it "inconclusive" (never certify what
  structure detection doubts);
* else a certified verdict names the arc types
  (:func:`~ocp.certificate.arc_record.certified_verdict`).
"""

from __future__ import annotations

import numpy as np

from ..structure.arcs import ArcStructure
from ..transcriptions.gridview import mesh_level
from .arc_record import FAILS, HOLDS, UNCERTAIN, ArcCheck, certified_verdict
from .checks import CERTIFIED, INCONCLUSIVE, NOT_BANG_BANG
from .result import PMPCertificate, interior_arcs

NOT_EXTREMAL = "not an extremal"
"""The refutation of a candidate with non-bang arcs (``"not bang-bang"`` for bang-bang ones)."""

_FREE = ("interior", "singular", "state boundary")


def covered(arcs: list[ArcCheck], span: tuple[float, float], kinds: tuple[str, ...] = _FREE,
            statuses: tuple[str, ...] = (HOLDS, UNCERTAIN), margin: float = 0.0) -> bool:
    """True when rows of ``kinds`` with a status in ``statuses`` cover all of ``span`` but
    ``margin`` at each end (a junction known to that accuracy).

    A span no longer than two margins must have its midpoint covered: a short doubt is
    still a doubt.

    Parameters
    ----------
    arcs : list of ArcCheck
    span : (float, float)
    kinds, statuses : tuple of str
    margin : float
        How far from each end of ``span`` a row may stop short (>= 0).
    """
    a, b = span
    lo, hi = a + margin, b - margin
    if hi <= lo:
        lo = hi = 0.5 * (a + b)
    rows = sorted((r.start, r.end) for r in arcs if r.kind in kinds and r.status in statuses)
    slack = 1e-12 * max(1.0, abs(a), abs(b))
    reach = lo  # the union of the rows, swept from lo: a gap before hi is uncovered
    for s, e in rows:
        if s > reach + slack:
            break
        reach = max(reach, e)
    return reach >= hi - slack


def junction_margin(sol: object) -> float:
    """How far a detected junction may be from the true one: 1.5 the longest interval of
    the transcription's grid (shooting intervals, or collocation mesh intervals).

    Parameters
    ----------
    sol : TranscribedSolution
    """
    t = np.asarray(mesh_level(sol).t, dtype=float)
    return 1.5 * float(np.max(np.diff(t))) if len(t) > 1 else 0.0


def settle(cert: PMPCertificate, structure: ArcStructure | None, refuting: bool,
           margin: float = 0.0) -> None:
    """The verdict of ``cert`` with its table ``cert.arcs`` (in place).

    Parameters
    ----------
    cert : PMPCertificate
        With its global verdict and its per-arc table.
    structure : ArcStructure or None
        The structure detected on the candidate's transcription (None: no doubt to hold).
    refuting : bool
        A failing row refutes (a refined candidate, whose errors are measured).
    margin : float
        How far a holding row's junction may be from the detected arc's (the grid's
        accuracy of a detected junction): the rest of the arc must be covered.
    """
    rows = cert.arcs
    free = [r for r in rows if r.kind != "bang" and r.kind != "control boundary"]
    if cert.verdict == NOT_BANG_BANG and free and refuting:
        # (a transcription's global refutation says only what it measured: sigma vanishes
        # on an interval, or sits off its bound: "not bang-bang"; its per-arc rows carry
        # the grid's error and refute nothing)
        cert.verdict = NOT_EXTREMAL
    bad = [r for r in rows if r.status != HOLDS]
    for r in bad:
        cert.reasons.append(f"{r.where()}: {r.status}: " + "; ".join(r.notes))
    if any(r.status == FAILS for r in bad) and refuting and cert.verdict != NOT_BANG_BANG:
        cert.verdict = NOT_EXTREMAL
    elif bad and cert.verdict == CERTIFIED:
        cert.verdict = INCONCLUSIVE
    if not refuting and any(r.status == FAILS and r.kind in ("interior", "singular")
                            for r in bad):
        cert.reasons.append("a transcription's control on an interior or singular arc "
                            "carries the grid's error: certify(sol, refine_switching(sol)) "
                            "checks the arcs flown exactly")
    doubt = [(c, a, b) for c, a, b in (interior_arcs(structure) if structure else [])
             if not covered([r for r in rows if r.control == c or r.kind == "state boundary"],
                            (a, b), statuses=(HOLDS,), margin=margin)]
    if doubt:
        spans = ", ".join(f"[{a:.6g}, {b:.6g}] ({c})" for c, a, b in doubt)
        if cert.verdict == CERTIFIED:
            cert.verdict = INCONCLUSIVE
        if cert.verdict not in (NOT_BANG_BANG, NOT_EXTREMAL):
            cert.reasons.append(f"structure detection finds an interior arc on {spans}: a "
                                "singular, free or unresolved arc whose conditions were not "
                                "shown to hold, never certified")
    if cert.verdict == CERTIFIED and rows:
        cert.verdict = certified_verdict(rows)


__all__ = ["NOT_EXTREMAL", "covered", "junction_margin", "settle"]
