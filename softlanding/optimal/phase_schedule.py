"""A refined multi-phase solution as a controller of the exact simulator.

Every refined interval is an affine law of the augmented state ``z = [x_b, v_b,
x_f, v_f, 1]``: a bang arc is the constant ``u = value``; a boundary arc is the
state feedback ``u = K x + k0`` that holds its constraint (read off
:attr:`ocp.structure.switching.RefinedSwitching.control_laws`). The whole schedule is
therefore a :class:`~softlanding.model.controllers.FeedbackSchedule` (piecewise-affine
in time), replayed exactly by :func:`softlanding.simulation.simulator.simulate`. Where every
feedback law only reads states that its mode keeps constant (the crater-capacity
arc of a static phase reads the pinned foot's ``x_f``), the law *is* a constant
force and a :class:`~softlanding.model.controllers.ForceSchedule` replays it exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ocp.structure.phase_refinement import RefinedPhases
from softlanding.model import controllers as _controllers
from softlanding.model.controllers import ForceSchedule

TAIL_DAMPING = 1.0
"""Damping on the body's velocity added to the force held after the last phase."""

TINY = 1e-10
"""Intervals shorter than this (relative to the horizon) are left out (touch points)."""

FORCE_TOLERANCE = 1e-7
"""How far (relative to ``max(1, u_max)``) a transcription's force may exceed the force
limit and be clipped to it for the replay: Ipopt meets bounds within its bound relaxation
(``bound_relax_factor``, 1e-8 of ``max(1, |bound|)``), an actuator exactly; ten times that
is allowed. A larger excess is replayed as it is, and the replay's check flags it."""


def clipped_forces(u: np.ndarray, u_max: float) -> tuple[np.ndarray, float]:
    """``u`` with the forces beyond ``+-u_max`` by at most :data:`FORCE_TOLERANCE` clipped to
    it; and the largest excess clipped (0: none).

    Parameters
    ----------
    u : ndarray
        Forces.
    u_max : float
        The force limit (inf: none).
    """
    u = np.asarray(u, dtype=float)
    excess = np.abs(u) - u_max
    clip = (excess > 0) & (excess <= FORCE_TOLERANCE * max(1.0, u_max))
    if not clip.any():
        return u, 0.0
    return np.where(clip, np.sign(u) * u_max, u), float(excess[clip].max())


def clip_note(excess: float) -> str:
    """How a replay says that it clipped forces to the limit (empty: none clipped).

    Parameters
    ----------
    excess : float
        The largest excess clipped (:func:`clipped_forces`).
    """
    return (f"; forces up to {excess:.1e} beyond the force limit (Ipopt's bound tolerance) "
            "clipped to it") if excess > 0 else ""


@dataclass
class ArcLaw:
    """One refined interval as an affine law.

    Attributes
    ----------
    phase : int
        Phase index.
    duration : float
        Interval length.
    gain : ndarray (5,)
        ``u = gain . [x_b, v_b, x_f, v_f, 1]``.
    constant : float or None
        The law's value when it is constant along the exact arc (to 1e-13 relative: it
        only reads states the mode keeps still), None otherwise.
    kind : str
        ``"max"``, ``"min"`` or ``"boundary(...)"``.
    """

    phase: int
    duration: float
    gain: np.ndarray
    constant: float | None
    kind: str


def arc_laws(refined: RefinedPhases, first: int = 0) -> list[ArcLaw]:
    """The affine law of every interval of every phase (from phase ``first``), in time order.

    Parameters
    ----------
    refined : RefinedPhases
        A refined multi-phase landing (single control ``u``, states ``x_b, v_b, x_f, v_f``).
    first : int
        First phase included.

    Raises
    ------
    ValueError
        If a boundary law is not affine in the state.
    """
    out: list[ArcLaw] = []
    horizon = max(refined.T - float(refined.t0[0]), 1.0)
    for i, r in enumerate(refined.phases):
        if i < first:
            continue
        laws = r.control_laws
        _, xs, _, ks = r.samples(400)
        for k, (modes, dur) in enumerate(zip(r.modes, r.durations, strict=True)):
            if dur <= TINY * horizon:
                continue
            gain = np.zeros(5)
            if laws[k] is None:
                gain[4] = float(r.values[k])
            else:
                law = laws[k]
                if law is None or "gain" not in law:
                    raise ValueError(f"phase {r.problem.name!r}: the boundary law of interval "
                                     f"{k} is not affine in the state")
                gain[:4] = np.asarray(law["gain"][0], dtype=float)
                gain[4] = float(law["offset"][0])
            along = xs[ks == k][:, :4] @ gain[:4] + gain[4]
            spread = float(np.ptp(along)) if len(along) else 0.0
            const = float(along[0]) if spread <= 1e-13 * max(1.0, float(np.max(np.abs(
                along)))) else None
            out.append(ArcLaw(i, float(dur), gain, const, modes[0].label()))
    return out


def feedback_available() -> bool:
    """Whether :class:`softlanding.model.controllers.FeedbackSchedule` exists in this version."""
    return hasattr(_controllers, "FeedbackSchedule")


def replay_controller(refined: RefinedPhases, tail: float, first: int = 0) -> tuple[Any, str]:
    """The refined schedule (from phase ``first``, time counted from its start) as a
    simulator controller, then ``u = tail`` forever.

    Parameters
    ----------
    refined : RefinedPhases
        A refined multi-phase landing.
    tail : float
        Force held after the last phase (e.g. the body's weight at rest).
    first : int
        First phase replayed (the simulator starts at touchdown).

    Returns
    -------
    controller, str
        A FeedbackSchedule (the laws, then ``tail`` with a damper on the body's
        velocity, :data:`TAIL_DAMPING`); without FeedbackSchedule in this version, a
        ForceSchedule when every law is a constant along its arc. And which one.

    Raises
    ------
    NotImplementedError
        When a feedback law is needed and FeedbackSchedule is not available.
    """
    laws = arc_laws(refined, first)
    durs = [a.duration for a in laws]
    if not feedback_available():
        if all(a.constant is not None for a in laws):
            vals = [float(a.constant) for a in laws] + [tail]  # type: ignore[arg-type]
            return (ForceSchedule.from_arcs(durs, vals),
                    "ForceSchedule (every law constant on its arc)")
        raise NotImplementedError("a boundary arc with state feedback needs softlanding.model."
                                  "controllers.FeedbackSchedule (not in this version)")
    # after the last phase: the tail force plus a damper on the body's velocity, so a
    # rounding-level residual velocity of a body arrested at the stroke limit dies out
    # instead of carrying it through the limit
    # a law constant along its arc is replayed as that constant: the crater-capacity law
    # u = -x_f - 1/(1+r_m) is neutral for a foot that still creeps by a rounding error
    # when the simulator's foot stop falls just after the switch (it would never stop)
    gains = [a.gain if a.constant is None else np.r_[0.0, 0.0, 0.0, 0.0, a.constant]
             for a in laws] + [np.r_[0.0, -TAIL_DAMPING, 0.0, 0.0, tail]]
    fs = _controllers.FeedbackSchedule
    kinds = "constant forces" if all(a.constant is not None for a in laws) else \
        "constant forces and state feedback"
    return (fs(tuple(np.cumsum(durs)), tuple(tuple(g) for g in gains)),
            f"FeedbackSchedule ({kinds}; then the tail force with a damper)")


def propagate(laws: list[ArcLaw], A: np.ndarray, B: np.ndarray,
              x0: np.ndarray) -> np.ndarray:
    """The state after the arcs ``laws`` under one affine mode ``z' = A z + B u`` (exactly:
    the matrix exponential of each closed loop ``A + B gain``).

    Parameters
    ----------
    laws : list of ArcLaw
        The arcs, in order.
    A : ndarray (5, 5)
        Mode matrix of the augmented state (e.g. flight, from
        :func:`softlanding.model.dynamics.mode_matrices`).
    B : ndarray (5,)
        Its control column.
    x0 : ndarray (4,)
        State at the start.
    """
    from ocp.structure.flows import expm

    z = np.r_[np.asarray(x0, dtype=float), 1.0]
    for a in laws:
        z = expm((A + np.outer(B, a.gain)) * a.duration) @ z
    return z[:4]


def transcribed_controller(sol: Any, tail: float, first: int = 0,
                           u_max: float = math.inf) -> tuple[Any, str]:
    """A transcription's piecewise-constant force, from phase ``first`` on, then ``tail``:
    the replay of a result that was not refined (exact up to the transcription's grid).

    Parameters
    ----------
    sol : ocp.Solution
        A transcribed multi-phase solution (multiple shooting: one force per interval).
    tail : float
        Force held after the last phase (the body's weight share).
    first : int
        First phase replayed (earlier ones, e.g. a flight, are propagated elsewhere).
    u_max : float
        The force limit the transcription was bounded by: forces beyond it within
        :data:`FORCE_TOLERANCE` are clipped to it (:func:`clipped_forces`), as the
        description then says.
    """
    durs: list[float] = []
    vals: list[float] = []
    for ph in sol.phases[first:]:
        h = float(ph.T - ph.t0) / ph.N
        if h > 0:
            durs += [h] * ph.N
            vals += [float(u) for u in ph.u[:, 0]]
    return piecewise_controller(durs, vals, tail, u_max, "the transcription's "
                                "piecewise-constant force")


def sampled_controller(sol: Any, tail: float, u_max: float = math.inf,
                       pieces: int = 2000) -> tuple[Any, str]:
    """A smooth (collocation) solution's force sampled at the midpoints of ``pieces`` equal
    pieces per phase and held on each, then ``tail``: the replay of a continuous force
    (its error, second order in the pieces' length, is far below the transcription's).

    Parameters
    ----------
    sol : ocp.Solution
        A transcribed multi-phase solution (collocation: the force's polynomials).
    tail : float
        Force held after the last phase.
    u_max : float
        The force limit (see :func:`transcribed_controller`).
    pieces : int
        Pieces per phase.
    """
    durs: list[float] = []
    vals: list[float] = []
    for ph in sol.phases:
        t0, T = float(ph.t0), float(ph.T)
        if T > t0:
            h = (T - t0) / pieces
            durs += [h] * pieces
            # each interval's control polynomial, extrapolated before its first point
            # (what the collocation equations integrate; ph.at holds a line there instead,
            # which the replay of a varying force feels: 2.5e-5 in depth on 32 intervals)
            mid = t0 + h * (np.arange(pieces) + 0.5)
            vals += [float(u) for u in ph.resample(mid)[1][:, 0]]
    return piecewise_controller(durs, vals, tail, u_max, f"the force sampled on {pieces} "
                                "pieces a phase")


def piecewise_controller(durs: list[float], vals: list[float], tail: float, u_max: float,
                         what: str) -> tuple[Any, str]:
    """The force ``vals[i]`` for ``durs[i]`` each, then ``tail``, as a controller of the
    exact simulator, and its description.

    Parameters
    ----------
    durs, vals : list of float
        The pieces.
    tail : float
        Force held after the last piece.
    u_max : float
        Forces beyond it within :data:`FORCE_TOLERANCE` are clipped to it.
    what : str
        What the pieces are, for the description.
    """
    forces, excess = clipped_forces(np.asarray(vals), u_max)
    vals = [float(v) for v in forces]
    if not feedback_available():
        return (ForceSchedule.from_arcs(durs, vals + [tail]),
                f"ForceSchedule ({what}{clip_note(excess)})")
    # the tail damps the body's velocity, as replay_controller's does: the transcription
    # leaves a residual body velocity of its own accuracy (~1e-8) that would carry the
    # body through the stroke limit forever
    gains = [(0.0, 0.0, 0.0, 0.0, v) for v in vals] + [(0.0, -TAIL_DAMPING, 0.0, 0.0, tail)]
    return (_controllers.FeedbackSchedule(tuple(np.cumsum(durs)), tuple(gains)),
            f"FeedbackSchedule ({what}; then the tail force with a damper{clip_note(excess)})")


__all__ = ["FORCE_TOLERANCE", "ArcLaw", "arc_laws", "clip_note", "clipped_forces",
           "feedback_available", "piecewise_controller", "propagate", "replay_controller",
           "sampled_controller", "transcribed_controller"]
