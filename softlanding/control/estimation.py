"""Ground estimation from what a landing robot measures: recursive least squares.

While the foot yields, the ground force follows from the foot's equation of motion
(:func:`softlanding.model.dynamics.robot_rhs`, affine in the ground force): from the foot's
measured acceleration and the robot's own force, ``f_g = (a_f - alpha - beta u) / gamma``.
The force is linear in the unknowns of ``f = K d + c_d v_f^2``: ``f = theta . phi`` with
``phi = (d, v_f^2)``, ``theta = (K, c_d)``, which recursive least squares fits sample by
sample, with the covariance of the estimate (its uncertainty given the measurement noise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from softlanding.errors import ParameterError, check
from softlanding.model.dynamics import VF, robot_rhs
from softlanding.model.ground import DragGround, Ground, LinearGround
from softlanding.model.robot import Robot


@dataclass(frozen=True)
class GroundEstimate:
    """The current fit.

    Attributes
    ----------
    stiffness, c_d : float
        ``K`` and the drag number (``c_d`` is 0 when the drag is not fitted).
    stiffness_std, c_d_std : float
        Their standard deviations (from the covariance and the noise level).
    samples : int
        Measurements used.
    """

    stiffness: float
    c_d: float
    stiffness_std: float
    c_d_std: float
    samples: int

    def ground(self) -> Ground:
        """The ground model of the estimate (drag clipped at 0, stiffness at 1e-3)."""
        k = max(self.stiffness, 1e-3)
        return DragGround(self.c_d, k) if self.c_d > 0 else LinearGround(k)


class GroundEstimator:
    """Recursive least squares for ``f = K d + c_d v_f^2`` from the foot's equation.

    Parameters
    ----------
    robot : Robot
        The robot (its mass ratio relates acceleration and force).
    drag : bool
        Fit the drag number too (else ``f = K d``).
    prior : (float, float)
        Prior ``(K, c_d)`` (the paper's ground by default).
    prior_std : (float, float)
        Prior standard deviations (how little the prior is trusted).
    noise_std : float
        Standard deviation of the ground force inferred from one measurement.
    """

    def __init__(self, robot: Robot, *, drag: bool = True, prior: tuple[float, float] = (1.0, 0.0),
                 prior_std: tuple[float, float] = (1.0, 1.0), noise_std: float = 1e-6) -> None:
        self.drag = bool(drag)
        n = 2 if self.drag else 1
        self.theta = np.array(prior[:n], float)
        std = np.array([check("prior_std", v, (lambda x: x > 0, "must be > 0"))
                        for v in prior_std[:n]])
        self.noise = check("noise_std", noise_std, (lambda x: x > 0, "must be > 0"))
        self.P = np.diag((std / self.noise) ** 2)  # covariance in units of the noise variance
        self.samples = 0
        # the foot's acceleration is affine in (u, f_g), with coefficients from robot_rhs
        x = np.zeros(4)
        a0 = float(robot_rhs(x, 0.0, 0.0, robot.r_m)[VF])
        self._alpha = a0
        self._beta = float(robot_rhs(x, 1.0, 0.0, robot.r_m)[VF]) - a0
        self._gamma = float(robot_rhs(x, 0.0, 1.0, robot.r_m)[VF]) - a0

    def ground_force(self, a_f: float, u: float) -> float:
        """The ground force the foot's acceleration and the robot's force imply.

        Parameters
        ----------
        a_f : float
            Measured foot acceleration.
        u : float
            The actuator force applied.
        """
        return (a_f - self._alpha - self._beta * u) / self._gamma

    def update(self, x: np.ndarray, a_f: float, u: float, weight: float = 1.0
               ) -> GroundEstimate:
        """One measurement of a yielding foot (``v_f < 0``; other modes carry no law).

        Parameters
        ----------
        x : array of 4
            Measured state ``[x_b, v_b, x_f, v_f]``.
        a_f : float
            Measured foot acceleration.
        u : float
            The actuator force.
        weight : float
            The measurement's weight (its force's variance is the estimator's noise's over
            ``weight``; :func:`filtered_weight`).

        Raises
        ------
        ParameterError
            The foot is not yielding (``v_f >= 0``).
        """
        if not x[3] < 0:
            raise ParameterError("x", "ground estimation needs a yielding foot (v_f < 0)")
        phi = np.array([-x[2], x[3] ** 2][: len(self.theta)])
        y = self.ground_force(a_f, u)
        Pphi = self.P @ phi
        k = Pphi / (1.0 / weight + phi @ Pphi)
        self.theta = self.theta + k * (y - phi @ self.theta)
        self.P = self.P - np.outer(k, Pphi)
        self.samples += 1
        return self.estimate

    @property
    def estimate(self) -> GroundEstimate:
        """The current fit and its uncertainty."""
        std = np.sqrt(np.maximum(np.diag(self.P), 0.0)) * self.noise
        c_d, c_std = (self.theta[1], std[1]) if self.drag else (0.0, 0.0)
        return GroundEstimate(float(self.theta[0]), float(c_d), float(std[0]), float(c_std),
                              self.samples)


@njit(cache=True, fastmath=False)  # (in the compiled filtered sample, and from Python)
def filtered_weight(x: np.ndarray, force: float, theta: tuple[float, float],
                    cov: tuple[float, float, float], force_var: float, allowance: float
                    ) -> float:
    """The weight of one sample of the filtered regression: the estimator's noise variance
    over this sample's (at most 1).

    The filtered foot state (:mod:`softlanding.control.foot_filter`) puts its own error into
    the sample's force through the regressors: ``-K dx_f + 2 c_d v_f dv_f``, of variance
    ``K^2 P_xx - 4 K c_d v_f P_xv + 4 c_d^2 v_f^2 P_vv`` (the filter's covariance), which
    the estimator's constant noise allows for only as ``allowance^2``: at a fast impact on
    draggy ground (``v_f`` large, the filter recovering from the impact's transient) far
    more, and the first samples' errors bias the fit. ``K`` and ``c_d`` are the estimate's
    (clipped at 0), no more than the sample's force alone allows (each term of
    ``K d + c_d v_f^2`` is at most the force). Measured (2026-11-26, margin 2, 9 trial cases): the
    estimate plus 1 of its standard deviations instead lands deeper on the 5 it changes,
    plus 3 deeper on 3 and a creep's rest not proven.

    Parameters
    ----------
    x : array of 4
        The filtered state (``v_f < 0``).
    force : float
        The sample's ground force (from the foot's acceleration and the force applied).
    theta : (float, float)
        The estimate ``(K, c_d)`` before this sample.
    cov : (float, float, float)
        The filter's covariance ``P_xx, P_xv, P_vv``, in units of the sensor's noise
        variance.
    force_var : float
        The variance of one force from the acceleration's noise alone, in the same units
        (``1 / gamma^2``).
    allowance : float
        The filtered state's error the estimator's noise allows for, in units of the
        sensor's noise (:data:`~softlanding.control.bangbang.FILTERED_REGRESSOR`).
    """
    d, v = max(-float(x[2]), 0.0), float(x[3])
    f = max(float(force), 0.0)
    k = min(max(theta[0], 0.0), f / d if d > 0.0 else math.inf)
    c = min(max(theta[1], 0.0), f / (v * v) if v != 0.0 else math.inf)
    var = k * k * cov[0] - 4.0 * k * c * v * cov[1] + 4.0 * c * c * v * v * cov[2]
    if not var > allowance * allowance:  # (a NaN too: no weight)
        return 1.0
    return max((force_var + allowance * allowance) / (force_var + var), MIN_WEIGHT)


#: The least weight of a sample (a variance 1e6 times the estimator's noise).
MIN_WEIGHT = 1e-6


__all__ = ["GroundEstimate", "GroundEstimator", "filtered_weight"]
