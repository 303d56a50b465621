"""Bounded work for any input, and statuses that say what was (not) proven.

Inputs that used to run for minutes with no output now return at once with a
status; a foot that rests under a body that falls through it is not a rest.
"""

import math
import time

import numpy as np
import pytest

from softlanding import ForceSchedule, Impact, Impedance, Robot, simulate
from softlanding.model.controllers import impedance_gains as impedance_gain_vector
from softlanding.model.dynamics import mode_matrices
from softlanding.simulation import kernel as K


def run(kp, kd, v0, r_m=5.0, s=20.0, l0=None, max_steps=K.DEFAULT_MAX_STEPS):
    l0 = s / 2 if l0 is None else l0
    Kf = np.empty((3, 5))
    Kf[:] = impedance_gain_vector(kp, kd, l0)
    x0 = np.array([l0, v0, 0.0, v0])
    c = time.process_time()
    out, seg = K.run_landing(mode_matrices(r_m), Kf, math.inf, np.zeros(0), np.zeros(0), x0, s,
                             1e4, 500, True, max_steps=max_steps)
    return out, seg, time.process_time() - c


@pytest.mark.parametrize("args,status", [
    (dict(kp=1e7, kd=0.2, v0=-1.0), K.STEP_BUDGET),
    (dict(kp=0.2, kd=0.2, v0=-1.0, r_m=1e300), K.STEP_BUDGET),
    (dict(kp=0.2, kd=0.2, v0=-1.0, r_m=1e-300), K.STEP_BUDGET),
    (dict(kp=0.2, kd=0.2, v0=-1.0, s=1e300), K.OUT_OF_RANGE),
    (dict(kp=0.2, kd=0.2, v0=-1.0, l0=1e9), K.OUT_OF_RANGE),
    (dict(kp=0.2, kd=0.2, v0=-1e6), K.HORIZON),
])
def test_hostile_inputs_return_at_once_with_a_status(args, status):
    run(0.2, 0.2, -1.0)  # compiled and loaded before the clock starts
    out, _, cpu = run(**args)
    assert cpu < 1.0
    assert out[K.O_STATUS] == status
    assert out[K.O_FEAS] == 0.0 and out[K.O_FOOT_REST] == 0.0
    assert int(out[K.O_STATUS]) in K.STATUS_NAMES


def test_budget_ends_a_landing_and_does_not_touch_normal_ones():
    full, seg_full, _ = run(0.2, 0.18, -1.0)
    assert full[K.O_STATUS] == K.REST_PROVEN
    small, _, _ = run(0.2, 0.18, -1.0, max_steps=5)
    assert small[K.O_STATUS] == K.STEP_BUDGET and small[K.O_FOOT_REST] == 0.0
    again, seg_again, _ = run(0.2, 0.18, -1.0, max_steps=10 ** 7)
    assert ((again == full) | (np.isnan(again) & np.isnan(full))).all()
    assert (seg_again["t"] == seg_full["t"]).all()


@pytest.mark.parametrize("v0", [-1.0, -3.0, 0.0])
def test_no_actuator_force_is_a_falling_body_not_a_rest(v0):
    r_m = 5.0
    out, _, _ = run(0.0, 0.0, v0, r_m=r_m)
    assert out[K.O_STATUS] == K.BODY_THROUGH_FOOT
    assert out[K.O_FOOT_REST] == 1.0 and out[K.O_FEAS] == 0.0
    assert out[K.O_SMIN] == -math.inf
    # the foot alone on the ground: m x'' = -m - x, m = 1/(1+r), from x = 0, x' = v0
    mf = 1 / (1 + r_m)
    assert out[K.O_DEPTH] == pytest.approx(mf + math.sqrt(mf ** 2 + v0 ** 2 * mf), abs=1e-12)
    assert out[K.O_DLIM] == out[K.O_DEPTH]


def test_simulate_names_the_falling_body():
    r = simulate(Robot(5, 20), Impact(-1.0), Impedance(0.0, 0.0))
    assert not r.rest_proven and not r.feasible
    assert "passes through" in r.status
    assert r.depth == pytest.approx(0.6076252185107651, abs=1e-12)


def test_constant_push_lifts_the_body_off_a_resting_foot():
    r = simulate(Robot(5, 20), Impact(-1.0), ForceSchedule((), (3.0,)))
    assert r.status == K.STATUS_NAMES[K.BODY_FLIES_OFF]
    assert r.stroke_max == math.inf and not r.feasible


def test_batch_reports_the_new_statuses():
    from softlanding import simulate_batch

    b = simulate_batch(Robot(5, 20), [-1.0, -0.5, -5.0, -2.0, -6.0], [0.0, 0.0, 0.5, 0.3, 0.26],
                       [0.0, 0.28, 0.0, 0.4, 0.0])
    assert list(b.status) == [K.BODY_THROUGH_FOOT, K.NEVER_RESTS_CREEP, K.HOPS_TO_LIMIT,
                              K.REST_PROVEN, K.TOO_MANY_SEGMENTS]
