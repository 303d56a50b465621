"""The landing OCP from a measured mid-landing state, on a ground whose stiffness factor and
drag number are parameters.

A controller that re-plans while the foot yields (:mod:`softlanding.control.mpc`) needs the
paper's landing problem started anywhere, for a ground it only estimates: here the start and
the ground law ``f = K d + c_d v_f^2`` are NLP parameters, so one problem (and one solved
structure of :func:`ocp.refine_structure`) serves every sample and every estimate. The
constraints, dynamics and objective are the landing's own
(:func:`softlanding.optimal.landing.landing_stance`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ocp import MultipleShooting, OptimalControlProblem, Solution, Trajectory
from ocp.structure.switching import RefinedSwitching
from softlanding.errors import ParameterError
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.dynamics import STATE_NAMES
from softlanding.model.ground import DragGround, Ground, LinearGround
from softlanding.model.robot import Robot
from softlanding.optimal.landing import (
    ARREST,
    ARREST_FORCE,
    affine_laws,
    landing_schedule,
    landing_stance,
    transcribed_schedule,
)
from softlanding.optimal.landing_problem import ParametricGround
from softlanding.optimal.limits import force_limit
from softlanding.optimal.phase_solve import refined_switching
from softlanding.optimal.pipeline import PhasedVariant, solve_phased
from softlanding.optimal.stance_phases import crater_capacity

STATE_NODES = 60
"""Shooting intervals of :func:`state_transcription` (the MPC's re-plan of last resort and
:func:`plan_from_state`): 30 are hardly faster (Ipopt's iterations dominate) and land one
creep 15 % deeper."""

COAST = "a rising body coasts to its top within the stroke"
"""The state-started landing's condition on a body still rising at the foot's stop."""

STATE_PARAMETERS = ("r_m", "s", "u_max", "stiffness", "c_d", "x_b0", "v_b0", "x_f0", "v_f0")
"""The parameters of :func:`state_landing_problem`, in order."""


@lru_cache(maxsize=1)
def state_landing_problem() -> OptimalControlProblem:
    """The landing OCP started at the parameters ``x_b0, v_b0, x_f0, v_f0`` (a yielding foot:
    ``v_f0 <= 0``, the crater's bottom at the foot) on the ground ``K d + c_d v_f^2``."""
    p = OptimalControlProblem("landing_from_state")
    for n in STATE_NAMES:
        p.state(n)
    r_m, s, u_max, k, c_d, *x0 = (p.parameter(n) for n in STATE_PARAMETERS)
    ground: Any = ParametricGround(k, c_d)  # (a Ground to the OCP's expressions only)
    landing_stance(p, r_m, s, u_max, ground, omit=(ARREST, ARREST_FORCE))
    # the body's arrest at the foot's stop as the landing's, for a descending body; a body
    # still rising (a state a re-plan may start from, after a push too long for the true
    # ground) needs no force beyond its weight: it coasts up at no force (-1 its
    # acceleration, the foot resting under its own weight) and is held at its top, which
    # must be within the stroke. (The landing's own condition, on v_b^2, asked the crater
    # to hold the force that would stop it were it descending: the foot crept deeper.)
    x = p.x
    stroke, down, up = x[0] - x[2], ca.fmin(x[1], 0.0), ca.fmax(x[1], 0.0)
    ub_stroke = r_m / (1 + r_m) * (stroke + down ** 2 / 2)
    p.terminal_constraint(stroke * (crater_capacity(x, ground) - 1 / (1 + r_m)) - ub_stroke,
                          0, ca.inf, name=ARREST)
    p.terminal_constraint(stroke * u_max - ub_stroke, 0, ca.inf, name=ARREST_FORCE)
    p.terminal_constraint(s - stroke - up ** 2 / 2, 0, ca.inf, name=COAST)
    for i, n in enumerate(STATE_NAMES):
        p.initial_constraint(p.x[i] - x0[i], 0.0, name=f"{n}(0) measured")
    return p


def ground_numbers(ground: Ground) -> tuple[float, float]:
    """``(K, c_d)`` of a linear or drag ground (what :func:`state_landing_problem` takes).

    Parameters
    ----------
    ground : LinearGround or DragGround
        The ground.

    Raises
    ------
    TypeError
        Another ground model (its law is not ``K d + c_d v^2``).
    """
    if isinstance(ground, LinearGround):
        return ground.stiffness, 0.0
    if isinstance(ground, DragGround):
        return ground.stiffness, ground.c_d
    raise TypeError(f"the state-started landing takes a linear or drag ground, not "
                    f"{ground.name}")


def state_parameters(robot: Robot, ground: Ground, x: np.ndarray) -> dict[str, float]:
    """The values of :data:`STATE_PARAMETERS` for a robot, a (model) ground and a state.

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit).
    ground : LinearGround or DragGround
        The ground the plan assumes.
    x : array of 4
        The measured state.
    """
    k, c_d = ground_numbers(ground)
    return dict(zip(STATE_PARAMETERS, (robot.r_m, robot.s, force_limit(robot), k, c_d,
                                       *map(float, x)), strict=True))


@lru_cache(maxsize=1)
def state_transcription() -> MultipleShooting:
    """The transcription of :func:`state_landing_problem` (:data:`STATE_NODES` intervals,
    RK4), built once."""
    return MultipleShooting(state_landing_problem(), nodes=STATE_NODES, integrator="rk4",
                            substeps=4, expand=True)


@dataclass
class StatePlan:
    """A landing planned from a mid-landing state (what :func:`solve_from_state` reads).

    Attributes
    ----------
    refined : RefinedSwitching or None
        The refined arcs, when they are an exact schedule (else the transcription is the
        plan).
    transcribed : ocp.Solution or None
        The transcription.
    notes : list of str
        What the solve noticed.
    refine_requested : bool
        Whether the switching times were to be refined.
    """

    refined: RefinedSwitching | None
    transcribed: Solution | None
    notes: list[str] = field(default_factory=list)
    refine_requested: bool = True


class StateStarted(PhasedVariant[StatePlan]):
    """The state-started landing's hooks in the pipeline
    (:func:`~softlanding.optimal.pipeline.solve_phased`): the transcription of
    :func:`state_landing_problem` from the neighbour's solution, else ``guess``, else Ipopt's
    default start; its switching structure refined as the single-phase landing's
    (:func:`~softlanding.optimal.phase_solve.refined_switching`) and kept when it is an exact
    schedule. No replay: the controller's plant is the replay.

    Parameters
    ----------
    robot, ground, x, guess
        As for :func:`solve_from_state` (``x`` stands for the impact, which the hooks do
        not read).
    """

    default_start = True  # a guess from the last plan's rest may mislead from a new state

    def __init__(self, robot: Robot, ground: Ground, x: np.ndarray,
                 guess: Trajectory | None) -> None:
        self.robot, self.ground, self.x, self.start = robot, ground, x, guess

    def parameters(self) -> dict[str, float]:
        """:func:`state_parameters` of the state."""
        return state_parameters(self.robot, self.ground, self.x)

    def transcription(self) -> MultipleShooting:
        """:func:`state_transcription`."""
        return state_transcription()

    def guess(self) -> Trajectory | None:
        """The caller's guess (None: Ipopt's default start)."""
        return self.start

    def refinement(self, sol: Solution, notes: list[str]) -> RefinedSwitching | None:
        """The arcs refined, if finite, with no arc collapsed and an exact schedule (every
        law affine): else None, and the transcription is the plan.

        Parameters
        ----------
        sol : ocp.Solution
            The transcription.
        notes : list of str
            Receives why there is no refinement.
        """
        refined, _ = refined_switching(sol, notes)
        if refined is None:
            return None
        if (np.all(np.isfinite(refined.durations)) and np.all(np.isfinite(refined.xT))
                and np.min(refined.durations) > 1e-9 * refined.T and affine_laws(refined)):
            return refined
        notes.append("the refined arcs are not an exact schedule; the transcription is "
                     "the plan")
        return None

    def assemble(self, sol: Solution | None, ref: RefinedSwitching | None, notes: list[str],
                 path: str) -> StatePlan:
        """The plan.

        Parameters
        ----------
        sol : ocp.Solution or None
            The transcription.
        ref : RefinedSwitching or None
            The accepted refinement.
        notes : list of str
            What the solve noticed.
        path : str
            Always ``"transcription"`` (no neighbour's structure is re-solved here).
        """
        return StatePlan(ref, sol, notes)


def solve_from_state(robot: Robot, ground: Ground, x: np.ndarray, *,
                     guess: Trajectory | None = None,
                     warm_start: Solution | None = None) -> RefinedSwitching | Solution:
    """The optimal landing from a mid-landing state on a known ground: refined arcs when the
    transcription's structure is bang-bang and every arc's law is affine (an exact schedule),
    else the transcription itself.

    It runs on the variants' pipeline (:func:`~softlanding.optimal.pipeline.solve_phased`,
    :class:`StateStarted`): the same fallback order of starts and the same refinement.

    Parameters
    ----------
    robot : Robot
        The robot (with a force limit).
    ground : LinearGround or DragGround
        The ground.
    x : array of 4
        The state (a yielding foot, ``v_f < 0``).
    guess : ocp.Trajectory, optional
        A start for the solver (times from the state's instant); Ipopt's default start if
        it is not given or fails.
    warm_start : ocp.Solution, optional
        A solution of :func:`state_transcription` to start from (then ``guess``, then
        Ipopt's default start, if it fails); a solution of another transcription is not
        used.

    Raises
    ------
    ParameterError
        Not a state of a yielding foot.
    ocp.SolveError
        No plan from this state.
    """
    x = np.asarray(x, float)
    if x.shape != (4,) or not np.all(np.isfinite(x)):
        raise ParameterError("x", f"needs 4 finite numbers (x_b, v_b, x_f, v_f), got {x!r}")
    if not x[3] < 0:
        raise ParameterError("x", "the foot must still yield (v_f < 0) to plan its landing")
    if warm_start is not None and warm_start.transcription is not state_transcription():
        # another problem's solution (the first landing's transcription, unrefined): not
        # resampled as a start, which took Ipopt more iterations than the guess
        warm_start = None
    plan = solve_phased(StateStarted(robot, ground, x, guess), warm_start, replay=False)
    if plan.refined is not None:
        return plan.refined
    assert plan.transcribed is not None
    return plan.transcribed


def plan_from_state(robot: Robot, ground: Ground, x: np.ndarray,
                    guess: Trajectory | None = None) -> ForceSchedule | FeedbackSchedule:
    """The optimal landing from a mid-landing state on a known ground, as a schedule
    (:func:`solve_from_state`): the arcs (or the transcription's steps), then the arrest
    force and the body's weight (:func:`~softlanding.optimal.landing.landing_schedule`).

    Parameters
    ----------
    robot, ground, x, guess
        As for :func:`solve_from_state` (a yielding foot's state, a start for the solver).

    Raises
    ------
    ParameterError, ocp.SolveError
        As :func:`solve_from_state` does.
    """
    return plan_schedule(solve_from_state(robot, ground, x, guess=guess), robot)


def plan_schedule(plan: RefinedSwitching | Solution,
                  robot: Robot) -> ForceSchedule | FeedbackSchedule:
    """A state-started plan's open-loop control: its refined arcs (or the transcription's
    steps), then, for a body descending at the foot's stop, the arrest force until it
    stops and its weight (:func:`~softlanding.optimal.landing.landing_schedule`); for a
    body still rising there (:data:`COAST`), no force until its weight stops it (``v_b``
    later: its acceleration is -1), then its weight (damped after a transcription).

    Parameters
    ----------
    plan : RefinedSwitching or ocp.Solution
        What :func:`solve_from_state` returned.
    robot : Robot
        The robot (with a force limit).
    """
    if isinstance(plan, Solution):
        x_t, t_stop = np.asarray(plan.x[-1], float), float(plan.T)
        # (a rising body's coast ends with the transcription's error in its velocity, which
        # the weight alone would carry through the stroke: its hold is damped)
        out = transcribed_schedule(plan, robot.r_m, force_limit(robot), damped=x_t[1] > 0)
    else:
        out = landing_schedule(plan, robot.r_m)
        x_t, t_stop = np.asarray(plan.xT, float), float(np.sum(plan.durations))
    if not x_t[1] > 0:
        return out
    # (no arrest arc: the weight's piece starts at the foot's stop)
    times = (*out.times, t_stop + float(x_t[1]))
    if isinstance(out, ForceSchedule):
        return ForceSchedule(times, (*out.values[:-1], 0.0, out.values[-1]))
    return FeedbackSchedule(times, (*out.gains[:-1], (0.0,) * 5, out.gains[-1]))


__all__ = ["COAST", "STATE_NODES", "STATE_PARAMETERS", "StatePlan",
           "StateStarted", "ground_numbers", "plan_from_state", "plan_schedule",
           "solve_from_state",
           "state_landing_problem", "state_parameters", "state_transcription"]
