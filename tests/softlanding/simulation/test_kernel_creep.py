"""Proven endless creep (no stiffness, k_p = 0): the foot approaches a limit depth forever.

Checked against the closed form (the limit depth is the weight over the ground
stiffness, 1 in these units) and against scipy solve_ivp written from the
paper's equations.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from softlanding import Impact, Impedance, Robot, simulate
from softlanding.model.controllers import impedance_gains as impedance_gain_vector
from softlanding.model.dynamics import mode_matrices
from softlanding.simulation import kernel as K


def run(kp, kd, v0, r_m=5.0, s=20.0, umax=math.inf, t_max=1e4, max_seg=500):
    Kf = np.empty((3, 5))
    Kf[:] = impedance_gain_vector(kp, kd, s / 2)
    x0 = np.array([s / 2, v0, 0.0, v0])
    return K.run_landing(mode_matrices(r_m), Kf, umax, np.zeros(0), np.zeros(0), x0, s, t_max,
                         max_seg, False)


@pytest.mark.parametrize("kd,v0,r_m", [(0.28, -0.5, 5.0), (0.07, -1.0, 5.0), (0.5, -0.3, 12.0),
                                       (0.12, -1.5, 5.0), (0.1, -1.0, 12.0)])
def test_creep_is_proven_with_the_closed_form_limit(kd, v0, r_m):
    out, seg = run(0.0, kd, v0, r_m=r_m)
    assert out[K.O_STATUS] == K.NEVER_RESTS_CREEP
    # closed form: at the limit v_f = 0, the body's acceleration vanishes (u = r/(1+r)) and
    # the ground holds the foot's weight plus u: depth 1/(1+r) + r/(1+r) = 1
    assert out[K.O_DLIM] == pytest.approx(1.0, abs=1e-12)
    assert out[K.O_DEPTH] == out[K.O_DLIM]
    assert out[K.O_SMIN] == -math.inf  # the body falls through the foot at a terminal speed
    assert out[K.O_UMAX] == pytest.approx(r_m / (1 + r_m), abs=1e-12)
    assert out[K.O_FEAS] == 0.0
    assert math.isnan(out[K.O_ET])
    assert seg["t"][-1] < 1e3  # proven at once, not marched to the horizon


def _yielding_rhs(r_m, kd):
    """The paper's yielding mode with u = -k_d (v_b - v_f), on (v_b, x_f, v_f) (x_b drops out)."""
    c = (1 + r_m) / r_m

    def rhs(_, y):
        vb, xf, vf = y
        u = -kd * (vb - vf)
        return [-1 + c * u, vf, -1 - (1 + r_m) * (xf + u)]
    return rhs


def test_creep_agrees_with_solve_ivp():
    kd, v0, r_m = 0.28, -0.5, 5.0
    out, seg = run(0.0, kd, v0, r_m=r_m)
    assert out[K.O_STATUS] == K.NEVER_RESTS_CREEP and out[K.O_NSEG] == 1
    stop = lambda t, y: y[2]  # noqa: E731
    stop.direction = 1
    sol = solve_ivp(_yielding_rhs(r_m, kd), (0, 60), [v0, 0.0, v0], method="DOP853",
                    rtol=1e-12, atol=1e-16, events=stop, dense_output=True)
    assert sol.t_events[0].size == 0  # the foot does not stop on [0, 60] (v_f ~ -5e-11 there)
    t = np.linspace(0.5, 60, 20000)
    y = sol.sol(t)
    assert (y[2] < 0).all() and (np.diff(y[1]) < 0).all()
    assert -y[1, -1] == pytest.approx(out[K.O_DLIM], abs=1e-9)
    assert y[0, -1] == pytest.approx(-1 / ((1 + r_m) / r_m * kd), rel=1e-9)


def test_real_rests_without_stiffness_are_untouched():
    # overshoot: the foot stops below depth 1 and stays (support force tends to 1 < d)
    for kd, v0 in [(0.3, -4.0), (0.6, -10.0), (0.05, -2.0)]:
        out, _ = run(0.0, kd, v0)
        # the foot rests; without a spring the body then falls through it
        assert out[K.O_STATUS] == K.BODY_THROUGH_FOOT and out[K.O_FOOT_REST] == 1.0
        assert out[K.O_DEPTH] > 1.0 + 1e-6
        assert out[K.O_DLIM] == out[K.O_DEPTH]


def test_creep_with_saturation_that_never_binds():
    out, _ = run(0.0, 0.28, -0.5, umax=5.0)
    assert out[K.O_STATUS] == K.NEVER_RESTS_CREEP
    # a force limit below the force the creep needs (r/(1+r)) saturates: no creep proof
    out, _ = run(0.0, 0.28, -0.5, umax=0.5, t_max=300.0)
    assert out[K.O_STATUS] != K.NEVER_RESTS_CREEP


def test_simulate_reports_the_creep_by_name():
    r = simulate(Robot(5, 20), Impact(-1.0), Impedance(0.0, 0.07), t_max=200.0)
    assert not r.rest_proven
    assert r.status == K.STATUS_NAMES[K.NEVER_RESTS_CREEP]
    assert "creeps" in r.status and not r.feasible
