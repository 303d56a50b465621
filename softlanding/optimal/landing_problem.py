"""The paper's soft-landing OCP: its stance, its conditions and its transcription.

Minimise the final depth ``-x_f(T)`` over a free final time ``T`` (when the foot stops),
subject to the yielding-stance dynamics, ``|u| <= u_max``, ``0 <= x_b - x_f <= s`` and
``v_f <= 0``, ``v_f(T) = 0`` and the body-arrest condition (see
:mod:`softlanding.optimal.landing`, which solves it).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ocp import MultipleShooting, OptimalControlProblem
from softlanding.model.dynamics import STATE_NAMES, stance_dynamics
from softlanding.model.ground import LINEAR_GROUND, DragGround, Ground, LinearGround
from softlanding.optimal.stance_phases import crater_capacity

T_MAX = 30.0
MAX_NODES = 5000
"""Largest transcription (the NLP grows linearly; 5000 nodes take about a minute)."""


STROKE = "stroke limits 0 <= x_b - x_f <= s"
DESCENDING = "foot descending v_f <= 0"
ARREST = "body arrest -x_f(T) >= 1/(1+r_m) + u_b"
ARREST_FORCE = "arrest force u_b <= u_max"
DIAGNOSABLE = (ARREST_FORCE, ARREST, STROKE, DESCENDING)


# Ipopt on a relaxed problem of the diagnosis, which is often infeasible too: its heuristics
# for an infeasible problem (restoration sooner) took the 41 infeasible requests of a grid of
# v0 in [-10, -2], u_max in [0.3, 3], s in {1, 4, 20} from 333.5 to 106.0 s CPU, every message
# the same
RELAXED_IPOPT = {"expect_infeasible_problem": "yes"}

PARAMETERS = ("r_m", "s", "v0", "u_max", "l0")
"""The landing OCP's parameters, in order."""


GROUND_PARAMETERS = ("stiffness", "c_d")
"""The parameters a ground family adds to the landing OCP (after :data:`PARAMETERS`)."""


class ParametricGround:
    """``f = K d + c_d v_f^2`` with ``K`` and ``c_d`` symbols (a ground for the OCP only;
    ``c_d = 0``: the linear family, ``K d``).

    Parameters
    ----------
    stiffness, c_d : casadi.SX or float
        The parameters.
    """

    name: ClassVar[str] = "parametric"

    def __init__(self, stiffness: Any, c_d: Any) -> None:
        self.stiffness, self.c_d = stiffness, c_d

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``K d + c_d v_f^2``.

        Parameters
        ----------
        depth, v_f : expression
            Foot depth and velocity.
        """
        spring = self.stiffness * depth
        return spring if isinstance(self.c_d, float) and self.c_d == 0.0 else \
            spring + self.c_d * v_f ** 2

    def added_mass(self, depth: Any) -> Any:
        """No grains move with the foot.

        Parameters
        ----------
        depth : expression
            Unused.
        """
        return 0.0


def ground_family(ground: Ground) -> tuple[str, ...]:
    """The ground's numbers that are parameters of its landing OCP: ``stiffness`` for a
    linear ground other than the paper's, ``stiffness, c_d`` for a drag ground (``stiffness``
    for one without drag); none for the paper's spring and the other laws (their numbers are
    constants of their own NLP).

    One transcription, and one set of switching NLPs, then serve every ground of a family:
    building them (0.5 s, and up to 3 s for a switching NLP of a drag arc) cost more than a
    solve, and a study lands on many grounds (the unknown-ground study's 15).

    Parameters
    ----------
    ground : Ground
        Ground model.
    """
    if type(ground) is LinearGround and ground != LINEAR_GROUND:
        return GROUND_PARAMETERS[:1]
    if type(ground) is DragGround:  # without drag a spring: the linear family (affine arcs)
        return GROUND_PARAMETERS if ground.c_d else GROUND_PARAMETERS[:1]
    return ()


def ground_values(ground: Ground) -> dict[str, float]:
    """The values of the parameters :func:`ground_family` adds for ``ground``.

    Parameters
    ----------
    ground : Ground
        Ground model.
    """
    return {n: float(getattr(ground, n)) for n in ground_family(ground)}


def ocp_ground(p: OptimalControlProblem, ground: Ground) -> Any:
    """The ground as the landing OCP ``p`` sees it: for a family's ground
    (:func:`ground_family`), a :class:`ParametricGround` on parameters declared on ``p``;
    else the ground itself.

    Parameters
    ----------
    p : OptimalControlProblem
        The problem being built.
    ground : Ground
        Ground model.
    """
    family = ground_family(ground)
    if not family:
        return ground
    k, *c_d = (p.parameter(n) for n in family)
    return ParametricGround(k, c_d[0] if c_d else 0.0)


def build_landing_problem(omit: tuple[str, ...] = (),
                          ground: Ground = LINEAR_GROUND) -> OptimalControlProblem:
    """The soft-landing OCP with parameters ``r_m, s, v0, u_max, l0``.

    Parameters
    ----------
    omit : tuple of str
        Named conditions to drop (used to diagnose infeasible requests).
    ground : Ground
        Ground model of the yielding stance (a linear ground other than the paper's, or a
        drag ground: its numbers are parameters, :func:`ground_family`).
    """
    p = OptimalControlProblem("soft_landing")
    xb, vb, xf, vf = (p.state(n) for n in STATE_NAMES)
    r_m, s, v0, u_max, l0 = (p.parameter(n) for n in PARAMETERS)
    landing_stance(p, r_m, s, u_max, ocp_ground(p, ground), omit)
    p.initial_constraint(xb - l0, 0.0, name="x_b(0) = l0")
    p.initial_constraint(vb - v0, 0.0, name="v_b(0) = v0")
    p.initial_constraint(xf, 0.0, name="x_f(0) = 0")
    p.initial_constraint(vf - v0, 0.0, name="v_f(0) = v0")
    return p


def landing_stance(p: OptimalControlProblem, r_m: Any, s: Any, u_max: Any, ground: Any,
                   omit: tuple[str, ...] = ()) -> None:
    """Everything of the landing OCP but its start: the force, the yielding stance's
    dynamics, the stroke and descent limits, the foot's stop, the body-arrest conditions,
    the free final time and the depth objective (on ``p``'s states ``x_b, v_b, x_f, v_f``).

    Parameters
    ----------
    p : OptimalControlProblem
        A problem with the four states declared.
    r_m, s, u_max : float or parameter expression
        Mass ratio, stroke, force limit.
    ground : Ground
        Ground model (its law may hold parameter expressions).
    omit : tuple of str
        Named conditions to drop.
    """
    x = p.x
    xb, xf, vf = x[0], x[2], x[3]
    u = p.control("u", lower=-u_max, upper=u_max)
    p.set_dynamics(stance_dynamics(x, u, r_m, ground))
    stroke = xb - xf
    if STROKE not in omit:
        p.path_constraint(stroke, 0, s, name=STROKE)
    if DESCENDING not in omit:
        p.path_constraint(vf, -ca.inf, 0, name=DESCENDING)
    p.terminal_constraint(vf, 0.0, name="foot stopped v_f(T) = 0")
    # stroke * (hold - 1/(1+r_m) - u_b) >= 0 and stroke * (u_max - u_b) >= 0, with the
    # crater's hold f(-x_f, 0) (-x_f on the paper's spring)
    ub_stroke = arrest_force_times_stroke(x, r_m)
    if ARREST not in omit:
        p.terminal_constraint(stroke * (crater_capacity(x, ground) - 1 / (1 + r_m)) - ub_stroke,
                              0, ca.inf, name=ARREST)
    if ARREST_FORCE not in omit:
        p.terminal_constraint(stroke * u_max - ub_stroke, 0, ca.inf, name=ARREST_FORCE)
    p.free_final_time(lower=1e-3, upper=T_MAX, guess=1.0)
    p.minimize_terminal(-xf)


_TRANSCRIPTIONS: OrderedDict[tuple, MultipleShooting] = OrderedDict()
TRANSCRIPTIONS_KEPT = 16
"""How many landing transcriptions are kept (the least recently used is dropped)."""


def landing_transcription(nodes: int = 100, substeps: int = 4, omit: tuple[str, ...] = (),
                          ground: Ground = LINEAR_GROUND, expand: bool = True) -> MultipleShooting:
    """The transcribed soft-landing NLP, built once per arguments and reused (once per
    family for a family's grounds, :func:`ground_family`: solve it with
    :func:`ground_values` among the parameters).

    Expanded to SX by default: slower to build once, faster at every re-solve of a sweep.

    Parameters
    ----------
    nodes : int
        Shooting intervals.
    substeps : int
        RK4 steps per interval.
    omit : tuple of str
        Conditions dropped (diagnosis of infeasible requests): such a relaxed problem is
        solved with :data:`RELAXED_IPOPT` (Ipopt's heuristics for an infeasible problem).
    ground : Ground
        Ground model.
    expand : bool
        Expand to SX. A problem solved once (the diagnosis' relaxed ones) is cheaper
        unexpanded: the four relaxations of the paper's infeasible ``v0 = -10``,
        ``u_max = 2`` took 4.5 s CPU unexpanded against 9.2 s expanded, same verdicts.
    """
    key = (nodes, substeps, omit, ground_family(ground) or ground, expand)
    if key in _TRANSCRIPTIONS:
        _TRANSCRIPTIONS.move_to_end(key)
    else:
        if len(_TRANSCRIPTIONS) >= TRANSCRIPTIONS_KEPT:
            _TRANSCRIPTIONS.popitem(last=False)
        _TRANSCRIPTIONS[key] = MultipleShooting(build_landing_problem(omit, ground), nodes=nodes,
                                                integrator="rk4", substeps=substeps,
                                                expand=expand,
                                                ipopt_options=RELAXED_IPOPT if omit else None)
    return _TRANSCRIPTIONS[key]


def arrest_force_times_stroke(x, r_m):
    """``u_b (x_b - x_f)``, where ``u_b = r_m/(1+r_m) (1 + v_b^2 / (2 (x_b - x_f)))`` is the
    constant force that stops the body in the remaining stroke (symbolic or numeric).

    Parameters
    ----------
    x : array or casadi expression of 4
        State at the foot's stop.
    r_m : float or expression
        Mass ratio.
    """
    return r_m / (1 + r_m) * ((x[0] - x[2]) + x[1] ** 2 / 2)


def arrest_force(r_m: float, x_T: np.ndarray) -> float:
    """``u_b``: the constant force that stops the body in the remaining stroke.

    Parameters
    ----------
    r_m : float
        Mass ratio.
    x_T : array of 4
        State at the foot's stop.
    """
    return float(arrest_force_times_stroke(x_T, r_m) / (x_T[0] - x_T[2]))


def build_landing_problem_of(nodes: int, ground: Ground) -> OptimalControlProblem:
    """The (cached) landing problem of :func:`landing_transcription` (one phase).

    Parameters
    ----------
    nodes : int
        Shooting intervals of the transcription it belongs to.
    ground : Ground
        Ground model.
    """
    problem = landing_transcription(nodes, ground=ground).problem
    assert isinstance(problem, OptimalControlProblem)
    return problem


__all__ = ["ARREST", "ARREST_FORCE", "DESCENDING", "DIAGNOSABLE", "GROUND_PARAMETERS",
           "MAX_NODES", "PARAMETERS", "RELAXED_IPOPT", "STROKE", "T_MAX", "TRANSCRIPTIONS_KEPT",
           "ParametricGround", "arrest_force", "arrest_force_times_stroke",
           "build_landing_problem", "build_landing_problem_of", "ground_family", "ground_values",
           "landing_stance", "landing_transcription", "ocp_ground"]
