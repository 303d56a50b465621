"""A landing's open-loop control for the exact simulator: its arcs (or its transcribed
force), then the arrest force ``u_b`` until the body stops, then the body's weight."""

from __future__ import annotations

import math

import numpy as np

from ocp import Solution
from ocp.structure.switching import RefinedSwitching
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.optimal.landing_problem import arrest_force


def affine_laws(refined: RefinedSwitching) -> bool:
    """Whether every arc's control is a constant or an affine state feedback ``u = K x + k0``
    (what :func:`landing_schedule` replays exactly). A boundary arc on a drag ground holds
    the stroke with a law in ``v_f^2``: not affine, so no exact schedule.

    Parameters
    ----------
    refined : RefinedSwitching
        Refined arcs.
    """
    return all(law is None or "gain" in law for law in (refined.control_laws or []))


def landing_schedule(refined: RefinedSwitching, r_m: float) -> ForceSchedule | FeedbackSchedule:
    """A refined landing's open-loop control: its arcs, then ``u_b`` until the body stops,
    then the body's weight.

    A bang arc is a constant force; a boundary arc (a stroke limit held) is the state
    feedback that holds it, so the schedule is then a :class:`FeedbackSchedule`.

    Parameters
    ----------
    refined : RefinedSwitching
        The refined arcs (of the landing OCP or of one started mid-landing).
    r_m : float
        Mass ratio.

    Raises
    ------
    ValueError
        An arc's law is not affine (:func:`affine_laws`).
    """
    if not affine_laws(refined):
        raise ValueError("a boundary arc's law is not affine in the state (drag): no exact "
                         "schedule; replay the transcription (transcribed_schedule)")
    keep = [i for i, d in enumerate(refined.durations) if d > 1e-14]
    durs = [float(refined.durations[i]) for i in keep]
    rows = [_law_row(refined, i) for i in keep]
    return _with_arrest(durs, rows, refined.xT, r_m)


def transcribed_schedule(sol: Solution, r_m: float, u_max: float = math.inf,
                         damped: bool = False) -> ForceSchedule | FeedbackSchedule:
    """A transcribed landing's open-loop control: its piecewise-constant force, then ``u_b``
    until the body stops, then the body's weight (see :func:`landing_schedule`).

    Parameters
    ----------
    sol : ocp.Solution
        A one-phase transcription of the landing OCP (or of one started mid-landing).
    r_m : float
        Mass ratio.
    u_max : float
        The force limit: Ipopt meets its bounds to its tolerance (~1e-8), the actuator
        exactly, so forces beyond it by at most
        :data:`~softlanding.optimal.phase_schedule.FORCE_TOLERANCE` are clipped to it (a
        larger excess is kept, and the replay's check flags it).
    damped : bool
        Hold the body's weight with a damper on its velocity
        (:data:`~softlanding.optimal.phase_schedule.TAIL_DAMPING`): the transcription
        leaves the body a residual velocity of its accuracy (~1e-8) that would otherwise
        carry it through the stroke limit forever.
    """
    from softlanding.optimal.phase_schedule import clipped_forces

    u, _ = clipped_forces(sol.u[:, 0], u_max)
    h = sol.T / sol.N
    return _with_arrest([h] * len(u), [_const_row(v) for v in u], sol.x[-1], r_m,
                        damped=damped)


def arrest_schedule(x: np.ndarray, r_m: float) -> ForceSchedule | FeedbackSchedule:
    """From a foot at rest in state ``x``: the constant force that stops the body in the
    stroke left, then the body's weight (the tail of :func:`landing_schedule`).

    Parameters
    ----------
    x : array of 4
        The state (the foot stopped).
    r_m : float
        Mass ratio.
    """
    return _with_arrest([], [], np.asarray(x, float), r_m)


def _with_arrest(durs: list[float], rows: list[list[float]], xT: np.ndarray,
                 r_m: float, damped: bool = False) -> ForceSchedule | FeedbackSchedule:
    """``durs, rows`` then the arrest force until the body stops, then the body's weight
    (``damped``: with a damper on the body's velocity, for a transcribed schedule whose
    body keeps a residual velocity of the transcription's accuracy)."""
    stroke = xT[0] - xT[2]
    if xT[1] < 0 and stroke > 0:  # the arrest force until the body stops (none if stopped)
        rows.append(_const_row(arrest_force(r_m, xT)))
        decel = xT[1] ** 2 / (2 * stroke)
        durs.append(-xT[1] / decel)
    rows.append(_const_row(r_m / (1 + r_m)))
    if damped:
        from softlanding.optimal.phase_schedule import TAIL_DAMPING

        rows[-1][1] = -TAIL_DAMPING
    if all(not any(r[:4]) for r in rows):
        return ForceSchedule.from_arcs(durs, [r[4] for r in rows])
    return FeedbackSchedule.from_arcs(durs, rows)


def _const_row(u: float) -> list[float]:
    return [0.0, 0.0, 0.0, 0.0, float(u)]


def _law_row(refined: RefinedSwitching, i: int) -> list[float]:
    """Interval ``i``'s control as a row of ``u = K . [x, 1]``: its bang value, or the
    boundary arc's law ``u = K x + k0``."""
    law = refined.control_laws[i] if refined.control_laws else None
    if law is None:
        return _const_row(refined.values[i])
    return [float(k) for k in np.asarray(law["gain"], float).reshape(-1)[:4]] + [
        float(np.asarray(law["offset"], float).reshape(-1)[0])]


__all__ = ["affine_laws", "arrest_schedule", "landing_schedule", "transcribed_schedule"]
