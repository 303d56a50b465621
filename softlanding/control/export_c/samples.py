"""Random inputs of the landing controller: the calls of random landings, recorded.

A landing is the robot on a random ground ``(K, c_d)`` at a random impact velocity, with
a random sample period, sensor noise and margin. Its first plan is solved from the impact
state (:func:`~softlanding.control.bangbang.solve_plan`), then the samples follow
(:func:`~softlanding.control.bangbang.control_step`), each from the state the last plan
gave (a plant by Euler steps on the true ground, whose ``K`` and ``c_d`` are off the
controller's prior by up to 50 %, and noisy sensors; or, in a fifth of the landings, the
state the plan predicted, after a first sample at the impact: the plan-holds path),
until the plan's foot stop (a state the structure does not cover gets the compiled fallback:
its samples too); every other landing with the creep law on (``P_CREEP = 1``: creeping or
braking, the plant's foot stop ends it). Every
call's inputs (``P`` and ``M`` before it included) are recorded, so that another
implementation can be run on exactly the same ones.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.limits import force_limit

#: Samples of one landing at most (more landings, more grounds, for the same number).
MAX_SAMPLES = 30

@dataclass(frozen=True)
class Probe:
    """A first plan every comparison runs.

    Attributes
    ----------
    K, c_d : float
        The ground (the controller's prior).
    guess : (float, float)
        The push and pull durations Newton starts from.
    x : (float, float, float, float)
        The state.
    """

    K: float
    c_d: float
    guess: tuple[float, float]
    x: tuple[float, float, float, float]


#: A creep's state (``K = 1.5``, ``c_d = 1``, the paper's robot, a few samples after impact)
#: whose push-pull plan stops the foot with the body rising: the paper's robot's first plan
#: from it is not covered (status ``CREEP``), a path random landings reach only by chance.
#: Its first plan is compared too (for another robot whatever its status is).
CREEP_PROBE = Probe(1.5, 1.0, (0.05, 0.04), (9.9768, 0.768, -0.5035, -2.7782))


@dataclass(frozen=True)
class Landing:
    """One landing's inputs.

    Attributes
    ----------
    P : array
        The robot's numbers (the ground's ``K``, ``c_d``: the controller's prior).
    guess : (float, float)
        The first plan's durations before Newton.
    x0 : array of 4
        The state at impact.
    truth : (float, float)
        The ground's ``(K, c_d)`` the measured accelerations come from.
    noise : float
        Relative standard deviation of the measured state and acceleration.
    exact : bool
        The measured state is the plan's prediction (when it has one).
    seed : int
        Of the measurements' noise.
    """

    P: np.ndarray
    guess: tuple[float, float]
    x0: np.ndarray
    truth: tuple[float, float]
    noise: float
    exact: bool
    seed: int


def random_landings(robot: Robot, seed: int = 0) -> Iterator[Landing]:
    """Random landings of ``robot``, one after another.

    Parameters
    ----------
    robot : Robot
        With a force limit.
    seed : int
        Of :func:`numpy.random.default_rng`.
    """
    rng = np.random.default_rng(seed)
    r = robot
    u_max = force_limit(robot)
    for i in itertools.count():
        k = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
        c_d = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 1.0))
        noise = float(rng.choice([0.0, 1e-6, 1e-4]))
        exact = rng.random() < 0.2  # the plant follows the plan's prediction exactly
        margin = 0.0 if exact else float(rng.choice([0.0, 2.0]))
        P = bb.robot_numbers(r.r_m, r.s, u_max, k, c_d, max(noise, 1e-6), margin,
                             float(rng.uniform(0.005, 0.03)), creep=i % 2 == 1)
        if i % 5 == 4:  # a tight bound on a sample's work: the deferred samples too
            P[bb.P_WORK] = 30.0
        truth = (k, c_d) if exact else (k * float(rng.uniform(0.5, 1.5)),
                                         c_d * float(rng.uniform(0.5, 1.5)))
        x0 = Impact(float(rng.uniform(-10.0, -0.5))).initial_state(r)
        yield Landing(P, (float(rng.uniform(0.05, 0.2)), float(rng.uniform(0.05, 0.2))), x0,
                      truth, 0.0 if exact else noise, exact, seed * 100_003 + i)


@dataclass(frozen=True)
class Call:
    """One call of the controller: its inputs.

    Attributes
    ----------
    P, M : array
        The numbers and the memory before the call.
    x : array of 4
        The (measured) state.
    a_f, u, h : float
        The measured foot acceleration, the force the sample ended under, its length
        (unused by a first plan).
    first : bool
        The first plan (:func:`~softlanding.control.bangbang.solve_plan`), else a sample
        (:func:`~softlanding.control.bangbang.control_step`).
    estimate : bool
        The sample updates the estimate (the random landings' always do).
    """

    P: np.ndarray
    M: np.ndarray
    x: np.ndarray
    a_f: float
    u: float
    h: float
    first: bool
    estimate: bool = True


def recorded_calls(robot: Robot, n_steps: int, seed: int = 0) -> tuple[list[Call], int]:
    """The calls of random landings (:func:`random_landings`) of ``robot`` to the Python
    controller, ``n_steps`` samples in all (each landing's first plan besides).

    Parameters
    ----------
    robot : Robot
        With a force limit.
    n_steps : int
        Samples.
    seed : int
        Of the landings.

    Returns
    -------
    calls : list of Call
        In order, and last the first plan from :data:`CREEP_PROBE`'s state.
    landings : int
        How many landings they make (the probe not counted).
    """
    ws = bb.workspace()
    calls: list[Call] = []
    steps = n_landings = 0
    landings = random_landings(robot, seed)
    while steps < n_steps:
        case = next(landings)
        n_landings += 1
        rng = np.random.default_rng(case.seed)
        P = case.P.copy()
        M = bb.new_memory(*case.guess, (float(P[bb.P_K]), float(P[bb.P_CD])), (1.0, 1.0),
                          float(P[bb.P_NOISE]))
        x = np.ascontiguousarray(case.x0, float)
        h = float(P[bb.P_PERIOD])
        for sample in range(MAX_SAMPLES + 1):
            if sample == 0:
                calls.append(Call(P.copy(), M.copy(), x, 0.0, 0.0, 0.0, True))
                st = int(bb.solve_plan(P, M, x, *ws, np.inf))
            else:
                hk = h
                creeping = M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING)  # (a force, held)
                if case.exact and not creeping:  # the plan's own prediction (first: a
                    # sample at impact)
                    hk = h if M[bb.M_PRED_OK] == 1.0 else 0.0
                    x = M[bb.M_PRED:bb.M_PRED + 4].copy() if hk else x.copy()
                    u = float(P[bb.P_UMAX]) if M[bb.M_PHASE] == bb.PUSH and M[bb.M_TAU1] > hk \
                        else -float(P[bb.P_UMAX])
                    a_f = float(P[bb.P_AF0] + P[bb.P_BF] * u + P[bb.P_GF] * (
                        case.truth[0] * -x[2] + case.truth[1] * x[3] * x[3]))
                else:  # the plant, and the sensors' noise
                    x, u, a_f = _plant(P, M, x, h, case.truth)
                    if creeping and x[3] >= 0.0:
                        break  # the creep law's foot stopped
                    x = x * (1.0 + case.noise * rng.standard_normal(4))
                    a_f = a_f * (1.0 + case.noise * rng.standard_normal())
                x[3] = min(x[3], -1e-6)  # (the foot still sinks: the loop's condition)
                calls.append(Call(P.copy(), M.copy(), x, a_f, u, hk, False))
                st = int(bb.control_step(P, M, x, a_f, u, hk, True, *ws))
                steps += 1
            length = np.inf if M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING) else (
                (M[bb.M_TAU1] if M[bb.M_PHASE] == bb.PUSH else 0.0) + M[bb.M_TAU2])
            if steps >= n_steps or length <= h or (sample == 0 and st != bb.OK):
                break  # the foot's stop within the next sample, or a first plan not made
    pr = CREEP_PROBE
    P = bb.robot_numbers(robot.r_m, robot.s, force_limit(robot), pr.K, pr.c_d)
    M = bb.new_memory(*pr.guess, (pr.K, pr.c_d), (1.0, 1.0), 1e-6)
    calls.append(Call(P, M, np.array(pr.x, float), 0.0, 0.0, 0.0, True))
    return calls, n_landings


def _plant(P: np.ndarray, M: np.ndarray, x: np.ndarray, h: float,
           truth: tuple[float, float]) -> tuple[np.ndarray, float, float]:
    """The robot on the true ground over one sample under the plan in ``M`` (push until
    its switch, then pull), by 20 semi-implicit Euler steps (a plant that is not the
    controller's model); the state, the force and the foot's acceleration at its end."""
    t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
    xb, vb, xf, vf = (float(v) for v in x)
    dt = h / 20
    u = a_f = 0.0
    for i in range(20):
        u = float(P[bb.P_UMAX]) if (i + 1) * dt <= t1 else -float(P[bb.P_UMAX])
        if M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING):  # (the creep law's or the brake's
            u = float(M[bb.M_UCREEP])  # force, held)
        a_f = float(P[bb.P_AF0] + P[bb.P_BF] * u
                    + P[bb.P_GF] * (truth[0] * -xf + truth[1] * vf * vf))
        vb += dt * float(P[bb.P_AB0] + P[bb.P_BB] * u)
        xb += dt * vb
        vf += dt * a_f
        xf += dt * vf
    return np.array([xb, vb, xf, vf]), u, a_f


__all__ = ["CREEP_PROBE", "MAX_SAMPLES", "Call", "Landing", "Probe", "random_landings",
           "recorded_calls"]
