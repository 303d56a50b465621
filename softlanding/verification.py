"""The checks every optimal-control result of the package states (``unverified_reasons``).

A result is *verified* when its switching times were refined, its schedule replayed in the
exact simulator comes to rest inside the stroke at the same depth, and (when one is given)
its PMP certificate certifies it; otherwise each failed check is one line of
``unverified_reasons``. These are the shared lines.
"""

from __future__ import annotations

from typing import Any


def replay_reasons(replay: Any, depth: float, refined: bool) -> list[str]:
    """What the exact replay of a schedule disproves (empty: it confirms the result).

    Parameters
    ----------
    replay : LandingResult
        The schedule replayed in the exact simulator.
    depth : float
        The depth the optimiser reports.
    refined : bool
        The result was refined (exact arcs: replay to 1e-9; else 1e-6, the transcription's
        grid error).
    """
    out = []
    if not replay.rest_proven:
        out.append(f"the exact-simulator replay does not come to rest ({replay.status})")
    elif not replay.feasible:
        out.append(f"the exact-simulator replay leaves the stroke [0, {replay.robot.s:g}] "
                   f"(leg length from {replay.stroke_min:.6g} to {replay.stroke_max:.6g})")
    tol = (1e-9 if refined else 1e-6) * max(1.0, depth)
    diff = abs(replay.depth - depth)
    if not diff <= tol:
        out.append(f"the replay's depth differs by {diff:.2e} (> {tol:.0e})")
    return out


def certificate_reasons(certificate: Any) -> list[str]:
    """One line when a PMP certificate does not certify (empty when it does or is None).

    Parameters
    ----------
    certificate : PMPCertificate, PhasesCertificate or None
        The certificate.
    """
    if certificate is None or certificate.certified:
        return []
    why = f": {certificate.reasons[0]}" if certificate.reasons else ""
    return [f"PMP certificate {certificate.verdict}{why}"]


__all__ = ["certificate_reasons", "replay_reasons"]
