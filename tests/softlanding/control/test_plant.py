"""The stepping plant against one uninterrupted simulation."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, simulate, solve_landing
from softlanding.control import SteppingPlant
from softlanding.errors import ParameterError
from softlanding.model.controllers import ForceSchedule
from softlanding.model.ground import DragGround, LinearGround


def _from(schedule, t0):
    """The schedule from time t0 on, restarted at 0."""
    i = int(np.searchsorted(schedule.times, t0, side="right"))
    return ForceSchedule(tuple(t - t0 for t in schedule.times[i:]), schedule.values[i:])


@pytest.mark.parametrize("ground,tol", [(LinearGround(), 1e-12), (LinearGround(2.0), 1e-9),
                                        (DragGround(0.2), 1e-9)])
def test_stepped_run_equals_the_uninterrupted_one(ground, tol):
    sched = solve_landing(-3).schedule()
    full = simulate(PAPER_ROBOT, -3, sched, ground)
    plant = SteppingPlant(PAPER_ROBOT, -3, ground)
    for _ in range(20):  # through the switch at 0.126 and into the second arc
        plant.step(_from(sched, plant.t), 0.01)
    ref = full.trajectory(t_end=plant.t, n=2).x[-1]
    assert np.abs(plant.x - ref).max() <= tol * max(1.0, np.abs(ref).max())
    assert plant.crater == pytest.approx(-plant.x[2])
    end = plant.finish(_from(sched, plant.t))
    assert end.depth == pytest.approx(full.depth, rel=tol)


def test_bad_period_is_refused():
    with pytest.raises(ParameterError, match="duration"):
        SteppingPlant(PAPER_ROBOT, -3).step(ForceSchedule((), (0.0,)), 0.0)


def test_the_plant_saturates_a_constant_force_at_the_limit():
    # a command beyond u_max (a noisy arrest's) is applied at u_max: as the schedule of u_max
    over, at = SteppingPlant(PAPER_ROBOT, -3), SteppingPlant(PAPER_ROBOT, -3)
    over.step(ForceSchedule((0.005,), (20.0, -1e100)), 0.01)
    at.step(ForceSchedule((0.005,), (PAPER_ROBOT.u_max, -PAPER_ROBOT.u_max)), 0.01)
    assert np.array_equal(over.x, at.x)
    assert over.history[-1][1].u_peak == PAPER_ROBOT.u_max


def test_the_plant_saturates_an_affine_law_as_an_impedance_is():
    # a stiff affine row u = -k_p (x_b - x_f - l) - k_d (v_b - v_f) (a hold's) leaves the limit
    # at impact: applied saturated, it is the impedance (k_p, k_d, l), which the simulator
    # saturates with its own events
    from softlanding.model.controllers import FeedbackSchedule, Impedance, impedance_gains

    row = tuple(impedance_gains(40.0, 2.0, 9.0))
    plant = SteppingPlant(PAPER_ROBOT, -3)
    plant.step(FeedbackSchedule((), (row,)), 0.05)
    ref = simulate(PAPER_ROBOT, -3, Impedance(40.0, 2.0, 9.0), t_max=0.05)
    assert ref.u_peak == pytest.approx(PAPER_ROBOT.u_max, rel=1e-12)  # (it saturates)
    assert np.abs(plant.x - ref.trajectory(t_end=0.05, n=2).x[-1]).max() <= 1e-12
    assert max(r.u_peak for _, r in plant.history) <= PAPER_ROBOT.u_max * (1 + 1e-12)
