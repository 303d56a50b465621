"""The compiled controller's arrays and numbers: the layout of its robot and ground numbers
``P``, of its memory ``M`` and its work arrays, its phases, statuses and tolerances, and how
they are built (:func:`robot_numbers`, :func:`new_memory`, :func:`workspace`) from the one
definition of the dynamics (:func:`softlanding.model.dynamics.robot_rhs`).

:mod:`softlanding.control.bangbang` (the compiled step) and
:mod:`softlanding.control.fallback` (what acts where its structure does not cover a state)
read them; ``bangbang`` re-exports every name, as before, and the exported C's layout is
generated from them (:mod:`softlanding.control.export_c.layout`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.model.dynamics import VB, VF, robot_rhs
from softlanding.simulation.kernel.const import JIT

#: Relative and absolute tolerance of the foot's integration (Newton's last steps).
RTOL = 1e-13

#: Newton's iterations per sample at most, and its tolerance on the durations (relative to
#: the plan's length).
MAX_NEWTON, NEWTON_TOL = 30, 1e-13

#: The relative tolerance of the arcs while Newton's last step (relative to the plan's
#: length) is above ``TIGHTEN`` (the error of the arcs is then far below the step: the step
#: is as good; the last steps, to convergence, are at :data:`RTOL`), and the relative change
#: of the estimated ground after which a sample's first step counts as large.
LOOSE_RTOL, TIGHTEN = 1e-8, 1e-6

#: The integrator steps (taken or rejected) one sample may spend: the hard bound on its
#: work. A sample that runs out keeps the last whole Newton iterate (or the last plan,
#: shifted) and the next sample's Newton goes on from there (``M_DEFERRED`` counts them).
WORK = 100

#: What :func:`_flow` returns: the arc marched, the march failed, no integrator step left.
MARCH_FAILED, MARCHED, SPENT = 0, 1, 2

# the layout of the robot and ground numbers P
(P_AB0, P_BB, P_AF0, P_BF, P_GF, P_K, P_CD, P_RM, P_S, P_UMAX, P_HOLD0, P_NOISE,
 P_MARGIN, P_BUDGET, P_PERIOD, P_WORK, P_CREEP) = range(17)
NP = 17
# the layout of the controller's memory M
(M_PHASE, M_TAU1, M_TAU2, M_TH0, M_TH1, M_P00, M_P01, M_P11, M_SAMPLES, M_ITER,
 M_STATUS, M_XBT, M_VBT, M_XFT, M_UNCONVERGED, M_PRED, M_PRED_OK, M_KPLAN,
 M_CPLAN, M_LAST_STEP, M_WORK, M_DEFERRED, M_UCREEP, M_FALLBACKS, M_WHY) = (
    *range(15), 15, 19, 20, 21, 22, 23, 24, 25, 26, 27)
NM = 28

#: Phases: pushing (both arcs left), pulling (the foot's stop left), creeping (the creep
#: law's force, :mod:`softlanding.control.creep`, every sample to the foot's stop), braking
#: (the fallback's safe brake, :mod:`softlanding.control.fallback`, every sample to the
#: foot's stop).
PUSH, PULL, CREEPING, BRAKING = 0, 1, 2, 3
#: Statuses of a step: covered (the plan re-solved), and why not.
#: (:data:`DEFERRED`: the sample's integrator steps ran out, see :data:`WORK`.)
#: (:data:`CREEP_LAW`: the creep law's force, in ``M[M_UCREEP]``, covers the state; only with
#: ``P[P_CREEP] = 1``, else such a state is :data:`CREEP`, not covered.)
#: (:data:`KEPT`, :data:`BRAKE`: the fallback's, where the structure did not cover the
#: state: the plan kept with the margin dropped, the safe brake's force.)
(OK, NEWTON_FAILED, ARREST_FAILS, PATH_LIMIT, CONVERGING, HOLDS, CREEP, DEFERRED,
 CREEP_LAW, KEPT, BRAKE) = range(11)
STATUS_NAMES = {OK: "ok", NEWTON_FAILED: "newton failed", ARREST_FAILS: "arrest fails",
                PATH_LIMIT: "path limit", CONVERGING: "converging", HOLDS: "plan holds",
                CREEP: "creep", DEFERRED: "deferred", CREEP_LAW: "creep law", KEPT: "kept",
                BRAKE: "brake"}

#: Relative agreement of the measured state with the plan's prediction, and of the estimate
#: with the plan's ground, under which a sample keeps the plan (as the re-planning MPC's).
PLAN_HOLDS_TOL = 1e-8

#: Standard deviations of the estimate by which the ground the creep law's takeover is judged
#: on is stiffer and less draggy than the estimate (:func:`_step`).
CREEP_SIGMAS = 3.0

#: The creep law's force is limited to keep the stroke this fraction of ``s`` inside its
#: limits (:func:`stroke_guard`; the force is held over a sample, the ground's changes).
STROKE_MARGIN = 1e-3

#: The fraction of the body's deceleration under the force limit the safe brake keeps in
#: reserve to stop the body by, above the foot's present position, while the foot yields
#: (:func:`~softlanding.control.fallback.body_floor`).
BODY_DECEL = 1.0

#: Newton iterations per sample while the switch is more than three samples away (one:
#: acados' real-time iteration).
BUDGET = 1
#: Samples in a row whose Newton step is still above a tenth of the period before the
#: state counts as not covered.
MAX_UNCONVERGED = 12


def force_coefficients(r_m: float) -> tuple[float, float]:
    """``beta, gamma`` of the foot's acceleration ``alpha + beta u + gamma f_g``.

    Parameters
    ----------
    r_m : float
        Mass ratio.
    """
    P = robot_numbers(r_m, 1.0, 1.0, 1.0, 0.0)
    return float(P[P_BF]), float(P[P_GF])


def ground_force_noise(r_m: float, sensor_noise: float, filtered: bool = False) -> float:
    """Standard deviation of one ground force the estimator derives from the foot's measured
    acceleration and force, each with noise ``sensor_noise`` (at least ``1e-6``: the
    estimator's weight of an exact measurement).

    Parameters
    ----------
    r_m : float
        Mass ratio.
    sensor_noise : float
        Standard deviation of the measured acceleration and force.
    filtered : bool
        The force is the one applied (known) and the foot's state filtered
        (:mod:`softlanding.control.foot_filter`): the acceleration's noise, and
        :data:`FILTERED_REGRESSOR` for the filtered state's error in the regressors.
    """
    beta, gamma = force_coefficients(r_m)
    if filtered:
        return max(sensor_noise * float(np.hypot(1.0 / gamma, FILTERED_REGRESSOR)), 1e-6)
    return max(sensor_noise * float(np.hypot(1.0, beta)) / abs(gamma), 1e-6)


#: The ground force's error from the filtered foot state in the regressors (its position
#: times ``K``, its velocity times ``2 c_d |v_f|``), relative to the sensor's noise: about
#: 1e-2 and 5e-2 of it measured at ``v0 = -1``; 0.1 (0.3: deeper on 4 of 5 cases).
FILTERED_REGRESSOR = 0.1


def robot_numbers(r_m: float, s: float, u_max: float, stiffness: float, c_d: float,
                  noise_std: float = 1e-6, margin: float = 0.0,
                  period: float = 0.01, creep: bool = False) -> np.ndarray:
    """The numbers the compiled step reads (``P``), from the one definition of the dynamics.

    Parameters
    ----------
    r_m, s, u_max : float
        Mass ratio, stroke, force limit.
    stiffness, c_d : float
        The ground's ``K`` and drag number (the plan's).
    noise_std : float
        Standard deviation of one measured ground force (the estimator's).
    margin : float
        Plan for the estimate less ``margin`` standard deviations.
    period : float
        The sample period (the plan-holds check predicts the next sample).
    creep : bool
        A state whose plan ends with the body rising (:data:`CREEP`) on ground with drag
        switches to the creep law (:mod:`softlanding.control.creep`; status
        :data:`CREEP_LAW`) instead of being reported not covered (``mpc_landing`` and
        ``softlanding export-controller``'s numbers have it on; the exported C has the law
        too).
    """
    x = np.zeros(4)
    b0 = robot_rhs(x, 0.0, 0.0, r_m)
    b1 = robot_rhs(x, 1.0, 0.0, r_m)
    g1 = robot_rhs(x, 0.0, 1.0, r_m)
    P = np.zeros(NP)
    P[P_AB0], P[P_BB] = float(b0[VB]), float(b1[VB] - b0[VB])
    P[P_AF0], P[P_BF], P[P_GF] = float(b0[VF]), float(b1[VF] - b0[VF]), float(g1[VF] - b0[VF])
    P[P_K], P[P_CD], P[P_RM], P[P_S], P[P_UMAX] = stiffness, c_d, r_m, s, u_max
    P[P_HOLD0] = 1.0 / (1.0 + r_m)
    P[P_NOISE] = noise_std
    P[P_MARGIN] = margin
    P[P_BUDGET] = BUDGET
    P[P_PERIOD] = period
    P[P_WORK] = WORK
    P[P_CREEP] = 1.0 if creep else 0.0
    return P


def new_memory(tau1: float, tau2: float, prior: tuple[float, float],
               prior_std: tuple[float, float], noise_std: float) -> np.ndarray:
    """The controller's memory (``M``) before impact: the first plan and the estimator's prior.

    Parameters
    ----------
    tau1, tau2 : float
        The first plan's push and pull durations (``tau1 = 0``: pulling from the start).
    prior, prior_std : (float, float)
        The estimator's prior ``(K, c_d)`` and its standard deviations.
    noise_std : float
        Standard deviation of one measured ground force.
    """
    M = np.zeros(NM)
    M[M_PHASE] = PUSH if tau1 > 0 else PULL
    M[M_TAU1], M[M_TAU2] = tau1, tau2
    M[M_TH0], M[M_TH1] = prior
    M[M_P00] = (prior_std[0] / noise_std) ** 2
    M[M_P11] = (prior_std[1] / noise_std) ** 2
    return M


def workspace() -> tuple[np.ndarray, np.ndarray]:
    """Work arrays of the compiled step: nothing is allocated per sample, and two arrays
    (not nine) keep the call's dispatch short. ``K``: the 13 stages, then the Jacobian
    (rows 13-14); ``W``: trial state, new state, state, residuals, path and end numbers,
    body, largest ``v_f``, integrator steps left."""
    return np.zeros((15, 6)), np.zeros(33)


@njit(**JIT, inline="always")
def foot_acc(P, u, xf, vf):
    """The foot's acceleration under force ``u`` (``-c_d v_f |v_f|``: the law ``c_d v_f^2`` of
    a descending foot, continued past the stop as a drag, so that a guess whose pull runs
    past the stop still marches)."""
    return P[P_AF0] + P[P_BF] * u + P[P_GF] * (-P[P_K] * xf - P[P_CD] * vf * abs(vf))


__all__ = ["ARREST_FAILS", "BODY_DECEL", "BRAKE", "BRAKING", "BUDGET", "CONVERGING", "CREEP",
           "CREEPING", "CREEP_LAW", "CREEP_SIGMAS", "DEFERRED", "FILTERED_REGRESSOR", "HOLDS",
           "KEPT", "LOOSE_RTOL", "MARCHED", "MARCH_FAILED", "MAX_NEWTON", "MAX_UNCONVERGED",
           "M_CPLAN", "M_DEFERRED", "M_FALLBACKS", "M_ITER", "M_KPLAN", "M_LAST_STEP", "M_P00",
           "M_P01", "M_P11", "M_PHASE", "M_PRED", "M_PRED_OK", "M_SAMPLES", "M_STATUS", "M_TAU1",
           "M_TAU2", "M_TH0", "M_TH1", "M_UCREEP", "M_UNCONVERGED", "M_VBT", "M_WHY", "M_WORK",
           "M_XBT", "M_XFT", "NEWTON_FAILED", "NEWTON_TOL", "NM", "NP", "OK", "PATH_LIMIT",
           "PLAN_HOLDS_TOL", "PULL", "PUSH", "P_AB0", "P_AF0", "P_BB", "P_BF", "P_BUDGET", "P_CD",
           "P_CREEP", "P_GF", "P_HOLD0", "P_K", "P_MARGIN", "P_NOISE", "P_PERIOD", "P_RM", "P_S",
           "P_UMAX", "P_WORK", "RTOL", "SPENT", "STATUS_NAMES", "STROKE_MARGIN", "TIGHTEN", "WORK",
           "foot_acc", "force_coefficients", "ground_force_noise", "new_memory", "robot_numbers",
           "workspace"]
