"""A batch of landings on several worker threads is the one-thread batch, bit for bit (the
tests run batches on one thread: tests/conftest.py)."""

import threading

import numpy as np
import pytest

import softlanding.simulation.kernel as kernel
from softlanding import PAPER_IMPEDANCE_ROBOT, simulate_batch
from softlanding.model.ground import DragGround, LinearGround


@pytest.mark.parametrize("ground", [LinearGround(1.5), DragGround(0.4)])
def test_threads_take_chunks_and_give_the_serial_batch(ground, monkeypatch):
    kp, kd = np.linspace(0.0, 2.0, 13), np.linspace(0.0, 2.5, 11)
    v0 = -4.0 if isinstance(ground, LinearGround) else -2.0
    one = simulate_batch(PAPER_IMPEDANCE_ROBOT, v0, kp[:, None], kd[None, :], ground)
    monkeypatch.setattr(kernel, "default_threads", lambda: 3)
    three = simulate_batch(PAPER_IMPEDANCE_ROBOT, v0, kp[:, None], kd[None, :], ground)
    # 143 landings in chunks of 16 (affine) or 4 (integrated), so more than one chunk: the
    # thread count was read and the batch given to a pool of three (the pool outlives a
    # batch: for the second ground it is the first one's)
    workers = [t for t in threading.enumerate() if t.name.startswith("softlanding_")]
    assert len(workers) >= 3
    for name in ("depth", "u_peak", "stroke_min", "stroke_max", "status"):
        a, b = np.asarray(getattr(one, name)), np.asarray(getattr(three, name))
        assert a.shape == (13, 11) and np.array_equal(a, b, equal_nan=True), name
