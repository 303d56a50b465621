"""One sample of the compiled controller with the filtered estimate, as
``mpc_landing(..., controller="bangbang", estimator="filtered")`` runs it: the sample's
weight in the regression, the weighted step, and the bounded full solve that recovers a push
whose real-time iteration ran out of samples.

Pure functions of the controller's arrays (no state of their own: the count of samples the
recovery has gone on over is an argument and a result), so that the exported C
(``sl_filtered_weight``, ``sl_filtered_step`` of ``softlanding export-controller``) mirrors
them operation by operation and its check runs both from the same inputs. Compiled (numba,
no fast-math: the same operations as the C), and fused with the foot filter's step in
:func:`filtered_sample`, one call per sample: the filtered sample's Python around the
compiled step was 2/3 of its time (measured 2026-11-26: filter step 7, weight 10, weighted
step 21 us median in a landing, the step alone ~10 us).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.control import bangbang as bb
from softlanding.control.estimation import filtered_weight
from softlanding.control.fallback import fallback
from softlanding.control.foot_filter import covariance, filter_step
from softlanding.simulation.kernel.const import ENTRY, JIT

# (numba caches this module's entries with the step's and the fallback's code compiled in, and
# checks only this file for changes: the package's sources stamp drops them when bangbang.py or
# fallback.py changes, softlanding/control/__init__.py)

#: Most samples in a row the filtered estimate's bounded full solve may go on over (each
#: within the work bound) before the landing falls back.
RECOVERY_SAMPLES = 6


@njit(**ENTRY)
def sample_weight(P: np.ndarray, M: np.ndarray, F: np.ndarray, x: np.ndarray, a_f: float,
                  u: float) -> float:
    """The filtered regression's weight of a sample
    (:func:`~softlanding.control.estimation.filtered_weight`): the sample's ground force from
    the foot's acceleration under the applied force, the estimate in ``M`` before it, the
    foot filter's covariance, one force's variance from the acceleration's noise
    (``1 / P[P_GF]^2``) and the allowance
    :data:`~softlanding.control.bangbang.FILTERED_REGRESSOR`.

    Parameters
    ----------
    P, M : array
        The controller's numbers and memory (before the step).
    F : array
        The foot filter's memory after this sample's filter step.
    x : array of 4
        The filtered state (``v_f < 0``).
    a_f : float
        The foot's measured acceleration.
    u : float
        The force the sample ended under (as applied).
    """
    force = (a_f - P[bb.P_AF0] - P[bb.P_BF] * u) / P[bb.P_GF]
    return filtered_weight(x, force, (M[bb.M_TH0], M[bb.M_TH1]), covariance(F),
                           1.0 / P[bb.P_GF] ** 2, bb.FILTERED_REGRESSOR)


@njit(**ENTRY)
def filtered_step(P: np.ndarray, M: np.ndarray, x: np.ndarray, a_f: float, u: float,
                  h: float, estimate: bool, weight: float, recovering: int, K: np.ndarray,
                  W: np.ndarray) -> tuple[int, int]:
    """One sample of the compiled controller with the filtered estimate; the status and the
    new count of samples the recovery has gone on over.

    The estimate's update weighs the sample by ``weight`` (at most 1: :func:`sample_weight`):
    a weighted update is the plain one on the covariance times the weight (the gain is the
    same, the covariance comes out times it), so the covariance ``M[M_P00..M_P11]`` is
    scaled by it around :func:`~softlanding.control.bangbang.control_step`, and the noise
    ``P[P_NOISE]`` by ``1 / sqrt(weight)`` meanwhile (the margin's standard deviations).

    Then the recovery: a push whose real-time iteration ran out of samples (its Newton steps
    above a tenth of the period for :data:`~softlanding.control.bangbang.MAX_UNCONVERGED`
    samples in a row: the plan's ground, the estimate less ``margin`` standard deviations,
    moves every sample as they shrink) is solved to convergence from ``x``
    (:func:`~softlanding.control.bangbang.solve_plan` on a copy of ``M``) and kept if it
    covers the state (:data:`~softlanding.control.bangbang.OK`, ``M_UNCONVERGED`` reset),
    before a fallback. The solve is bounded by ``P[P_WORK]`` integrator steps of its own
    (counted in ``M[M_WORK]``, which may then reach twice the bound); one that runs out
    keeps the plan (the push goes on: :data:`~softlanding.control.bangbang.DEFERRED`,
    counted in ``M_DEFERRED``) and goes on from its iterate at the next sample, for at most
    :data:`RECOVERY_SAMPLES` samples in a row. A state still not covered gets the compiled
    fallback (:func:`~softlanding.control.fallback.fallback`).

    Parameters
    ----------
    P, M : array
        The controller's numbers and memory, updated in place.
    x : array of 4
        The filtered state.
    a_f, u, h : float
        The foot's measured acceleration, the force the sample ended under, its length.
    estimate : bool
        Update the estimate (no fit from the filter's provisional samples).
    weight : float
        The sample's weight in the estimate (1: the plain step).
    recovering : int
        Samples the recovery has gone on over so far (0 at impact).
    K, W : array
        :func:`~softlanding.control.bangbang.workspace`.
    """
    st, recovering = _recovered(P, M, x, a_f, u, h, estimate, weight, recovering, K, W)
    return fallback(P, M, x, st), recovering


@njit(**JIT)
def _recovered(P, M, x, a_f, u, h, estimate, weight, recovering, K, W):
    """:func:`filtered_step` before its fallback: the weighted step and the recovery."""
    if weight == 1.0 or not estimate:
        st = int(bb.structure_step(P, M, x, a_f, u, h, estimate, K, W))
    else:
        noise = P[bb.P_NOISE]
        M[bb.M_P00] *= weight
        M[bb.M_P01] *= weight
        M[bb.M_P11] *= weight
        P[bb.P_NOISE] = noise / np.sqrt(weight)
        st = int(bb.structure_step(P, M, x, a_f, u, h, estimate, K, W))
        P[bb.P_NOISE] = noise
        M[bb.M_P00] /= weight
        M[bb.M_P01] /= weight
        M[bb.M_P11] /= weight
    if not (st == bb.NEWTON_FAILED and M[bb.M_PHASE] == bb.PUSH
            and M[bb.M_UNCONVERGED] > bb.MAX_UNCONVERGED):
        return st, recovering
    trial = M.copy()
    # bounded as a sample's own work (P_WORK more integrator steps, counted in M_WORK: such
    # a sample may take twice the bound)
    solved = int(bb.solve_plan(P, trial, x.copy(), K, W, P[bb.P_WORK]))
    M[bb.M_WORK] = trial[bb.M_WORK]
    if solved == bb.DEFERRED and recovering < RECOVERY_SAMPLES:
        # the bound ran out: the sample keeps its plan (the push goes on), and the next one
        # goes on from this iterate, from its own state
        M[bb.M_TAU1], M[bb.M_TAU2] = trial[bb.M_TAU1], trial[bb.M_TAU2]
        M[bb.M_DEFERRED] += 1
        return bb.DEFERRED, recovering + 1
    if solved != bb.OK:
        return st, 0
    trial[bb.M_UNCONVERGED] = 0
    for i in range(M.shape[0]):  # (not ``M[:] = trial``: its shape check's error message
        M[i] = trial[i]          # compiled numba's string formatting, ~4 s of a cold start)
    return bb.OK, 0


@njit(**ENTRY)
def filtered_sample(P: np.ndarray, M: np.ndarray, F: np.ndarray, x: np.ndarray, g: float,
                    U1: float, U2: float, h: float, beta: float, noise: float, a_f: float,
                    u: float, estimate: bool, stop: float, recovering: int, K: np.ndarray,
                    W: np.ndarray) -> tuple[int, int]:
    """A whole sample of the compiled controller with the filtered estimate, in one call:
    the foot filter's step (:func:`~softlanding.control.foot_filter.filter_step`: ``x``'s
    foot entries become the filtered ones), the filtered ``v_f`` clipped at ``-stop`` (the
    foot still yields: the plans start from a yielding foot), the sample's weight
    (:func:`sample_weight`, 1 without a fit) and :func:`filtered_step`; the status and the
    new count of samples the recovery has gone on over.

    Parameters
    ----------
    P, M, F : array
        The controller's numbers and memory, the foot filter's memory, updated in place.
    x : array of 4
        The measured state, filtered in place.
    g, U1, U2, h, beta, noise : float
        :func:`~softlanding.control.foot_filter.filter_step`'s.
    a_f, u : float
        The foot's measured acceleration, the force the sample ended under (as applied).
    estimate : bool
        Update the estimate (no fit from the filter's provisional samples).
    stop : float
        The speed below which the foot counts as stopped.
    recovering : int
        Samples the recovery has gone on over so far (0 at impact).
    K, W : array
        :func:`~softlanding.control.bangbang.workspace`.
    """
    filter_step(F, x, g, U1, U2, h, beta, noise)
    x[3] = min(x[3], -stop)
    weight = sample_weight(P, M, F, x, a_f, u) if estimate else 1.0
    return filtered_step(P, M, x, a_f, u, h, estimate, weight, recovering, K, W)


__all__ = ["RECOVERY_SAMPLES", "filtered_sample", "filtered_step", "sample_weight"]
