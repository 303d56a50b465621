"""The closed loop's objects: any controller that follows the protocol runs in one runner."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, simulate, solve_landing
from softlanding.control import (
    Command,
    CompiledController,
    LandingController,
    LoopRecord,
    MeasuredEstimator,
    ReplanController,
    Sensor,
    SteppingPlant,
    run_loop,
)
from softlanding.model.ground import LINEAR_GROUND


class OpenLoop:
    """A controller of the protocol that ignores its readings: one schedule from the impact."""

    name = "open loop"

    def __init__(self, schedule, stop):
        self.schedule, self.stop = schedule, stop
        self.record = LoopRecord()
        self.estimator = MeasuredEstimator(PAPER_ROBOT, LINEAR_GROUND, 0.0, False, 1e-9)
        self.readings = []

    def prepare(self, x0):
        return Command(0.0, self.schedule, self.stop)

    def step(self, r):
        self.readings.append(r.sample)
        return r.issued[-1]


def test_an_open_loop_controller_lands_as_its_simulation():
    # the runner steps the plant under the command, samples until the foot stops, then
    # arrests the body from the measured state: with exact sensing, the plan's own tail
    plan = solve_landing(-3)
    ctrl = OpenLoop(plan.schedule(), float(np.sum(plan.refined.durations)))
    assert isinstance(ctrl, LandingController)
    plant = SteppingPlant(PAPER_ROBOT, -3)
    run = run_loop(ctrl, plant, Sensor(), period=0.01, max_samples=1000, stop=3e-9)
    whole = simulate(PAPER_ROBOT, -3, plan.schedule())
    assert run.final.rest_proven and not run.sample_limit_hit
    assert run.final.depth == pytest.approx(whole.depth, rel=1e-9)
    # one step per sample while the foot yielded (the last sample ends at the foot's stop)
    assert ctrl.readings == list(range(1, run.samples))


def test_the_controllers_follow_the_protocol():
    for cls in (CompiledController, ReplanController):
        assert all(callable(getattr(cls, m)) for m in ("prepare", "step"))
        assert isinstance(cls.name, str)
