"""Exact hybrid simulator: analytic cases, the paper's figures, energy, a second method."""

import math

import numpy as np
import pytest
import scipy.linalg

from softlanding import (
    ForceSchedule,
    Impact,
    Impedance,
    ParameterError,
    Rigid,
    Robot,
    paper_rig,
    simulate,
    simulate_batch,
)
from softlanding.simulation.simulator import stroke
from tests.oracles.ivp_reference import landing_depth_ivp

R = Robot(r_m=5, s=20)  # the paper's robot without force limit


def robot(u_max=None, r_m=5.0):
    return Robot(r_m=r_m, s=20, u_max=None if u_max is None or math.isinf(u_max) else u_max)


@pytest.mark.parametrize("v0", [0.0, -0.3, -1.0, -3.0, -7.5, -10.0])
def test_rigid_leg_depth_and_stop_time_are_analytic(v0):
    r = simulate(R, Impact(v0), Rigid())
    assert r.rest_proven and r.steps == 1 and r.feasible
    assert r.depth == pytest.approx(1 + math.sqrt(1 + v0 * v0), abs=1e-10)
    # x = -1 + cos t + v0 sin t stops when tan t = v0, t in (pi/2, pi]
    assert r.t_first_stop == pytest.approx(math.pi + math.atan(v0), abs=1e-12)
    assert r.stroke_min == pytest.approx(10.0, abs=1e-12)
    assert r.stroke_max == pytest.approx(10.0, abs=1e-12)


@pytest.mark.parametrize("kd,steps", [(0.4, 1), (0.18, 2), (0.0, 3)])
def test_paper_stepped_intrusions(kd, steps):
    r = simulate(R, Impact(-1.0), Impedance(0.2, kd))
    assert r.rest_proven
    assert r.steps == steps


CASES = [(0.2, 0.4, -1.0, None), (0.5, 0.5, -10.0, None), (0.2, 0.0, -1.0, None),
         (0.8, 0.1, -4.0, 3.0), (0.3, 0.9, -7.0, 2.0), (0.05, 0.05, -0.5, None)]


@pytest.mark.parametrize("kp,kd,v0,umax", CASES)
def test_energy_ledger_closes(kp, kd, v0, umax):
    r = simulate(robot(umax), Impact(v0), Impedance(kp, kd))
    e = r.energy
    assert r.rest_proven
    assert e.ground == pytest.approx(0.5 * r.depth**2, rel=1e-15)
    scale = max(abs(e.E0), abs(e.ET), e.ground, abs(e.actuator))
    assert abs(e.residual) <= 1e-9 * scale


def test_energy_ledger_rigid_leg_has_no_actuator_loss():
    r = simulate(R, Impact(-3.0), Rigid())
    # the lock force does no work (no relative motion): all energy goes into the ground
    assert abs(r.energy.actuator) < 1e-12
    assert r.energy.E0 - r.energy.ET == pytest.approx(r.energy.ground, rel=1e-12)


def test_same_landing_in_si_and_dimensionless_units():
    ph = paper_rig(v0=-0.9, K_p=0.3 * 4400.0, K_d=0.25 * math.sqrt(3.0 * 4400.0))
    d = ph.to_dimensionless()
    r_si = simulate(*d)
    r_nd = simulate(R, Impact(d.impact.v0), Impedance(0.3, 0.25))
    assert r_si.depth == pytest.approx(r_nd.depth, rel=1e-12)
    assert r_si.steps == r_nd.steps


def _sample_cases(n=14, seed=7):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        kp, kd = rng.uniform(0.03, 1.0, 2)
        v0 = rng.uniform(-10, 0)
        umax = math.inf if i % 3 else rng.uniform(1.5, 8.0)
        out.append((kp, kd, v0, umax))
    return out + [(0.2, 0.18, -1.0, math.inf), (0.2, 0.0, -1.0, math.inf)]


@pytest.mark.parametrize("kp,kd,v0,umax", _sample_cases())
def test_agrees_with_solve_ivp(kp, kd, v0, umax):
    r = simulate(robot(umax), Impact(v0), Impedance(kp, kd), energy=False)
    ref = landing_depth_ivp(v0, kp, kd, umax=umax)
    assert r.rest_proven
    assert r.steps == ref["steps"]
    assert r.depth == pytest.approx(ref["depth"], abs=1e-7)
    assert r.t_first_stop == pytest.approx(ref["t_first_stop"], abs=1e-7)


@pytest.mark.parametrize("kp,kd,v0,umax", CASES)
def test_stroke_and_force_extrema_bound_dense_samples(kp, kd, v0, umax):
    r = simulate(robot(umax), Impact(v0), Impedance(kp, kd))
    # two body periods past the final foot stop: the tail's extremes count too
    tr = r.trajectory(t_end=r.T + 30.0, n=6000)
    st = stroke(tr)
    # exact extrema enclose every sample and are attained (to sampling resolution)
    assert r.stroke_min <= st.min() + 1e-12 and r.stroke_max >= st.max() - 1e-12
    assert np.abs(tr.u).max() <= r.u_peak + 1e-12
    if umax is not None:
        assert r.u_peak <= umax + 1e-12
    assert st.min() - r.stroke_min < 1e-3
    assert r.stroke_max - st.max() < 1e-3


def test_open_loop_zero_force_is_a_lone_foot_and_a_falling_body():
    r_m, v0 = 5.0, -2.0
    r = simulate(robot(r_m=r_m), Impact(v0), ForceSchedule((), (0.0,)))
    mf = 1 / (1 + r_m)
    assert r.depth == pytest.approx(mf + math.sqrt(mf**2 + v0**2 * mf), abs=1e-12)
    assert not r.rest_proven  # the foot rests, the body does not: it falls through the foot
    assert "passes through" in r.status
    assert r.stroke_min == -math.inf
    assert not r.feasible


def test_open_loop_switch_matches_matrix_exponential_composition():
    r_m, v0, t1, u1, u2 = 5.0, -3.0, 0.4, 2.0, -1.5
    r = simulate(robot(r_m=r_m), Impact(v0), ForceSchedule((t1,), (u1, u2)))
    # yielding foot written out independently: x'' = -1 - (1+r)(x + u)
    w2 = 1 + r_m

    def seg(u):
        return np.array([[0, 1, 0], [-w2, 0, -1 - w2 * u], [0, 0, 0]])

    y1 = scipy.linalg.expm(seg(u1) * t1) @ np.array([0.0, v0, 1.0])
    assert y1[1] < 0  # still yielding at the switch
    xe = (-1 - w2 * u2) / w2
    amp = math.hypot(y1[0] - xe, y1[1] / math.sqrt(w2))
    assert r.depth == pytest.approx(-(xe - amp), abs=1e-12)


def test_rest_not_proven_is_reported():
    # no damping, hops toward a symmetric (periodic) hop: rest is not proven within the
    # horizon (hops shrinking toward the threshold stop early: test_kernel_hops)
    r = simulate(R, Impact(-6.0), Impedance(0.26, 0.0), t_max=50.0)
    assert not r.rest_proven
    assert "horizon" in r.status
    assert not r.feasible


def test_batch_matches_single_runs():
    kp = np.array([0.2, 0.2, 0.5, 0.9, 0.05])
    kd = np.array([0.4, 0.0, 0.5, 0.1, 0.3])
    v0 = np.array([-1.0, -1.0, -10.0, -3.0, -0.5])
    b = simulate_batch(R, v0, kp, kd, energy=True)
    for i in range(len(kp)):
        r = simulate(R, Impact(v0[i]), Impedance(kp[i], kd[i]))
        assert b.depth[i] == r.depth
        assert b.steps[i] == r.steps
        assert b.feasible[i] == r.feasible
        assert b.u_peak[i] == r.u_peak
        assert b.actuator[i] == pytest.approx(r.energy.actuator, rel=1e-12)


def test_batch_broadcasts_and_validates():
    b = simulate_batch(R, -2.0, np.linspace(0.1, 1, 4)[:, None], np.linspace(0.1, 1, 3)[None, :])
    assert b.depth.shape == (4, 3)
    with pytest.raises(ParameterError, match="k_d"):
        simulate_batch(R, -1.0, 0.2, [-0.1, 0.2])
    with pytest.raises(ParameterError, match="v0"):
        simulate_batch(R, [0.1], 0.2, 0.2)
    with pytest.raises(ParameterError, match="r_m"):
        simulate_batch(Robot(r_m=np.nan, s=20), -1.0, 0.2, 0.2)


@pytest.mark.parametrize("bad", [
    lambda: Impedance(-0.1, 0.2), lambda: Impedance(0.1, math.nan),
    lambda: Robot(r_m=5, s=20, u_max=0.0), lambda: ForceSchedule((1.0, 0.5), (0, 1, 2)),
    lambda: ForceSchedule((1.0,), (0.0,)),
])
def test_policy_bad_input(bad):
    with pytest.raises(ParameterError):
        bad()


@pytest.mark.parametrize("call,name", [
    (lambda: simulate(R, Impact(-1.0), Impedance(0.2, 0.1, l0=1e9)), "l0"),
    (lambda: simulate(R, Impact(-1.0), Impedance(0.2, 0.1), t_max=math.nan), "t_max"),
    (lambda: simulate(R, Impact(-1.0), Impedance(0.2, 0.1), max_segments=-5), "max_segments"),
    (lambda: simulate_batch(R, [-1.0, -2.0], [0.1, 0.2, 0.3], 0.1), "k_p"),
])
def test_api_misuse_names_the_argument(call, name):
    with pytest.raises(ParameterError, match=name):
        call()
