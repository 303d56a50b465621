"""Recursive least squares recovers the ground law from simulated measurements."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT
from softlanding.control import GroundEstimator, SteppingPlant
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
