"""What the exported C is compared with, from the Python modules: the plan's force (the
Python schedule, not the C's formula), its integrals over a sample, the ground estimate
(:class:`~softlanding.control.estimation.GroundEstimator`'s), and the relative difference
of two results."""

from __future__ import annotations

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.estimation import GroundEstimator
from softlanding.model.controllers import ForceSchedule
from softlanding.optimal.landing import arrest_schedule


def plan_schedule(P: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plan in ``M`` as a piecewise-constant force from the step, from the Python
    schedule (push, pull, then :func:`~softlanding.optimal.landing.arrest_schedule`, its
    force saturated at the limit; while creeping or braking, the creep law's or the brake's
    force ``M[M_UCREEP]`` held, as ``mpc_landing``'s):
    ``values[i]`` until ``times[i]``, the last value after.

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    """
    if M[bb.M_PHASE] in (bb.CREEPING, bb.BRAKING):
        return np.array([]), np.array([float(M[bb.M_UCREEP])])
    t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
    t2 = t1 + float(M[bb.M_TAU2])
    u_max = float(P[bb.P_UMAX])
    tail = arrest_schedule(np.array([M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT], 0.0]),
                           float(P[bb.P_RM]))
    assert isinstance(tail, ForceSchedule)  # (a constant arrest force, then the weight)
    times = np.array([t1, t2, *(t2 + np.array(tail.times))])
    arrest = [min(u_max, max(-u_max, v)) for v in tail.values]  # (saturated, as applied)
    return times, np.array([u_max, -u_max, *arrest])


def plan_forces(P: np.ndarray, M: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The force of the plan in ``M`` at ``times`` after the step (:func:`plan_schedule`).

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    times : array
        Times after the step.
    """
    ends, values = plan_schedule(P, M)
    return values[np.searchsorted(ends, times, side="right")]


def plan_force_integrals(P: np.ndarray, M: np.ndarray, h: float) -> np.ndarray:
    """``int_0^h u dt`` and ``int_0^h (h - t) u dt`` of the plan's force
    (:func:`plan_schedule`), piece by piece.

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    h : float
        The sample.
    """
    ends, values = plan_schedule(P, M)
    U = np.zeros(2)
    a = 0.0
    for b, u in zip((*ends, np.inf), values, strict=True):
        lo, hi = max(a, 0.0), min(b, h)
        if hi > lo:
            U += u * (hi - lo) * np.array([1.0, h - 0.5 * (lo + hi)])
        a = max(a, b)
    return U


def ground_estimate(P: np.ndarray, M: np.ndarray, est: GroundEstimator) -> np.ndarray:
    """``[K, c_d, std K, std c_d]`` of the compiled controller's estimate in ``M``, given
    to the Python estimator ``est`` (as ``mpc_landing`` hands it over) and read from its
    :attr:`~softlanding.control.estimation.GroundEstimator.estimate`.

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    est : GroundEstimator
        Any, with drag (its fit and covariance replaced).
    """
    est.theta = np.array([M[bb.M_TH0], M[bb.M_TH1]])
    est.P = np.array([[M[bb.M_P00], M[bb.M_P01]], [M[bb.M_P01], M[bb.M_P11]]])
    est.noise = float(P[bb.P_NOISE])
    e = est.estimate
    return np.array([e.stiffness, e.c_d, e.stiffness_std, e.c_d_std])


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest ``|a - b| / max(|a|, |b|)`` (0 where both are 0; inf where one is not finite
    and they differ).

    Parameters
    ----------
    a, b : array
        Same shape.
    """
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
    rel = np.where(same, 0.0, np.where(np.isfinite(rel), rel, np.inf))
    return float(rel.max(initial=0.0))


__all__ = ["ground_estimate", "plan_force_integrals", "plan_forces", "plan_schedule",
           "relative_difference"]
