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
