"""Time-optimal swing-up of a pendulum with a bounded torque: several local optima.

``theta'' = u - sin(theta)``, ``|u| <= 0.4``, from hanging at rest
(``theta = 0``) to upright at rest (``theta = pi``) in minimum time. The torque
cannot lift the pendulum directly (0.4 < 1), so it pumps energy swing by
swing; every number of swings gives a bang-bang extremal, hence several local
optima (the time-optimal swing-up and its optimal synthesis: Mason, Broucke
and Piccoli 2008, "Time optimal swing-up of the planar pendulum", IEEE TAC
53(8), 1876-1886). No singular arc: on one, ``lambda_omega = 0`` on an
interval forces ``lambda_theta = 0`` and then ``H = 1 != 0``; so every
extremal is bang-bang.

Independent value (:func:`exact`): the optimum within each bang-bang
structure (first sign, number of arcs) is found by optimising the arc
durations with scipy (SLSQP, arcs integrated by ``odeint`` at rtol
1e-12, with their transition matrices: the constraints' exact derivative); the minimum over
the structures with 3 to 5 arcs is T* = 9.853736876 (:data:`REFERENCE`; four arcs: +, -, +,
-). Two arcs (or one) cannot swing up at all, by the energy ``E = omega^2/2 - cos(theta)``
(:func:`two_arc_energy_bound`): SLSQP searched them in vain for two thirds of the minute
the search took. Other extremals: five arcs (T = 17.288) and more. From the default guess,
a 50-interval collocation converges to the five-arc one, 75 % above the best.
"""

from __future__ import annotations

import math
from functools import cache, lru_cache

import casadi as ca
import numpy as np
from scipy.integrate import odeint
from scipy.optimize import brentq, minimize

from ocp import Collocation, OptimalControlProblem, Trajectory
from tests.oracles.ocp_suite.problems import SuiteProblem

UMAX = 0.4
INTERVALS = 50


def build() -> OptimalControlProblem:
    """The problem as a user would pose it: bounds, boundary values, nothing else."""
    p = OptimalControlProblem("pendulum_swingup")
    th, om = p.state("theta"), p.state("omega")
    u = p.control("u", -UMAX, UMAX)
    p.set_dynamics({"theta": om, "omega": u - ca.sin(th)})
    p.initial_constraint(th, 0.0)
    p.initial_constraint(om, 0.0)
    p.terminal_constraint(th, math.pi)
    p.terminal_constraint(om, 0.0)
    p.free_final_time(0.1, 50.0)
    p.minimize_terminal(p.T)
    return p


def transcription() -> Collocation:
    """The collocation :func:`ocp.multistart` solves (a module-level builder: picklable)."""
    return Collocation(build(), intervals=INTERVALS)


def _rhs(z: np.ndarray, _t: float, u: float) -> list[float]:
    return [z[1], u - math.sin(z[0])]


def _rhs_sensitivity(z: np.ndarray, _t: float, u: float) -> list[float]:
    """The state and its transition matrix ``Phi`` (row-major), ``Phi' = A(theta) Phi`` with
    ``A = [[0, 1], [-cos(theta), 0]]``."""
    c = math.cos(z[0])
    return [z[1], u - math.sin(z[0]), z[4], z[5], -c * z[2], -c * z[3]]


@lru_cache(maxsize=8)  # SLSQP asks the constraint, then its derivative, at the same point
def _end(durations: tuple[float, ...], first: float) -> tuple[np.ndarray, np.ndarray]:
    """State after the bang-bang arcs of these durations, the first with sign ``first``,
    and its derivative in the durations (2 x arcs): arc ``k`` lengthened moves the end by the
    later arcs' transition matrices times the field at arc ``k``'s end. Read only."""
    y = np.zeros(2)
    ends, phis = [], []
    for k, tau in enumerate(durations):
        u = first * UMAX * (-1) ** k
        phi = np.eye(2)
        if tau > 0:
            z = odeint(_rhs_sensitivity, np.r_[y, phi.ravel()], [0.0, tau], args=(u,),
                       rtol=1e-12, atol=1e-12, mxstep=100000)[-1]
            y, phi = z[:2], z[2:].reshape(2, 2)
        ends.append(np.array(_rhs(y, 0.0, u)))
        phis.append(phi)
    jac = np.empty((2, len(durations)))
    after = np.eye(2)  # the transition matrix of the arcs after arc k
    for k in range(len(durations) - 1, -1, -1):
        jac[:, k] = after @ ends[k]
        after = after @ phis[k]
    return y, jac


@cache  # the slow test reads the four-arc optimum, then exact() the same one among the rest
def structure_optimum(arcs: int, first: float, starts: int = 4) -> float:
    """Least total duration of ``arcs`` alternating bang arcs reaching (pi, 0) (inf if none)."""
    best = math.inf
    rng = np.random.default_rng(arcs * 10 + (first > 0))
    target = np.array([math.pi, 0.0])
    for _ in range(starts):
        x0 = rng.uniform(0.5, 4.0, arcs)
        res = minimize(np.sum, x0, jac=lambda d: np.ones_like(d), method="SLSQP",
                       bounds=[(0.0, 12.0)] * arcs,
                       constraints=[{"type": "eq",
                                     "fun": lambda d: _end(tuple(d), first)[0] - target,
                                     "jac": lambda d: _end(tuple(d), first)[1]}],
                       options={"ftol": 1e-13, "maxiter": 300})
        if res.success and np.max(np.abs(_end(tuple(res.x), first)[0] - target)) < 1e-9:
            best = min(best, float(res.fun))
    return best


# exact() (about 20 s of scipy) gives 9.8537368761452 (four arcs, +-+-; the five-arc
# structure -+-+- collapses onto it); with finite-difference derivatives it gave 9.853736876228
# (8e-12 apart). The fast tests use this value, a slow test recomputes it
REFERENCE = 9.8537368761452


def two_arc_energy_bound() -> float:
    """The most energy ``E = omega^2/2 - cos(theta)`` two bang arcs from hanging at rest can
    have on reaching ``theta = pi``: below the upright rest's ``E = 1``, so no structure of
    one or two arcs swings up.

    On an arc of constant ``u``, ``E' = u omega``: ``E`` changes by ``u`` times the angle
    swept. From rest (``E = -1``) the first arc stays in its well, ``u theta + cos(theta)
    >= 1``, so it ends within ``theta*`` of 0 on its torque's side (``0.4 theta* +
    cos(theta*) = 1``). First ``+``: the second arc (``u = -0.4``) sweeps ``theta`` up to
    ``pi`` against its torque and loses energy, ending below ``-1 + 0.4 theta*``. First
    ``-``: it ends at ``theta_1`` in ``[-theta*, 0]`` and the second (``u = +0.4``) gains
    ``0.4 (pi - theta_1)``: at most ``-1 + 0.4 pi + 0.8 theta*``, the larger of the two.
    """
    theta_star = brentq(lambda th: UMAX * th + math.cos(th) - 1.0, 0.1, math.pi)
    return -1.0 + UMAX * math.pi + 2 * UMAX * theta_star


@cache
def exact() -> float:
    """The global minimum time: the best structure with 3 to 5 arcs (see the module; fewer
    arcs cannot reach the upright rest, :func:`two_arc_energy_bound`)."""
    if not two_arc_energy_bound() < 1.0:
        raise AssertionError("two arcs could reach the upright rest: search them too")
    return min(structure_optimum(a, s) for a in range(3, 6) for s in (1.0, -1.0))


def reference() -> float:
    """:data:`REFERENCE`, the result of :func:`exact` (recomputed by a slow test)."""
    return REFERENCE


def hand_guess() -> Trajectory:
    """A hand-built start in the best basin: the known structure (+, -, +, -) with rounded
    arc durations (1.2, 3.2, 4.1, 1.4), simulated (what the issue needed without multistart)."""
    durations, t, y = (1.2, 3.2, 4.1, 1.4), [0.0], [np.zeros(2)]
    us = [UMAX]
    for k, tau in enumerate(durations):
        u = UMAX * (-1) ** k
        ts = np.linspace(0.0, tau, 41)[1:]
        ys = odeint(_rhs, y[-1], np.r_[0.0, ts], args=(u,), rtol=1e-10, atol=1e-10)[1:]
        t += list(t[-1] + ts)
        y += list(ys)
        us += [u] * ts.size
    return Trajectory(np.array(t), np.array(y), np.array(us), ("theta", "omega"), ("u",))


PROBLEM = SuiteProblem(
    "pendulum_swingup",
    "Mason, Broucke, Piccoli (2008), IEEE TAC 53(8) (bang-bang optimal synthesis of the "
    "pendulum swing-up); |u| <= 0.4: T* = 9.853737 by an independent switching-time "
    "optimisation over structures (scipy)",
    math.nan, 0.0, build, exact=reference, exact_rtol=1e-6, guess=hand_guess,
    covers=("several local optima (multistart)", "free final time", "bang-bang, one control"),
    bang_bang=True, intervals=INTERVALS, tol=1e-7,
    notes="from the default guess the collocation converges to the five-arc extremal "
          "(T = 17.288); ocp.multistart finds the four-arc optimum, as does the hand-built "
          "guess; exact() takes minutes, the suite uses its result REFERENCE")


def coarse_transcription() -> Collocation:
    """A 20-interval collocation: a cheap builder for tests of parallel starts."""
    return Collocation(build(), intervals=20)
