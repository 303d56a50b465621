"""The foot's position and velocity filtered from noisy measurements (compiled).

The ground estimate regresses the ground force on the foot's depth and squared velocity
(:mod:`softlanding.control.estimation`). Measured with noise, those regressors put an
error of ``K sigma`` into every sample's force (the errors-in-variables the estimator's
noise model leaves out), more than the force's own noise once the robot's force is the
one it commanded. The foot's acceleration, measured every sample too, moves its
velocity and position by amounts far more accurate than one measurement of them
(``h sigma`` against ``sigma``): a Kalman filter of ``[x_f, v_f]`` driven by it
(its continuous part, ``a_f - beta u``, interpolated through the last three samples'
measurements, the robot's force integrated exactly over the sample) and corrected by
the measured position and velocity.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import ENTRY, JIT

# the filter's memory F: estimate, covariance (in units of the noise variance), the last
# two samples' continuous accelerations, samples done, the last sample's length, and the
# first sample's start and force integrals (re-integrated once its second value is known)
# (the first two samples' force integrals at F_U1, F_U2 and two on)
(F_X, F_V, F_P00, F_P01, F_P11, F_G1, F_G0, F_N, F_H, F_X0, F_V0, F_U1, F_U2,
 F_H0) = (*range(13), 15)
NF = 16

#: Samples whose filtered state is provisional (redone at the third, once a quadratic
#: through three accelerations covers the first sample).
PROVISIONAL = 2

#: Process noise of a sample (relative to the noise's ``h sigma`` on the velocity): the
#: interpolation's error, allowed for.
PROCESS = 0.5

#: The normalized innovation (chi-square, 2 degrees of freedom) beyond which the
#: prediction's covariance is widened: 13.8, a 1e-3 chance for a consistent filter.
INNOVATION = 13.8

#: The impact state's standard deviation (relative to the noise): the foot touches down at
#: ``x_f = 0`` with the impact velocity the controller planned for.
START_STD = 0.01


def new_filter(x0: np.ndarray) -> np.ndarray:
    """The filter's memory at the impact.

    Parameters
    ----------
    x0 : array of 4
        The impact state (the foot at the ground's surface, at the impact velocity).
    """
    F = np.zeros(NF)
    F[F_X] = F[F_X0] = x0[2]
    F[F_V] = F[F_V0] = x0[3]
    F[F_P00] = F[F_P11] = START_STD ** 2
    return F


@njit(**JIT)
def _quad_integrals(g1, g2, g3, a, h):
    """``int g`` and ``int (b - s) g`` over ``[a h, (a + 1) h]`` of the quadratic through
    ``g1, g2, g3`` at ``h, 2 h, 3 h`` (two Gauss points: exact)."""
    dv = 0.0
    dx = 0.0
    r = 0.5 / np.sqrt(3.0)
    for q in (0.5 - r, 0.5 + r):
        s = a + q
        g = (g1 * (s - 2.0) * (s - 3.0) / 2.0 - g2 * (s - 1.0) * (s - 3.0)
             + g3 * (s - 1.0) * (s - 2.0) / 2.0)
        dv += 0.5 * h * g
        dx += 0.5 * h * h * (1.0 - q) * g
    return dv, dx


@njit(**JIT)
def _redo(F, g3, h, beta):
    """The first two samples again from the impact state, on the quadratic through the
    first three samples' values: the state at the start of the third."""
    g1, g2 = F[F_G0], F[F_G1]
    x, v = F[F_X0], F[F_V0]
    for a in range(2):
        dv, dx = _quad_integrals(g1, g2, g3, float(a), h)
        u1, u2 = F[F_U1 + 2 * a], F[F_U2 + 2 * a]
        x = x + h * v + dx + beta * u2
        v = v + dv + beta * u1
    F[F_X], F[F_V] = x, v


@njit(**ENTRY)
def filter_step(F, x, g, U1, U2, h, beta, noise=0.0):
    """One sample of the filter, in place: predict with the sample's accelerations, correct
    with the measured ``x[2], x[3]``, and write the filtered position and velocity into
    ``x``.

    Parameters
    ----------
    F : array
        :func:`new_filter`.
    x : array of 4
        The measured state (its foot's entries replaced by the filter's).
    g : float
        The measured foot acceleration less ``beta u`` at the sample's end (the ground's
        and the weight's part, continuous in time).
    U1, U2 : float
        ``int_0^h u dt`` and ``int_0^h (h - t) u dt`` over the sample (the robot's force
        as applied).
    h : float
        The sample.
    beta : float
        The foot's acceleration per unit of the robot's force.
    noise : float
        The measurements' standard deviation (0: no innovation check).
    """
    n = F[F_N]
    same = abs(F[F_H] - h) <= 1e-12 * h
    if n == 0.0:  # no value at the impact: the sample's end value, for now
        dv, dx, cv, cx = h * g, 0.5 * h * h * g, 1.0, 0.25
        F[F_U1], F[F_U2], F[F_H0] = U1, U2, h
    elif n == 1.0:  # the chord, for now
        g1 = F[F_G1]
        dv, dx = 0.5 * h * (g1 + g), h * h * (2.0 * g1 + g) / 6.0
        cv, cx = 0.5, 5.0 / 36.0
        F[F_U1 + 2], F[F_U2 + 2] = U1, U2
        if not (same and abs(F[F_H0] - h) <= 1e-12 * h):
            F[F_H0] = -1.0  # (unequal samples: no redo)
    elif n == 2.0 and same and F[F_H0] > 0.0:
        # the first two samples again, from the impact, with the quadratic through the
        # three samples' values (the drag's curvature at the impact, v_f^2 growing fast
        # under the push, is far beyond a chord's accuracy); then this one on it
        _redo(F, g, h, beta)
        dv, dx = _quad_integrals(F[F_G0], F[F_G1], g, 2.0, h)
        cv, cx = 1.0, 0.25
    elif n >= 2.0 and same:  # a quadratic through the last three samples' values
        g0, g1 = F[F_G0], F[F_G1]
        dv = h * (-g0 + 8.0 * g1 + 5.0 * g) / 12.0
        dx = h * h * (-g0 + 10.0 * g1 + 3.0 * g) / 24.0
        cv, cx = (1.0 + 64.0 + 25.0) / 144.0, (1.0 + 100.0 + 9.0) / 576.0
    else:  # (a shorter sample: the chord)
        g1 = F[F_G1]
        dv = 0.5 * h * (g1 + g)
        dx = h * h * (2.0 * g1 + g) / 6.0
        cv, cx = 0.5, 5.0 / 36.0
    xp = F[F_X] + h * F[F_V] + dx + beta * U2
    vp = F[F_V] + dv + beta * U1
    p00, p01, p11 = F[F_P00], F[F_P01], F[F_P11]
    # P <- A P A' + Q, A = [[1, h], [0, 1]]; Q from the accelerations' noise (their
    # weights cx, cv, in units of the noise) and the interpolation's error
    q = (1.0 + PROCESS * PROCESS) * h * h
    a00 = p00 + 2.0 * h * p01 + h * h * p11 + cx * h * h * q
    a01 = p01 + h * p11 + np.sqrt(cx * cv) * h * q
    a11 = p11 + cv * q
    # correct with the measured position and velocity (unit variance each)
    ex, ev = x[2] - xp, x[3] - vp
    s00, s01, s11 = a00 + 1.0, a01, a11 + 1.0
    det = s00 * s11 - s01 * s01
    i00, i01, i11 = s11 / det, -s01 / det, s00 / det
    if noise > 0.0:
        # measurements far outside the prediction's spread (a transient no interpolation
        # of the samples follows, the drag's at a fast impact): the prediction's covariance
        # widened until they fit, so that the filter follows them
        ux, uv = ex / noise, ev / noise
        nis = ux * (i00 * ux + i01 * uv) + uv * (i01 * ux + i11 * uv)
        if nis > INNOVATION:
            f = nis / 2.0
            a00, a01, a11 = f * a00, f * a01, f * a11
            s00, s01, s11 = a00 + 1.0, a01, a11 + 1.0
            det = s00 * s11 - s01 * s01
            i00, i01, i11 = s11 / det, -s01 / det, s00 / det
    k00 = a00 * i00 + a01 * i01
    k01 = a00 * i01 + a01 * i11
    k10 = a01 * i00 + a11 * i01
    k11 = a01 * i01 + a11 * i11
    F[F_X] = xp + k00 * ex + k01 * ev
    F[F_V] = vp + k10 * ex + k11 * ev
    F[F_P00] = (1.0 - k00) * a00 - k01 * a01
    F[F_P01] = (1.0 - k00) * a01 - k01 * a11
    F[F_P11] = -k10 * a01 + (1.0 - k11) * a11
    F[F_G0], F[F_G1], F[F_N], F[F_H] = F[F_G1], g, n + 1.0, h
    x[2], x[3] = F[F_X], F[F_V]


@njit(**ENTRY)
def covariance(F: np.ndarray) -> tuple[float, float, float]:
    """The filtered state's covariance ``P_xx, P_xv, P_vv``, in units of the noise variance.

    Parameters
    ----------
    F : array
        :func:`new_filter`, after its steps.
    """
    return float(F[F_P00]), float(F[F_P01]), float(F[F_P11])


__all__ = ["NF", "PROCESS", "PROVISIONAL", "covariance", "filter_step", "new_filter"]
