"""What the compiled controller does where its structure does not cover a state, within the
sample: the creep law's phase, the stroke guard, the safe brake, and the fallback that
chooses among them.

The compiled step (:mod:`softlanding.control.bangbang`) re-solves the push-then-pull plan;
where that fails (Newton diverges, or its real-time iteration stays unconverged over
``MAX_UNCONVERGED`` samples while a noisy estimate moves the plan's ground; a plan that
breaks a path limit; a creep on ground without drag) :func:`fallback` acts in the same call,
compiled, within the sample's bound:

1. the first time, on a Newton failure: the plan in memory (the last one, shifted by the
   sample, or the last iterate) goes on, the margin dropped for the rest of the landing (the
   plan is then for the estimate itself, as a re-plan's would be), and Newton tries again
   at the next sample (status :data:`KEPT`);
2. then, the creep law (:mod:`softlanding.control.creep`), where it applies (drag
   estimated): a feedback every sample to the foot's stop (status :data:`CREEP_LAW`);
3. else the safe brake: the pull at the force limit (the foot's fastest stop), limited by
   the stroke guard, every sample to the foot's stop (phase :data:`BRAKING`, status
   :data:`BRAKE`); the body's arrest follows from the measured state.

``M[M_FALLBACKS]`` counts the samples it acted on, ``M[M_WHY]`` holds the last status it
took over from. The exported C has the same functions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.control.bangbang_layout import (
    ARREST_FAILS,
    BODY_DECEL,
    BRAKE,
    BRAKING,
    CONVERGING,
    CREEP,
    CREEP_LAW,
    CREEPING,
    DEFERRED,
    HOLDS,
    KEPT,
    M_FALLBACKS,
    M_ITER,
    M_PHASE,
    M_PRED_OK,
    M_STATUS,
    M_TAU1,
    M_TAU2,
    M_UCREEP,
    M_UNCONVERGED,
    M_WHY,
    NEWTON_FAILED,
    OK,
    P_AB0,
    P_AF0,
    P_BB,
    P_BF,
    P_CD,
    P_CREEP,
    P_GF,
    P_HOLD0,
    P_K,
    P_MARGIN,
    P_PERIOD,
    P_S,
    P_UMAX,
    PULL,
    STROKE_MARGIN,
    foot_acc,
)
from softlanding.control.creep import creep_force
from softlanding.simulation.kernel.const import ENTRY, JIT


@njit(**JIT)
def creep_phase(P, M, x):
    """The creep law's force from ``x`` on the planned ground into ``M[M_UCREEP]``, the phase
    :data:`CREEPING`; :data:`CREEP_LAW`, or :data:`CREEP` where the law does not apply (no
    drag estimated: not covered)."""
    u = creep_force(P[P_AF0], P[P_BF], P[P_GF], P[P_AB0], P[P_BB], P[P_UMAX], P[P_HOLD0],
                    P[P_K], P[P_CD], x, P[P_PERIOD])
    M[M_ITER] = 0
    if not math.isfinite(u):
        M[M_STATUS] = CREEP
        return CREEP
    M[M_PHASE] = CREEPING
    M[M_UCREEP] = stroke_guard(P, x, u)
    M[M_STATUS] = CREEP_LAW
    return CREEP_LAW


@njit(**JIT)
def _approach_limit(dist, vel, h, decel):
    """The largest constant acceleration towards a limit ``dist`` away (approached at
    ``vel``) over a sample ``h`` after which the approach still stops short of it at
    ``decel``: the end speed ``w`` meets ``dist >= h (vel + w) / 2 + max(w, 0)^2 / (2 decel)``
    (receding by the end, ``w < 0``, when even stopping at the end is too late). No limit
    (``inf``) without a deceleration to stop by (``decel <= 0``: a force limit not above the
    body's weight)."""
    if not decel > 0.0:
        return np.inf
    c = dist - 0.5 * h * vel
    if c >= 0.0:
        w = decel * (math.sqrt(0.25 * h * h + 2.0 * c / decel) - 0.5 * h)
    else:
        w = 2.0 * c / h
    return (w - vel) / h


@njit(**ENTRY)
def stroke_guard(P, x, u):
    """The creep law's force ``u`` (held over a sample) limited so that the leg's extension
    (or compression) can still stop at half the body's own relative deceleration under the
    force limit (pulled extending, pushed compressing: the foot may rest) before the stroke
    leaves ``[m, s - m]`` (``m = STROKE_MARGIN s``; :func:`_approach_limit`): the law plans
    the foot only. The relative acceleration is affine in ``u`` (the yielding foot's
    included; a resting foot is taken to stay at rest, which a push beyond the crater's hold
    makes optimistic). A safety net, not a plan: a law that turns in time is untouched; where
    both limits cannot hold, the compression's wins, and the force limit over both."""
    S, V = x[0] - x[2], x[1] - x[3]
    m = STROKE_MARGIN * P[P_S]
    h, ab0, bb, umax = P[P_PERIOD], P[P_AB0], P[P_BB], P[P_UMAX]
    a0, slope = ab0, bb
    if x[3] < 0.0:
        a0 -= foot_acc(P, 0.0, x[2], x[3])
        slope -= P[P_BF]
    top = _approach_limit(P[P_S] - m - S, V, h, 0.5 * (bb * umax - ab0))
    if a0 + slope * u > top:
        u = (top - a0) / slope
    floor = _approach_limit(S - m, -V, h, 0.5 * (ab0 + bb * umax))
    if -(a0 + slope * u) > floor:
        u = (-floor - a0) / slope
    return min(umax, max(-umax, u))


@njit(**JIT)
def body_floor(P, x, u):
    """The brake's force ``u`` raised, while the foot yields, so that the body itself can
    still stop at :data:`BODY_DECEL` of its deceleration under the force limit before it
    comes within ``m`` (:func:`stroke_guard`'s) of the foot's present position. The foot
    only descends, so the stroke stays above the body's height over that position; the
    push at the limit decelerates the body at ``a_b0 + b_b u_max`` whatever the ground (its
    acceleration holds none). :func:`stroke_guard` judges by the relative approach, the
    still-yielding foot's: a foot the pull stops leaves the body's whole speed to arrest
    (issue 46: a body that fell 0.2 through the stroke's lower limit under that guard)."""
    if not x[3] < 0.0:
        return u
    ab0, bb, umax = P[P_AB0], P[P_BB], P[P_UMAX]
    floor = _approach_limit(x[0] - x[2] - STROKE_MARGIN * P[P_S], -x[1], P[P_PERIOD],
                            BODY_DECEL * (ab0 + bb * umax))
    if -(ab0 + bb * u) > floor:
        u = (-floor - ab0) / bb
    return min(umax, max(-umax, u))


@njit(**JIT)
def brake(P, M, x):
    """The safe brake's force from ``x`` into ``M[M_UCREEP]`` (the phase :data:`BRAKING`):
    the pull at the force limit, the foot's fastest stop, limited by :func:`stroke_guard`;
    :data:`BRAKE`."""
    M[M_PHASE] = BRAKING
    M[M_ITER] = 0
    M[M_UCREEP] = body_floor(P, x, stroke_guard(P, x, -P[P_UMAX]))
    M[M_STATUS] = BRAKE
    return BRAKE


@njit(**JIT)
def covered(M, st):
    """Whether a step's status ``st`` covers the state (its plan, the creep law's or the
    brake's force is the control): an arrest short of the crater's hold while pulling too
    (the pull is still the foot's fastest stop)."""
    return (st == OK or st == CONVERGING or st == HOLDS or st == DEFERRED
            or st == CREEP_LAW or st == KEPT or st == BRAKE
            or (st == ARREST_FAILS and M[M_PHASE] == PULL))


@njit(**JIT)
def fallback(P, M, x, st):
    """The fallback of a step whose status ``st`` does not cover the state ``x`` (the
    module's three steps); the status (``st`` itself where it covers)."""
    if covered(M, st):
        return st
    M[M_FALLBACKS] += 1.0
    M[M_WHY] = st
    usable = math.isfinite(M[M_TAU1]) and math.isfinite(M[M_TAU2]) and M[M_TAU2] > 0.0
    if st == NEWTON_FAILED and M[M_FALLBACKS] == 1.0 and M[M_PHASE] != CREEPING and usable:
        P[P_MARGIN] = 0.0
        M[M_UNCONVERGED] = 0.0
        M[M_PRED_OK] = 0.0
        M[M_STATUS] = KEPT
        return KEPT
    if P[P_CREEP] == 1.0 and creep_phase(P, M, x) == CREEP_LAW:
        return CREEP_LAW
    return brake(P, M, x)


@njit(**ENTRY)
def fallback_step(P, M, x, st):
    """:func:`fallback`, from Python (tests; the loop's calls have it inside)."""
    return fallback(P, M, x, st)


__all__ = ["body_floor", "brake", "covered", "creep_phase", "fallback", "fallback_step",
           "stroke_guard"]
