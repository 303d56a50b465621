"""The full landing as a hybrid multi-phase OCP (posed with the public :mod:`ocp` API).

Phase 1, **yielding** (as the paper's problem): from the impact state ``[l0, v0, 0,
v0]``, ``|u| <= u_max``, ``0 <= x_b - x_f <= s``, ``v_f <= 0``, until the foot
stops (``v_f(T1) = 0``).

Phase 2, **static**: the foot rests at the crater bottom (``x_f, v_f`` constant,
only the body moves, ``x_b'' = -1 + (1+r_m)/r_m u``); the actuator force is free
within ``|u| <= u_max``; the support force ``1/(1+r_m) + u`` stays within
``[0, -x_f(T1)]`` (the crater holds it: a mixed path constraint); the stroke
limits hold; the body descends until it comes to rest (``v_b(T2) = 0``) with
the leg inside the stroke on a crater that holds the robot's weight.

Objective: the final depth ``-x_f`` (at the end of the last phase, which is the
crater depth). Unlike the paper, nothing is assumed about the arrest: the
paper's constant force ``u_b`` is one admissible phase-2 control, so this
problem's depth is never larger than the paper's.

With ``steps=2`` the foot may yield a second time: yielding, static, yielding,
static (the first static phase ends when the actuator pushes harder than the
crater holds; the second yielding phase starts with the foot at rest and ends
when it stops again). Its optimum is never worse than the one-step problem's
(the middle phases may shrink to zero length).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.optimal.stance_phases import (
    ARREST_MAX,
    BODY_DESCENDING,
    CRATER,
    STROKE,
    T_MAX,
    add_static,
    add_yielding,
    arrest_to_rest,
    impact_state,
    parameters,
)

NODES = (100, 40)
"""Shooting intervals of the yielding and the static phase."""
NODES_TWO_STEPS = (80, 30, 30, 40)
"""Shooting intervals of the four phases of the two-step problem."""
OMITTABLE = (CRATER, STROKE)
"""Conditions of the static phases that a diagnosis of an infeasible request may drop."""


def build_two_phase_problem(steps: int = 1, ground: Ground = LINEAR_GROUND,
                            omit: tuple[str, ...] = ()) -> MultiPhaseProblem:
    """The full landing: yielding then static (``steps = 1``), or twice (``steps = 2``).

    Parameters
    ----------
    steps : {1, 2}
        Yielding steps.
    ground : Ground
        Ground model.
    omit : tuple of str
        Conditions of the static phases to leave out (:data:`OMITTABLE`; diagnosis only).
    """
    if steps not in (1, 2):
        raise ValueError(f"steps must be 1 or 2, got {steps}")
    mp = MultiPhaseProblem("full_landing" if steps == 1 else "full_landing_two_steps")
    par = parameters(mp)
    names = ["yielding", "static"] if steps == 1 else ["yielding 1", "static 1",
                                                       "yielding 2", "static 2"]
    phases = []
    for i, name in enumerate(names):
        if i % 2 == 0:
            ph = add_yielding(mp, name, par, ground)
            if i == 0:
                ph.free_final_time(1e-3, T_MAX, guess=0.3)
            else:
                ph.free_duration(0.0, T_MAX, guess=0.01)
        else:
            ph = add_static(mp, name, par, ground, omit)
            if i < len(names) - 1:  # the body keeps descending between the two steps
                ph.path_constraint(ph.x[1], -ca.inf, 0, name=BODY_DESCENDING)
                ph.free_duration(0.0, T_MAX, guess=0.01)
            else:
                ph.free_duration(1e-6, ARREST_MAX, guess=1.0)
        phases.append(ph)
    impact_state(phases[0], par)
    arrest_to_rest(phases[-1], par, ground)
    for a, b in zip(phases[:-1], phases[1:], strict=True):
        mp.link(a, b)
    mp.minimize(-phases[-1].at_tf(phases[-1].x[2]))
    return mp


@lru_cache(maxsize=8)
def two_phase_transcription(steps: int = 1, nodes: tuple[int, ...] | None = None,
                            ground: Ground = LINEAR_GROUND,
                            omit: tuple[str, ...] = ()) -> MultipleShooting:
    """The transcribed full landing, built once per arguments and reused (expanded to SX).

    Parameters
    ----------
    steps : {1, 2}
        Yielding steps.
    nodes : tuple of int, optional
        Shooting intervals per phase (default :data:`NODES` or :data:`NODES_TWO_STEPS`).
    ground : Ground
        Ground model.
    omit : tuple of str
        Conditions dropped (diagnosis).
    """
    nodes = nodes or (NODES if steps == 1 else NODES_TWO_STEPS)
    return MultipleShooting(build_two_phase_problem(steps, ground, omit), nodes=list(nodes),
                            integrator="rk4", substeps=4, expand=True,
                            inner_constraints=steps == 2)


__all__ = ["NODES", "NODES_TWO_STEPS", "OMITTABLE", "build_two_phase_problem",
           "two_phase_transcription"]
