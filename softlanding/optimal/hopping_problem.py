"""One vertical hop on yielding ground as a multi-phase OCP (public :mod:`ocp` API only).

**The cycle.** Heights are measured from the undisturbed surface and every landing
is on **fresh ground at the same surface level** (the robot hops on to an
untouched patch: a vertical model of hopping across a fresh bed). The apex
posture is the paper's: the leg at ``s/2`` and at rest, the foot at the height
``h = v0^2/2``; falling from there the robot touches down with the paper's impact
state ``[s/2, v0, 0, v0]`` (the fall is ballistic and needs no actuation, so the
cycle starts at touchdown). Phases:

1. **yielding** on fresh ground until the foot stops;
2. **static**: the foot at the crater bottom, the support force within ``[0,
   crater depth]``; the landing's arrest and the push-off. A harder push would
   yield the crater further: ``steps=2`` allows that (yielding, static, yielding,
   static). The phase ends at lift-off, where the actuator pulls the foot off the
   crater (the ground cannot pull);
3. **flight up** to the apex: the foot above the crater bottom (the crater depth is
   a constant state ``crater`` of this phase); at the apex the **centre of mass**
   is at rest at its starting height ``h + m_b s/2``, and the leg is back at
   ``s/2`` at rest (periodic: the next fall lands at ``v0`` again).

**The cost**: the energy the actuator draws per cycle with regenerative
efficiency ``eta`` in ``[0, 1)``: ``int (P+ - eta P-) dt`` with ``P = u (v_b - v_f)``
the power the actuator puts into the robot. It is posed smoothly with a slack
control ``p >= max(P, 0)`` (the mixed constraint ``p - P >= 0``) and the running
cost ``(1 - eta) p + eta P``. Over the cycle ``int P dt`` equals the ground's loss
``d^2/2`` (the robot's mechanical energy returns to its value at the apex), so the
cost is ``d^2/2 + (1 - eta) int P- dt``.

**Legs** (:data:`LEGS`) differ in stance; in flight the actuator is free for all
(the foot must be pulled out of the crater and the posture restored):

* ``"free"``: ``|u| <= u_max`` in every phase (the optimum);
* ``"impedance"``: in stance ``u = -k_p (l - s/2) - k_d l' + u_t`` with one ``(k_p,
  k_d)`` (``l = x_b - x_f``); the thrust ``u_t >= 0`` is on from the body's lowest
  point (its velocity crosses zero: the static phase is split there) until
  lift-off, where the support force reaches zero (the law is continuous). The
  gains and the thrust are decision variables; the law must stay within ``|u| <=
  u_max``;
* ``"rigid"``: the leg locked from touchdown until the foot stops (lock force
  unlimited, as the paper's rigid impactor), then the optimal push-off.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting, OptimalControlProblem
from softlanding.model.dynamics import STATE_NAMES, robot_rhs, stance_dynamics
from softlanding.optimal.stance_phases import (
    ABOVE_CRATER,
    ARREST_MAX,
    CRATER,
    DESCENDING,
    NO_PULL,
    STROKE,
    crater_capacity,
    impact_state,
    parameters,
    support_force,
)

LEGS = ("free", "impedance", "rigid")
POWER = "slack p >= actuator power u (v_b - v_f)"
FORCE = "force limit |u| <= u_max"
APEX = ("apex: centre of mass back at its height", "apex: centre of mass at rest",
        "apex: leg at s/2", "apex: leg at rest")
"""The names of :func:`apex_residuals`, in order."""


def apex_target(mb: Any, height: Any, s: Any) -> tuple[Any, Any, Any, Any]:
    """The apex posture: centre of mass height and velocity, leg length and rate.

    The centre of mass at rest at ``height + m_b s/2`` (the foot at ``height = v0^2/2``
    above the surface with the leg at ``s/2``), the leg at ``s/2`` and at rest. With
    :func:`apex_posture` the one definition of the apex, used by the transcribed problem,
    the exact-arc refinement (:mod:`softlanding.optimal.hop_arcs`) and the replay's check
    and the thrust's target (:mod:`softlanding.optimal.hopping`).

    Parameters
    ----------
    mb : float or CasADi expression
        Body mass (fraction of the total).
    height : float or CasADi expression
        The foot's apex height ``v0^2/2``.
    s : float or CasADi expression
        The stroke.
    """
    return (height + mb * s / 2, 0.0, s / 2, 0.0)


def apex_posture(x: Any, mb: Any, mf: Any) -> tuple[Any, Any, Any, Any]:
    """What :func:`apex_target` prescribes, of a state: centre of mass height and velocity,
    leg length and rate.

    Parameters
    ----------
    x : array or CasADi expression
        ``[x_b, v_b, x_f, v_f, ...]``.
    mb, mf : float or CasADi expression
        Body and foot masses (fractions of the total).
    """
    return (mb * x[0] + mf * x[2], mb * x[1] + mf * x[3], x[0] - x[2], x[1] - x[3])


def apex_residuals(x: Any, mb: Any, mf: Any, height: Any, s: Any) -> list[Any]:
    """The apex conditions as residuals, zero at the apex (named by :data:`APEX`):
    :func:`apex_posture` less :func:`apex_target`; on numbers, arrays or CasADi
    expressions.

    Parameters
    ----------
    x, mb, mf
        As for :func:`apex_posture`.
    height, s
        As for :func:`apex_target`.
    """
    return [p - t for p, t in zip(apex_posture(x, mb, mf), apex_target(mb, height, s),
                                  strict=True)]


def _add(mp: MultiPhaseProblem, name: str, par: dict, mode: str, law: Any, bounds: tuple,
         eta: ca.SX, crater: bool = False) -> OptimalControlProblem:
    """A phase of the hop: states, ``u`` (a control, or the law), the power slack ``p``, the
    dynamics of its ground ``mode`` and the running cost."""
    ph = mp.phase(name)
    for n in STATE_NAMES:
        ph.state(n)
    if crater:
        ph.state("crater")
    x = ph.x
    if law is None:
        u = ph.control("u", lower=bounds[0], upper=bounds[1])
    else:
        u = law(x)
        ph.path_constraint(u, -par["u_max"], par["u_max"], name=FORCE)
    p = ph.control("p", lower=0.0, upper=ca.inf)
    r_m = par["r_m"]
    if mode == "yielding":
        rhs = stance_dynamics(x[:4], u, r_m)
        ph.path_constraint(x[3], -ca.inf, 0, name=DESCENDING)
    elif mode == "static":
        f = support_force(x[:4], u, r_m)
        rhs = robot_rhs(x[:4], u, f, r_m)
        ph.path_constraint(f - crater_capacity(x[:4]), -ca.inf, 0, name=CRATER)
        ph.path_constraint(f, 0, ca.inf, name=NO_PULL)
    else:
        rhs = robot_rhs(x[:4], u, 0.0, r_m)
    ph.set_dynamics(ca.vertcat(rhs, 0) if crater else rhs)
    ph.path_constraint(x[0] - x[2], 0, par["s"], name=STROKE)
    power = u * (x[1] - x[3])
    ph.path_constraint(p - power, 0, ca.inf, name=POWER)
    ph.minimize_integral((1 - eta) * p + eta * power)
    return ph


def impedance_law(k_p: Any, k_d: Any, s: Any, u_t: Any = 0.0) -> Any:
    """``x -> -k_p (x_b - x_f - s/2) - k_d (v_b - v_f) + u_t`` (symbolic or numeric).

    Parameters
    ----------
    k_p, k_d : float or expression
        Stiffness and damping.
    s : float or expression
        Stroke (the rest length is ``s/2``).
    u_t : float or expression
        Thrust.
    """
    def law(x: Any) -> Any:
        return -k_p * (x[0] - x[2] - s / 2) - k_d * (x[1] - x[3]) + u_t

    return law


START = ("touchdown", "rest", "lift-off")
"""Where a hop problem starts: at touchdown (the whole cycle), at rest on the crater (the
push-off after a given landing), or at lift-off (the flight only)."""
START_PARAMETERS = ("start_x_b", "start_v_b", "start_x_f", "start_v_f")
"""The given start state (``start != "touchdown"``)."""


def build_hop_problem(start: str = "touchdown", steps: int = 1) -> MultiPhaseProblem:
    """The hop cycle (see the module docstring), or its end from a given state.

    Parameters
    ----------
    start : {"touchdown", "rest", "lift-off"}
        The whole cycle with a free actuator (the optimum); the push-off and flight from
        a given state at rest on the crater (after a rigid or impedance landing); or the
        flight alone from a given lift-off state.
    steps : {1, 2}
        Yielding steps allowed (``start="touchdown"``).
    """
    if start not in START:
        raise ValueError(f"start must be one of {START}, got {start!r}")
    if steps not in (1, 2) or (steps == 2 and start != "touchdown"):
        raise ValueError("steps=2 needs start='touchdown'")
    mp = MultiPhaseProblem("hop" + ("" if start == "touchdown" else
                                    "_from_" + start.replace("-", "_")))
    par = parameters(mp)
    eta = mp.parameter("eta")
    given = [mp.parameter(n) for n in START_PARAMETERS] if start != "touchdown" else []
    free = (-par["u_max"], par["u_max"])
    stance: list[OptimalControlProblem] = []
    if start == "touchdown":
        stance.append(_add(mp, "yielding", par, "yielding", None, free, eta))
        for k in range(steps):
            stance.append(_add(mp, f"static {k + 1}" if steps == 2 else "static", par,
                               "static", None, free, eta))
            if k + 1 < steps:
                stance.append(_add(mp, "yielding 2", par, "yielding", None, free, eta))
        impact_state(stance[0], par)
    elif start == "rest":
        stance.append(_add(mp, "static", par, "static", None, free, eta))
    up = _add(mp, "flight up", par, "flight", None, free, eta, crater=True)
    first = stance[0] if stance else up
    for k, g in enumerate(given):
        first.initial_constraint(first.x[k] - g, 0.0, name=f"{STATE_NAMES[k]}(0) given")
    if start == "lift-off":
        up.initial_constraint(up.x[4] + given[2], 0.0, name="crater under the foot")
    _cycle(mp, par, stance, up)
    return mp


def _cycle(mp: MultiPhaseProblem, par: dict, stance: list[OptimalControlProblem],
           up: OptimalControlProblem) -> None:
    """Foot stops, lift-off and apex conditions; times; the links."""
    r_m = par["r_m"]
    mb, mf = r_m / (1 + r_m), 1 / (1 + r_m)
    for i, ph in enumerate(stance):
        if ph.name.startswith("yielding"):
            ph.terminal_constraint(ph.x[3], 0.0, name="foot stopped v_f(T) = 0")
        if i == 0:
            ph.free_final_time(1e-3, ARREST_MAX, guess=1.0)
        else:
            ph.free_duration(0.0 if ph.name in ("static 1", "yielding 2") else 1e-3,
                             ARREST_MAX, guess=1.0)
    x = up.x
    up.path_constraint(x[2] + x[4], 0, ca.inf, name=ABOVE_CRATER)
    if stance:
        up.free_duration(1e-3, ARREST_MAX, guess=1.0)
    else:
        up.free_final_time(1e-3, ARREST_MAX, guess=1.0)
    for res, name in zip(apex_residuals(x, mb, mf, par["v0"] ** 2 / 2, par["s"]), APEX,
                         strict=True):
        up.terminal_constraint(res, 0.0, name=name)
    chain = [*stance, up]
    for a, b in zip(chain[:-1], chain[1:], strict=True):
        mp.link(a, b, states=list(STATE_NAMES))
    if stance:
        mp.link_constraint(up.at_t0(x[4]) + stance[-1].at_tf(stance[-1].x[2]), 0.0,
                           name="crater depth carried into the flight")


@lru_cache(maxsize=4)
def _hop_problem(start: str, steps: int) -> MultiPhaseProblem:
    """The problem every grid of :func:`hop_transcription` transcribes (one object: a grid
    warm-started from another's optimum is then the same problem, and keeps its scaling)."""
    return build_hop_problem(start, steps)


@lru_cache(maxsize=10)
def hop_transcription(start: str = "touchdown", steps: int = 1,
                      doublings: int = 0) -> MultipleShooting:
    """The transcribed hop problem, built once per arguments (expanded to SX; path
    constraints also at the RK4 inner steps).

    Parameters
    ----------
    start : {"touchdown", "rest", "lift-off"}
        See :func:`build_hop_problem`.
    steps : {1, 2}
        Yielding steps.
    doublings : int
        The base grid's nodes per phase doubled this many times (the grid sequence of
        :func:`softlanding.optimal.hopping.solve_hop`'s error estimate).
    """
    nodes = {"touchdown": [60, 80, 60], "rest": [80, 60], "lift-off": [40]}[start]
    if steps == 2:
        nodes = [60, 30, 30, 60, 60]
    nodes = [n * 2 ** doublings for n in nodes]
    # a doubled grid starts from the coarser grid's optimum, whose bang-bang controls sit on
    # their bounds: Ipopt's default push of the start 1e-2 into the interior (and its barrier
    # at 0.1) sent the v0 = -3 hop's 120/160/120 grid to another local optimum, 1.3 % above
    # its 60/80/60 start; kept at the start, it improves on it
    near = {"mu_init": 1e-6, "bound_push": 1e-8, "bound_frac": 1e-8} if doublings else {}
    # the flight alone is degenerate near its optima: Ipopt, trying its linear systems'
    # constraint block unperturbed first at every iteration, regularised the Hessian up to
    # 1e14 and spent about 0.1 s an iteration factorising (2 to 7.5 s a flight); with that
    # block always perturbed, 0.2 to 0.6 s (best_impedance_hop(-3): 27 -> 5 s), and at
    # v0 = -3 the default guess reaches the lower local optimum (17.036, not 19.90)
    flight = {"perturb_always_cd": "yes"} if start == "lift-off" else {}
    return MultipleShooting(_hop_problem(start, steps), nodes=nodes, integrator="rk4",
                            substeps=4, expand=True, inner_constraints=True,
                            ipopt_options={"max_iter": 1500, **near, **flight})


__all__ = ["APEX", "FORCE", "LEGS", "POWER", "START", "START_PARAMETERS", "apex_posture",
           "apex_residuals", "apex_target", "build_hop_problem", "hop_transcription",
           "impedance_law"]
