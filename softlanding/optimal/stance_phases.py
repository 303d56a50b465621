"""The ground modes of the paper's hybrid model as phases of an :class:`ocp.MultiPhaseProblem`.

Every phase has the state ``[x_b, v_b, x_f, v_f]`` and the control ``u``
(``|u| <= u_max``), and its dynamics come from the one definition,
:func:`softlanding.model.dynamics.robot_rhs`, with the ground force of its mode:

* **yielding** (:func:`add_yielding`): ``f_g`` = the ground model's yield force at the
  foot's depth, the foot moving down (``v_f <= 0``);
* **static** (:func:`add_static`): the foot rests at the crater bottom; ``f_g`` is the
  support force that keeps it still, solved from ``robot_rhs`` (``x_f'' = 0``): for the
  paper's robot ``1/(1+r_m) + u``. The crater holds it while ``0 <= f_g <= yield
  force at the crater depth`` (the ground cannot pull; a harder push yields it
  further): a *mixed* state-control path constraint, so on a boundary arc the
  actuator force is set by the crater (a bound that depends on the state);
* **flight** (:func:`add_flight`): ``f_g = 0``.

The problems' shared parameters are :data:`PARAMETERS` (the landing's, as in
:mod:`softlanding.optimal.landing`). Phase builders name their path constraints with the
constants below so a researcher can read and drop them.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from ocp import MultiPhaseProblem, OptimalControlProblem
from softlanding.model.dynamics import STATE_NAMES, VF, robot_rhs, stance_dynamics
from softlanding.model.ground import LINEAR_GROUND, Ground

PARAMETERS = ("r_m", "s", "v0", "u_max", "l0")
"""Parameters shared by every phase (as the single-phase landing's)."""

T_MAX = 30.0
"""Longest yielding phase (the landing's bound)."""
ARREST_MAX = 1.0e4
"""Longest static or flight phase."""

STROKE = "stroke limits 0 <= x_b - x_f <= s"
DESCENDING = "foot descending v_f <= 0"
CRATER = "crater holds the support force (<= yield force at the crater depth)"
NO_PULL = "ground cannot pull (support force >= 0)"
BODY_DESCENDING = "body descending v_b <= 0 until it stops"
ABOVE_SURFACE = "foot above the ground x_f >= 0"
ABOVE_CRATER = "foot above the crater bottom"


def parameters(mp: MultiPhaseProblem) -> dict[str, ca.SX]:
    """Declare :data:`PARAMETERS` on ``mp``; their symbols by name.

    Parameters
    ----------
    mp : MultiPhaseProblem
        The problem.
    """
    return {n: mp.parameter(n) for n in PARAMETERS}


def _phase(mp: MultiPhaseProblem, name: str, par: dict[str, ca.SX],
           omit: tuple[str, ...] = (), u_bound: ca.SX | None = None) -> OptimalControlProblem:
    ph = mp.phase(name)
    for n in STATE_NAMES:
        ph.state(n)
    bounded_by(ph, par, u_bound)
    x = ph.x
    if STROKE not in omit:
        ph.path_constraint(x[0] - x[2], 0, par["s"], name=STROKE)
    return ph


def bounded_by(ph: OptimalControlProblem, par: dict[str, ca.SX],
               u_bound: ca.SX | None = None) -> None:
    """Declare the control ``u`` of ``ph``, ``|u| <= u_bound`` (default ``u_max``).

    A ``u_bound`` that is a decision variable (the epigraph of the peak force) is the
    control's bounds too: :mod:`ocp` reads the control set at the variable's value, so the
    arcs at the bound are bang arcs, refined with the variable.

    Parameters
    ----------
    ph : OptimalControlProblem
        A phase without its control yet.
    par : dict
        The problem's parameters (:func:`parameters`).
    u_bound : casadi expression, optional
        The bound (default ``par["u_max"]``).
    """
    bound = par["u_max"] if u_bound is None else u_bound
    ph.control("u", lower=-bound, upper=bound)


@lru_cache(maxsize=1)
def _support_function() -> ca.Function:
    """``f_g(x, u, r_m)`` keeping the foot still: the root of ``x_f''`` in ``robot_rhs``."""
    x, u, fg, r = ca.SX.sym("x", 4), ca.SX.sym("u"), ca.SX.sym("f_g"), ca.SX.sym("r_m")
    acc = robot_rhs(x, u, fg, r)[VF]
    a0 = ca.substitute(acc, fg, 0)
    return ca.Function("support", [x, u, r], [-a0 / ca.jacobian(acc, fg)])


def support_force(x, u, r_m):
    """The support force that keeps a resting foot still (symbolic or numeric).

    Derived from :func:`softlanding.model.dynamics.robot_rhs` (for the paper's model
    ``1/(1+r_m) + u``).

    Parameters
    ----------
    x, u, r_m
        State (4 entries), actuator force and mass ratio, symbolic or numeric.
    """
    return _support_function()(x, u, r_m)


def crater_capacity(x, ground: Ground = LINEAR_GROUND):
    """Largest support force the crater under a resting foot holds: the ground's yield
    force at the crater depth ``-x_f`` (``-x_f`` for the paper's spring).

    Parameters
    ----------
    x : casadi expression or array of 4
        State (the foot at the crater bottom).
    ground : Ground
        Ground model.
    """
    return ground.yield_force(-x[2], 0.0)


def add_yielding(mp: MultiPhaseProblem, name: str, par: dict[str, ca.SX],
                 ground: Ground = LINEAR_GROUND,
                 u_bound: ca.SX | None = None) -> OptimalControlProblem:
    """A yielding-stance phase: foot descending, ``v_f(T) = 0`` (the foot stops).

    Parameters
    ----------
    mp, name, par
        The problem to add the phase to, the phase's name, the problem's parameters
        (:func:`parameters`).
    ground : Ground
        Ground model.
    u_bound : casadi expression, optional
        ``|u| <= u_bound`` instead of ``u_max`` (see :func:`bounded_by`).
    """
    ph = _phase(mp, name, par, u_bound=u_bound)
    ph.set_dynamics(stance_dynamics(ph.x, ph.u[0], par["r_m"], ground))
    ph.path_constraint(ph.x[3], -ca.inf, 0, name=DESCENDING)
    ph.terminal_constraint(ph.x[3], 0.0, name="foot stopped v_f(T) = 0")
    return ph


def add_static(mp: MultiPhaseProblem, name: str, par: dict[str, ca.SX],
               ground: Ground = LINEAR_GROUND, omit: tuple[str, ...] = (),
               u_bound: ca.SX | None = None) -> OptimalControlProblem:
    """Add a static-stance phase: the foot pinned at the crater bottom, the support force
    within ``[0, crater capacity]`` (mixed path constraints :data:`NO_PULL`, :data:`CRATER`).

    Parameters
    ----------
    mp, name, par, ground
        As :func:`add_yielding` (``ground``: whose yield force is the crater's capacity).
    omit : tuple of str
        Conditions to leave out (:data:`STROKE`, :data:`CRATER`; diagnosis only).
    u_bound : casadi expression, optional
        ``|u| <= u_bound`` instead of ``u_max`` (see :func:`bounded_by`).
    """
    ph = _phase(mp, name, par, omit, u_bound)
    x, u, r_m = ph.x, ph.u[0], par["r_m"]
    f = support_force(x, u, r_m)
    ph.set_dynamics(robot_rhs(x, u, f, r_m))
    if CRATER not in omit:
        ph.path_constraint(f - crater_capacity(x, ground), -ca.inf, 0, name=CRATER)
    ph.path_constraint(f, 0, ca.inf, name=NO_PULL)
    return ph


def add_flight(mp: MultiPhaseProblem, name: str, par: dict[str, ca.SX]) -> OptimalControlProblem:
    """A flight phase: no ground force.

    Parameters
    ----------
    mp, name, par
        The problem to add the phase to, the phase's name, the problem's parameters
        (:func:`parameters`).
    """
    ph = _phase(mp, name, par)
    ph.set_dynamics(robot_rhs(ph.x, ph.u[0], 0.0, par["r_m"]))
    return ph


def arrest_to_rest(ph: OptimalControlProblem, par: dict[str, ca.SX],
                   ground: Ground = LINEAR_GROUND) -> None:
    """Make a static phase the body's arrest: the body descends until it stops (``v_b(T) =
    0``) with the leg inside the stroke, on a crater that holds the robot's weight.

    Parameters
    ----------
    ph : OptimalControlProblem
        A static phase (:func:`add_static`).
    par : dict
        The problem's parameters.
    ground : Ground
        Ground model.
    """
    x = ph.x
    ph.path_constraint(x[1], -ca.inf, 0, name=BODY_DESCENDING)
    ph.terminal_constraint(x[1], 0.0, name="body at rest v_b(T) = 0")
    ph.terminal_constraint(x[0] - x[2], 0, par["s"], name="leg inside the stroke at rest")
    weight = support_force(x, par["r_m"] / (1 + par["r_m"]), par["r_m"])  # holding the body
    ph.terminal_constraint(weight - crater_capacity(x, ground), -ca.inf, 0,
                           name="crater holds the robot's weight at rest")


def impact_state(ph: OptimalControlProblem, par: dict[str, ca.SX]) -> None:
    """The paper's initial condition ``[l0, v0, 0, v0]`` on the first phase.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase starting at touchdown.
    par : dict
        The problem's parameters.
    """
    x = ph.x
    ph.initial_constraint(x[0] - par["l0"], 0.0, name="x_b(0) = l0")
    ph.initial_constraint(x[1] - par["v0"], 0.0, name="v_b(0) = v0")
    ph.initial_constraint(x[2], 0.0, name="x_f(0) = 0")
    ph.initial_constraint(x[3] - par["v0"], 0.0, name="v_f(0) = v0")


__all__ = ["ABOVE_CRATER", "ABOVE_SURFACE", "ARREST_MAX", "BODY_DESCENDING", "CRATER",
           "DESCENDING", "NO_PULL", "PARAMETERS", "STROKE", "T_MAX", "add_flight",
           "add_static", "add_yielding", "arrest_to_rest", "bounded_by", "crater_capacity",
           "impact_state", "parameters", "support_force"]
