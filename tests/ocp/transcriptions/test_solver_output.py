"""CasADi's messages are logged (``ocp.solver``, DEBUG), not printed; nothing else is held."""

import logging
import sys
import threading

import casadi as ca
import numpy as np
import pytest

from ocp.structure.active_set_newton import ActiveSetNewton
from ocp.transcriptions.solver_output import solver_output


@pytest.fixture(scope="module")
def nan_root():
    """A rootfinder whose Jacobian is NaN at a negative start (CasADi warns there)."""
    x, p = ca.SX.sym("x"), ca.SX.sym("p")
    return ca.rootfinder("nan_root", "newton", ca.Function("r", [x, p], [ca.sqrt(x) - p]),
                         {"error_on_fail": False})


def test_a_casadi_warning_is_logged_not_printed(nan_root, capfd, caplog):
    before = sys.stdout, sys.stderr
    with caplog.at_level(logging.DEBUG, logger="ocp.solver"), solver_output() as taken:
        nan_root(-1.0, 2.0)
        print("the caller's own line")
    out, err = capfd.readouterr()
    assert "WARNING(" not in out + err
    assert "the caller's own line" in out  # everything else passes through
    assert (sys.stdout, sys.stderr) == before  # the streams put back
    assert taken and "nan_root" in taken[0] and "NaN detected" in taken[0]
    assert any("NaN detected" in r.getMessage() and r.levelno == logging.DEBUG
               for r in caplog.records if r.name == "ocp.solver")


def test_without_the_context_casadi_prints_its_warning(nan_root, capfd):
    """What the context takes away (so the test above can fail)."""
    nan_root(-1.0, 2.0)
    out, err = capfd.readouterr()
    assert "WARNING(" in out + err


def test_the_active_set_newton_prints_no_warning(capfd):
    """Newton from a point outside the rows' domain (NaN) prints no CasADi line (it
    printed ``WARNING("active_set_newton:jac_g_x failed: NaN detected ...")``)."""
    w, p = ca.SX.sym("w"), ca.SX.sym("p", 0)
    nlp = {"x": w, "p": p, "g": ca.sqrt(w), "f": w}
    bounds = ca.Function("bounds", [p], [ca.DM([0.0]), ca.DM([2.0])])
    newton = ActiveSetNewton(nlp, bounds, np.array([0]), np.array([1]), np.zeros(0, int))
    newton.solve(np.zeros(0), np.array([-1.0]), np.zeros(0))
    assert newton.solve(np.zeros(0), np.array([1.0]), np.zeros(0))[0][0] == pytest.approx(4)
    out, err = capfd.readouterr()
    assert "WARNING(" not in out + err and "CasADi" not in out + err


def test_other_threads_and_unfinished_lines_pass_through(nan_root, capsys):
    inside, done = threading.Event(), threading.Event()

    def other():
        inside.wait(5)
        print("from another thread")
        done.set()

    t = threading.Thread(target=other)
    t.start()
    with solver_output():
        sys.stdout.write("Ca")  # could begin CasADi's format: held until the line ends
        inside.set()
        done.wait(5)
        with solver_output() as inner:  # nested: the inner one takes the messages
            nan_root(-1.0, 2.0)
        sys.stdout.write("lculated\n")
    t.join()
    out, err = capsys.readouterr()
    assert "from another thread" in out and "Calculated\n" in out
    assert inner and "WARNING(" not in out + err
