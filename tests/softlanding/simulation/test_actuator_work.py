"""The actuator's positive and negative work on one exact segment (closed form: Van Loan's
Gramian between the sign changes), against a second method: the power's sign changes found
on a fine grid of scipy's matrix exponential, and each piece integrated by adaptive
quadrature."""

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm
from scipy.optimize import brentq

from softlanding.model.dynamics import VB, VF, mode_matrices
from softlanding.simulation.actuator_work import segment_work


def _by_quadrature(A, z0, c, duration, grid=600):
    """``(positive, negative, sign changes)`` of ``int u (v_b - v_f) dt``, ``u = c . z``."""
    e = np.zeros(len(z0))
    e[VB], e[VF] = 1.0, -1.0
    M = 0.5 * (np.outer(c, e) + np.outer(e, c))  # P = z' M z

    def power(t):
        z = expm(A * t) @ z0
        return float(z @ M @ z)

    ts = np.linspace(0.0, duration, grid + 1)
    ps = [power(t) for t in ts]
    cuts = [0.0] + [brentq(power, a, b, xtol=1e-15, rtol=1e-15)
                    for a, b, pa, pb in zip(ts[:-1], ts[1:], ps[:-1], ps[1:], strict=True)
                    if pa * pb < 0] + [duration]
    pos = neg = 0.0
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        val = quad(power, a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        pos, neg = (pos + val, neg) if val >= 0 else (pos, neg - val)
    return pos, neg, len(cuts) - 2


@pytest.mark.parametrize("mode,kp,kd,duration", [(2, 3.0, 0.05, 12.0), (0, 3.0, 0.02, 6.0),
                                                 (1, 2.0, 0.0, 9.0)])
def test_segment_work_equals_adaptive_quadrature_between_sign_changes(mode, kp, kd, duration):
    # an impedance leg (u = -kp (S - 1) - kd S', S = x_b - x_f) oscillating: the power
    # changes sign many times within the segment, some near the probes' bracket ends
    mats = mode_matrices(5.0)
    c = np.array([-kp, -kd, kp, kd, kp])
    A = mats["A"][mode] + np.outer(mats["B"][mode], c)
    z0 = np.array([2.5, -1.2, 0.3, -0.4, 1.0])
    pos, neg, changes = _by_quadrature(A, z0, c, duration)
    assert changes >= 4  # the case is the one meant
    w = segment_work(A, z0, c, duration)
    assert w.positive == pytest.approx(pos, rel=1e-11, abs=1e-13)
    assert w.negative == pytest.approx(neg, rel=1e-11, abs=1e-13)


def test_a_long_decaying_segment_keeps_its_digits():
    # a stiff, heavily damped leg over a long segment: ||A|| T about 400, where one block
    # exponential of the whole segment would cancel e^(400) against e^(-400)
    mats = mode_matrices(5.0)
    kp, kd = 40.0, 12.0
    c = np.array([-kp, -kd, kp, kd, kp])
    A = mats["A"][1] + np.outer(mats["B"][1], c)
    z0 = np.array([2.5, -1.2, 0.3, 0.0, 1.0])
    pos, neg, _ = _by_quadrature(A, z0, c, 8.0)
    w = segment_work(A, z0, c, 8.0)
    assert w.positive == pytest.approx(pos, rel=1e-10, abs=1e-13)
    assert w.negative == pytest.approx(neg, rel=1e-10, abs=1e-13)
