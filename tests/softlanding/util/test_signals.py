"""A signal whose exception lands where it cannot propagate (a destructor: llvmlite's while
numba compiles) prints no "Exception ignored" traceback and still stops the run."""

import gc
import os
import signal
import time

import pytest

from softlanding.util.signals import Terminated, handle_signals


class _SignalledWhileDeleted:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGTERM)  # the handler runs here, inside __del__
        for _ in range(1000):
            pass


def test_a_signal_raised_in_a_destructor_is_delivered_again_quietly(capsys):
    reached = []
    with pytest.raises(Terminated), handle_signals():
        _SignalledWhileDeleted()  # deleted at once: Terminated lost in __del__
        gc.collect()
        reached.append("after the destructor")
        for _ in range(1000):  # the signal, delivered again, raises here (within 10 s)
            time.sleep(0.01)
        reached.append("the end")
    assert reached == ["after the destructor"]
    assert "Exception ignored" not in capsys.readouterr().err


def test_a_signal_as_a_compiled_landing_returns_comes_out_as_itself(monkeypatch):
    """numba wraps a handler's exception raised as its kernel returns in a SystemError ("...
    returned a result with an exception set"): measured with an alarm during robust_landing."""
    from softlanding.model import Rigid
    from softlanding.model.robot import PAPER_ROBOT
    from softlanding.simulation import kernel
    from softlanding.simulation.simulator import simulate

    def interrupted(*a, **k):
        try:
            raise TimeoutError("the alarm's handler")
        except TimeoutError as exc:
            raise SystemError("CPUDispatcher(<function landing_entry>) returned a result with "
                              "an exception set") from exc

    monkeypatch.setattr(kernel, "run_landing", interrupted)
    with pytest.raises(TimeoutError, match="the alarm's handler"):
        simulate(PAPER_ROBOT, -1.0, Rigid())
