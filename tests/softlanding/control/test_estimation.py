"""Recursive least squares recovers the ground law from simulated measurements."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT
from softlanding.control import GroundEstimator, SteppingPlant
from softlanding.control.estimation import filtered_weight
from softlanding.errors import ParameterError
from softlanding.model.controllers import ForceSchedule
from softlanding.model.ground import DragGround, LinearGround


@pytest.mark.parametrize("ground", [LinearGround(0.5), LinearGround(2.0), DragGround(0.2),
                                    DragGround(1.0, 1.5)])
def test_estimate_from_a_simulated_landing(ground):
    plant = SteppingPlant(PAPER_ROBOT, -6, ground)
    est = GroundEstimator(PAPER_ROBOT)
    u = 2.0
    while plant.x[3] < -1e-3 and est.samples < 30:
        plant.step(ForceSchedule((), (u,)), 0.01)
        if plant.x[3] < 0:
            e = est.update(plant.x, plant.foot_acceleration(u), u)
    d = ground.to_dict()
    assert e.stiffness == pytest.approx(d.get("stiffness", 1.0), rel=1e-6)
    assert e.c_d == pytest.approx(d.get("c_d", 0.0), abs=1e-6)
    assert e.ground().yield_force(2.0, -1.0) == pytest.approx(ground.yield_force(2.0, -1.0))


def test_noisy_measurements_give_an_honest_uncertainty():
    rng = np.random.default_rng(1)
    truth = DragGround(0.3, 1.2)
    est = GroundEstimator(PAPER_ROBOT, noise_std=0.05)
    for _ in range(400):
        d, v, u = rng.uniform(0.5, 4), -rng.uniform(0.1, 3), rng.uniform(-8, 8)
        f = truth.yield_force(d, v) + rng.normal(0, 0.05)
        a = est._alpha + est._beta * u + est._gamma * f  # noqa: SLF001 - the foot's equation
        e = est.update(np.array([5.0, -1.0, -d, v]), a, u)
    assert abs(e.stiffness - 1.2) < 4 * e.stiffness_std and abs(e.c_d - 0.3) < 4 * e.c_d_std
    assert 0 < e.stiffness_std < 0.05


def test_a_foot_not_yielding_carries_no_law():
    with pytest.raises(ParameterError, match="yielding"):
        GroundEstimator(PAPER_ROBOT).update(np.array([5.0, 0.0, -1.0, 0.0]), 0.0, 0.0)


def test_weighted_updates_are_the_weighted_least_squares():
    # an independent check: recursive updates with per-sample weights against the batch
    # weighted least squares from the prior, (P0^-1 + sum w phi phi')^-1 (P0^-1 theta0 +
    # sum w phi y), in units of the noise variance
    rng = np.random.default_rng(2)
    est = GroundEstimator(PAPER_ROBOT, prior=(1.0, 0.0), prior_std=(1.0, 1.0), noise_std=0.01)
    info = np.diag([0.01 ** 2, 0.01 ** 2])  # P0^-1 = (noise / prior_std)^2
    rhs = info @ np.array([1.0, 0.0])
    for _ in range(20):
        x = np.array([5.0, -1.0, -rng.uniform(0.1, 2.0), -rng.uniform(0.2, 4.0)])
        a, u, w = rng.uniform(-2, 2), rng.uniform(-8, 8), rng.uniform(1e-3, 1.0)
        phi = np.array([-x[2], x[3] ** 2])
        info += w * np.outer(phi, phi)
        rhs += w * phi * est.ground_force(a, u)
        e = est.update(x, a, u, w)
    theta = np.linalg.solve(info, rhs)
    assert [e.stiffness, e.c_d] == pytest.approx(theta, rel=1e-9)
    assert est.P == pytest.approx(np.linalg.inv(info), rel=1e-7)


def test_the_filtered_weight_counts_the_filtered_states_error_in_the_force():
    # f = K d + c_d v^2, its error from the filtered state -K dx + 2 c_d v dv: variance
    # K^2 Pxx - 4 K c_d v Pxv + 4 c_d^2 v^2 Pvv (here 0.25 + 2.4 + 64 = 66.65 noise
    # variances), the weight (1/36 + 0.01) / (1/36 + 66.65)
    x = np.array([10.0, -1.0, -1.0, -4.0])
    w = filtered_weight(x, 20.0, (0.5, 1.0), (1.0, 0.3, 1.0), 1 / 36, 0.1)
    assert w == pytest.approx((1 / 36 + 0.01) / (1 / 36 + 66.65), rel=1e-12)
    # K and c_d no more than the force allows (here c_d v^2 <= 8: c_d <= 0.5)
    assert filtered_weight(x, 8.0, (0.5, 1.0), (1.0, 0.3, 1.0), 1 / 36, 0.1) == pytest.approx(
        (1 / 36 + 0.01) / (1 / 36 + 0.25 + 1.2 + 16.0), rel=1e-12)
    # a state the estimator's allowance covers: weight 1 (the constant noise)
    assert filtered_weight(x, 20.0, (0.5, 1.0), (1e-4, 0.0, 1e-4), 1 / 36, 0.1) == 1.0
