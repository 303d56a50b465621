"""CasADi Functions called on numpy arrays through their FunctionBuffer (issue 31).

``BufferedCall`` must give what CasADi's ordinary call gives, bit for bit (inputs laid out
column-major, a column repeated across a map's columns, defaults for missing inputs, Ipopt's
statistics of *this* call); the re-solves that use it must still report what the solve did
and the check between the points must still see the parameter values of each solve.
"""

import warnings

import casadi as ca
import numpy as np
import pytest

from ocp import Collocation, MultipleShooting, OptimalControlProblem, PathViolationWarning
from ocp.transcriptions.buffered import BufferedCall
from tests.oracles.ocp_suite.problems import moon_lander


def _function():
    a, b, c = ca.SX.sym("a", 2, 3), ca.SX.sym("b", 3), ca.SX.sym("c", 0, 1)
    f = ca.Function("f", [a, b, c], [ca.mtimes(a, b) ** 2, a.T * ca.sin(b[0])],
                    ["a", "b", "c"], ["ab", "at"])
    return f.map(4)


def test_buffered_call_equals_the_ordinary_call_bit_for_bit():
    f = _function()
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 12)), rng.normal(size=(3, 4))
    c = np.zeros((0, 4))
    call = BufferedCall(f)
    ref = [np.array(r) for r in f(a, b, c)]
    got = call(a, b, c)
    assert call.buffered
    for r, g in zip(ref, got, strict=True):
        assert g.tobytes() == r.ravel(order="F").tobytes()
    # a column repeated across the map's columns, as CasADi's call repeats it
    col = b[:, 1]
    assert call(a, col, c)[0].tobytes() == np.array(f(a, col, c)[0]).ravel(order="F").tobytes()
    # results are fresh arrays, not views of the buffer's next evaluation
    first = call(a, b, c)[0]
    call(2 * a, b, c)
    assert first.tobytes() == ref[0].ravel(order="F").tobytes()
    with pytest.raises(ValueError, match="shape"):
        call(a[:, :5], b, c)
    # held by another caller (a second thread): the ordinary call, the same numbers
    with call.lock:
        again = call(a, b, c)
    assert not call.buffered and again[1].tobytes() == got[1].tobytes()


def test_buffered_ipopt_solve_equals_the_ordinary_one_with_its_own_statistics():
    x = ca.SX.sym("x", 2)
    p = ca.SX.sym("p")
    nlp = {"x": x, "p": p, "f": (1 - x[0]) ** 2 + p * (x[1] - x[0] ** 2) ** 2,
           "g": x[0] + x[1]}
    opts = {"ipopt": {"print_level": 0, "sb": "yes"}, "print_time": False}
    solver = ca.nlpsol("rosen", "ipopt", nlp, opts)
    call = BufferedCall(solver)
    args = {"x0": np.array([-1.2, 1.0]), "p": np.array([100.0]), "ubg": np.array([1.5])}
    ref = solver(**args)
    ref_stats = solver.stats()
    got = call.named(args)  # lbx, ubx, lbg, lam_x0, lam_g0 at their defaults
    st = call.stats()
    for k in ("x", "f", "g", "lam_x", "lam_g"):
        assert got[k].tobytes() == np.array(ref[k]).ravel().tobytes()
    assert st["iter_count"] == ref_stats["iter_count"] > 5
    assert st["return_status"] == ref_stats["return_status"] == "Solve_Succeeded"
    # the next call's statistics, not the first's
    call.named({**args, "x0": np.array(got["x"])})
    assert call.stats()["iter_count"] < st["iter_count"]
    with pytest.raises(ValueError, match="no input"):
        call.named({"x": args["x0"]})


def test_radau_re_solves_report_their_own_iterations_and_keep_the_solution():
    tr = Collocation(moon_lander(), intervals=6)
    cold = tr.solve()
    warm = tr.solve(warm_start=cold)
    again = tr.solve()
    assert cold.success and warm.success and again.success
    assert warm.iterations <= 3 < cold.iterations == again.iterations
    assert again.w.tobytes() == cold.w.tobytes() and again.objective == cold.objective
    assert np.max(np.abs(warm.w - cold.w)) < 1e-5
    assert warm.verified and warm.path_violation <= tr.verify_tol


def _band() -> OptimalControlProblem:
    """Rest to rest, min int u^2, above a bump between the nodes of a 10-node grid, the
    bump lowered by the parameter ``a``: a = 0 violated between the nodes, a = 2 not."""
    p = OptimalControlProblem("band_a")
    x, v = p.state("x"), p.state("v")
    u = p.control("u")
    a = p.parameter("a")
    p.set_dynamics({"x": v, "v": u})
    for s in (x, v):
        p.initial_constraint(s, 0.0)
        p.terminal_constraint(s, 0.0)
    p.path_constraint(x - (1 - ((p.t - 0.55) / 0.05) ** 2), lower=-a, name="above the bump")
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    return p


def test_the_check_between_nodes_sees_each_solves_parameter_values():
    """The check's bounds are kept between re-solves at the same parameter values: a
    re-solve at other values must be checked against its own (here the verdict flips)."""
    tr = MultipleShooting(_band(), nodes=10)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PathViolationWarning)
        low = tr.solve({"a": 2.0})
    assert low.verified and low.path_violation == 0.0
    with pytest.warns(PathViolationWarning, match="above the bump"):
        high = tr.solve({"a": 0.0}, warm_start=low)
    assert high.success and high.verified is False
    assert high.path_violation == pytest.approx(1.0, abs=1e-5)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PathViolationWarning)
        back = tr.solve({"a": 2.0}, warm_start=high)
    assert back.verified and back.violations == {}


@pytest.mark.slow  # about 1.5 s: a solve long enough to be interrupted inside Ipopt
def test_an_interruption_inside_ipopt_is_raised_not_turned_into_a_failed_solve():
    """CasADi's ordinary call turns Ctrl-C inside Ipopt into a failed solve
    (``NonIpopt_Exception_Thrown``, a ``SolveError`` that ``continuation`` retried); the
    buffered call raises the interruption."""
    import signal

    tr = Collocation(moon_lander(), intervals=400, expand=False, verify="off")
    tr.solve()  # built: the next solve's time is Ipopt's (about 0.6 s)

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.15)
        with pytest.raises(KeyboardInterrupt):
            tr.solve()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
    assert tr.solve().success  # the transcription solves again afterwards


def test_two_threads_on_one_transcription_each_report_their_own_solve():
    # (the buffer is the first thread's while it solves; the other takes CasADi's call:
    # each solve's statistics must be its own, read before the buffer is released)
    import sys
    import threading

    tr = Collocation(moon_lander(), intervals=8, expand=False, verify="off")
    cold = tr.solve()
    hot = tr.solve(guess=cold)
    assert cold.iterations != hot.iterations
    switch = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # (the threads interleave within each solve)
    stop, seen = threading.Event(), []

    def other():
        while not stop.is_set():
            seen.append(tr.solve(guess=cold).iterations)

    t = threading.Thread(target=other)
    t.start()
    try:
        mine = [tr.solve().iterations for _ in range(40)]
    finally:
        stop.set()
        t.join()
        sys.setswitchinterval(switch)
    assert set(mine) == {cold.iterations} and set(seen) == {hot.iterations}
    assert len(seen) > 5


def test_a_scalar_fills_its_input_as_casadis_call_does():
    x = ca.SX.sym("x", 2)
    f = ca.Function("s", [x], [2 * x], ["x0"], ["y"])
    assert BufferedCall(f).named({"x0": 0.5})["y"].tolist() == [1.0, 1.0]
