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


def _caught(pid):
    """The signals process ``pid`` has handlers for (Linux: /proc/PID/status, SigCgt)."""
    with open(f"/proc/{pid}/status") as f:
        mask = next(line for line in f if line.startswith("SigCgt:")).split()[1]
    return int(mask, 16)


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs Linux's /proc")
@pytest.mark.parametrize("name,code,line", [("SIGTERM", 143, "terminated (SIGTERM)"),
                                            ("SIGHUP", 129, "hung up (SIGHUP)")])
def test_a_signal_during_start_up_ends_the_command_with_one_line(tmp_path, name, code, line):
    """Issue 47, defect 10: SIGTERM in the first 0.3 s of start-up (before the handlers of
    the run were installed) exited -15 silently, and SIGHUP was not handled at all. The
    handlers are installed first thing (a SIGHUP handler is the sign), the signal is sent
    at once, while the command still imports: one line, its exit code, nothing written."""
    import subprocess
    import sys

    p = subprocess.Popen([sys.executable, "-m", "softlanding", "solve", "--v0", "-3",
                          "--plot", "f.png"], cwd=tmp_path, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not _caught(p.pid) & (1 << (signal.SIGHUP - 1)):
            assert p.poll() is None and time.monotonic() < deadline, "no SIGHUP handler"
            time.sleep(0.0005)
        p.send_signal(getattr(signal, name))
        out, err = p.communicate(timeout=60)
    finally:
        p.kill()
    assert (p.returncode, out, err) == (code, "", f"softlanding: {line}\n")
    assert list(tmp_path.iterdir()) == []


def test_sighup_is_handled_like_sigterm(capsys):
    from softlanding.util.signals import report_interrupt

    with pytest.raises(Terminated) as e, handle_signals():
        assert signal.getsignal(signal.SIGHUP) is not signal.SIG_DFL  # else it would kill
        os.kill(os.getpid(), signal.SIGHUP)
        for _ in range(1000):
            time.sleep(0.01)
    assert e.value.signum == signal.SIGHUP and report_interrupt(e.value) == 129
    assert capsys.readouterr().err == "softlanding: hung up (SIGHUP)\n"
    assert signal.getsignal(signal.SIGHUP) is signal.SIG_DFL  # restored


def test_a_signal_inside_a_solve_adds_no_casadi_warning(capsys):
    """Issue 47, defect 11: CasADi, meeting the interruption inside Ipopt, printed
    WARNING("KeyboardInterruptException") before the run's one line."""
    import threading

    import casadi as ca

    from softlanding.util.signals import raise_if_interrupted

    x = ca.SX.sym("x", 400)  # Rosenbrock: about a second of Ipopt iterations
    f = ca.sum1(100 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2)
    solver = ca.nlpsol("rosenbrock", "ipopt", {"x": x, "f": f}, {
        "print_time": False, "error_on_fail": False,
        "ipopt": {"print_level": 0, "sb": "yes", "max_iter": 100000, "tol": 1e-14,
                  "hessian_approximation": "limited-memory"}})
    timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGTERM))
    with pytest.raises(Terminated), handle_signals():
        timer.start()
        solver(x0=-1.2)
        raise_if_interrupted()
    timer.join()
    assert solver.stats()["return_status"] == "NonIpopt_Exception_Thrown"  # met inside
    assert "CasADi" not in capsys.readouterr().err
    print("CasADi - after the run: shown", file=__import__("sys").stderr)
    assert capsys.readouterr().err == "CasADi - after the run: shown\n"
