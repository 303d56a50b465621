"""CasADi's messages are the toolkit's to show: none in the command line's output."""

import subprocess
import sys

import pytest


@pytest.mark.slow
def test_the_mpc_of_notebook_07_prints_no_casadi_message(tmp_path):
    """The landing of notebook 07 (v0 = -3 on K = 2, c_d = 1) under the re-planning MPC:
    its re-solves try points where the arcs' functions are NaN, and CasADi printed 8
    ``WARNING("active_set_newton:jac_g_x failed: NaN detected ...")`` and ``WARNING("Failed
    to calculate multipliers")`` lines through it (now logged on ``ocp.solver``). The
    compiled controller (the default) solves no NLP on this landing and printed none even
    before the fix, so the command asks for ``--controller replan``. The same landing
    through the API in a Jupyter kernel is notebook 07's (tests/test_notebooks.py reads its
    outputs from the documentation build). About 6 s of CPU."""
    res = subprocess.run([sys.executable, "-m", "softlanding", "mpc", "--v0", "-3", "--ground",
                          "drag", "--stiffness", "2", "--cd", "1", "--controller", "replan"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=1800)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "replan" in res.stdout and "depth" in res.stdout
    assert "WARNING(" not in res.stdout + res.stderr and "CasADi" not in res.stderr, res.stderr
