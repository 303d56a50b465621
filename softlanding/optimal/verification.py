"""The checks every optimal-control result of the package states (``unverified_reasons``).

A result is *verified* when its switching times were refined, its schedule replayed in the
exact simulator comes to rest inside the stroke at the same depth, and (when one is given)
its PMP certificate certifies it; otherwise each failed check is one line of
``unverified_reasons``. These are the shared lines, and the one that says why a landing at
the static depth (the least depth any landing rests at) cannot be verified.
"""

from __future__ import annotations

import math
from typing import Any

from softlanding.model.ground import Ground
from softlanding.simulation.groundcode import hold_stiffness


def _within_grid(replay: Any, refined: bool) -> bool:
    """A transcribed schedule's replay that leaves the stroke by no more than the
    transcription's accuracy (1e-6, as its depth): a constraint the transcription holds
    at Ipopt's tolerance, not a violated one. A refined schedule gets no such allowance."""
    excess = max(-replay.stroke_min, replay.stroke_max - replay.robot.s)
    return not refined and excess <= 1e-6 * max(1.0, replay.robot.s)


def replay_reasons(replay: Any, depth: float, refined: bool) -> list[str]:
    """What the exact replay of a schedule disproves (empty: it confirms the result).

    Parameters
    ----------
    replay : LandingResult
        The schedule replayed in the exact simulator.
    depth : float
        The depth the optimiser reports.
    refined : bool
        The result was refined (exact arcs: replay to 1e-9 and the stroke exactly; else
        1e-6, the transcription's grid error, in depth and stroke).
    """
    out = []
    if not replay.rest_proven:
        out.append(f"the exact-simulator replay does not come to rest ({replay.status})")
    elif not replay.feasible and not _within_grid(replay, refined):
        excess = max(-replay.stroke_min, replay.stroke_max - replay.robot.s)
        out.append(f"the exact-simulator replay leaves the stroke [0, {replay.robot.s:g}] "
                   f"by {excess:.1e} (leg length from {replay.stroke_min:.6g} to "
                   f"{replay.stroke_max:.6g})")
    # a force beyond the limit by more than rounding (a boundary arc's law: 1e-14); a
    # transcription's excess within Ipopt's tolerance was clipped before the replay
    u_max = replay.robot.u_max
    if u_max is not None and replay.u_peak > u_max + 1e-12 * max(1.0, u_max):
        out.append(f"the replay applies a force {replay.u_peak - u_max:.1e} beyond the force "
                   f"limit u_max = {u_max:g}")
    tol = (1e-9 if refined else 1e-6) * max(1.0, depth)
    diff = abs(replay.depth - depth)
    if not diff <= tol:
        out.append(f"the replay's depth differs by {diff:.2e} (> {tol:.0e})")
    return out


def static_depth(ground: Ground) -> float:
    """The static depth ``W / K``: the least depth at which a landing can come to rest on
    ``ground`` whose crater's static hold is ``K d`` (at rest it holds the robot's weight
    ``W``, 1 in the paper's units, so no landing rests shallower); NaN where the hold is
    not proportional to the depth.

    Parameters
    ----------
    ground : Ground
        The ground model.
    """
    k = hold_stiffness(ground)
    return math.nan if k is None else 1.0 / k


def at_static_depth(depth: float, bound: float) -> bool:
    """Whether ``depth`` is the static depth ``bound`` to the NLP's tolerance: 1e-7, absolute
    for a bound below 1 (the NLP's error is absolute), relative above; False where no bound is
    known (NaN).

    Parameters
    ----------
    depth, bound : float
        A landing's depth and :func:`static_depth` of its ground.
    """
    return abs(depth - bound) <= 1e-7 * max(1.0, bound)


def static_depth_reason(depth: float, bound: float, v_b: float, u_b: float,
                        body_weight: float, replay: Any = None) -> list[str]:
    """The line an unverified landing at the static depth adds (empty elsewhere): its depth
    is the least any landing that rests can reach, and, when its replay does not come to
    rest, why.

    Parameters
    ----------
    depth : float
        The landing's depth.
    bound : float
        :func:`static_depth` of its ground (NaN: no line).
    v_b : float
        The body's velocity when the foot stops.
    u_b, body_weight : float
        The arrest force and the body's weight ``r_m / (1 + r_m)``.
    replay : LandingResult, optional
        The landing's replay in the exact simulator.
    """
    if not at_static_depth(depth, bound):
        return []
    line = (f"the depth is the static depth W/K = {bound:.10g} (to {abs(depth - bound):.1e}),"
            " the least at which any landing comes to rest (to the NLP's tolerance); there"
            " the crater holds the robot's weight with no margin (arrest force u_b ="
            f" {u_b:.10g}, the body's weight {body_weight:.10g})")
    if replay is not None and not replay.rest_proven and v_b != 0.0:
        line += (", so the body must already be at rest when the foot stops, and this"
                 f" schedule's body velocity then, {v_b:.1e}, is never arrested in the replay")
    return [line]


def refined_result_reasons(refined: bool, notes: list[str], replay: Any, replay_kind: str,
                           depth: float, gain: float, baseline: str) -> list[str]:
    """The lines every refined multi-phase result states: refinement, replay, and a
    depth worse than an admissible baseline's (a local optimum).

    Parameters
    ----------
    refined : bool
        The switching times were refined.
    notes : list of str
        Why not, when they were not.
    replay : LandingResult or None
        The exact-simulator replay.
    replay_kind : str
        Why there is no replay, when there is none.
    depth : float
        The depth the optimiser reports.
    gain : float
        ``baseline depth - depth`` (>= 0 up to the tolerance when the result is optimal).
    baseline : str
        What the baseline is and why it is admissible, e.g. ``"the paper's initial
        condition by {:.2e}: a local optimum (...)"`` with one ``{:.2e}`` for the excess.
    """
    out = []
    if not refined:
        out.append("switching times not refined (" + "; ".join(notes) + ")")
    if replay is None:
        out.append(f"not replayed in the exact simulator ({replay_kind})")
    else:
        out += replay_reasons(replay, depth, refined)
    if gain < -(1e-9 if refined else 1e-5) * max(1.0, depth):
        out.append("deeper than " + baseline.format(-gain))
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


__all__ = ["at_static_depth", "certificate_reasons", "refined_result_reasons", "replay_reasons",
           "static_depth", "static_depth_reason"]
