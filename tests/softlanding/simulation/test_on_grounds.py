"""One schedule landed on several grounds on worker threads: the serial landings, bit for bit,
in the grounds' order (the robust search replays every point it evaluates this way)."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, simulate
from softlanding.model.controllers import ForceSchedule
from softlanding.model.ground import DragGround, LinearGround
from softlanding.simulation.on_grounds import simulate_on_grounds

GROUNDS = [LinearGround(0.5), DragGround(1.0, 0.5), LinearGround(), DragGround(1.0, 2.0),
           DragGround(0.3)]


@pytest.mark.parametrize("threads", [None, 1, 2, 8])
def test_threads_give_the_serial_landings(threads):
    # the robust schedule of test_robust's four grounds at v0 = -3
    sched = ForceSchedule((0.2041950236531257, 0.4330684063158512, 5.924636276051642),
                          (8.2, -8.2, 1.3911435899190614, 0.8333333333333334))
    serial = [simulate(PAPER_ROBOT, -3, sched, g, energy=False) for g in GROUNDS]
    again = simulate_on_grounds(PAPER_ROBOT, -3, sched, GROUNDS, threads=threads)
    assert [r.ground for r in again] == GROUNDS
    for a, b in zip(serial, again, strict=True):
        assert (a.depth, a.stroke_min, a.stroke_max, a.t_first_stop, a.status, a.feasible) == (
            b.depth, b.stroke_min, b.stroke_max, b.t_first_stop, b.status, b.feasible)
        for key, value in a.segments.items():
            if key != "law":
                assert np.array_equal(value, b.segments[key], equal_nan=True)
