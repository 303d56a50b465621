"""The one dynamics definition and the mode matrices derived from it."""

import casadi as ca
import numpy as np
import pytest

from softlanding.model.dynamics import mode_matrices, robot_rhs, stance_functions


def paper_f_g(x, r):
    """The paper's eq. (6), typed in from the paper independently of the code."""
    f = np.array([x[1], -1.0, x[3], -(1 + r) * x[2] - 1])
    g = np.array([0.0, (1 + r) / r, 0.0, -(1 + r)])
    return f, g


@pytest.mark.parametrize("r", [0.5, 5.0, 20.0])
def test_stance_f_g_match_paper(r):
    f, g = stance_functions()
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = rng.normal(size=4)
        fp, gp = paper_f_g(x, r)
        np.testing.assert_allclose(np.array(f(x, r)).ravel(), fp, rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.array(g(x, r)).ravel(), gp, rtol=0, atol=1e-14)


@pytest.mark.parametrize("r", [1.0, 5.0])
def test_mode_matrices_reproduce_rhs(r):
    m = mode_matrices(r)
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = rng.normal(size=4)
        u = rng.normal()
        z = np.r_[x, 1.0]
        yld = np.array(ca.DM(robot_rhs(x, u, -x[2], r))).ravel()
        np.testing.assert_allclose((m["A"][0] @ z + m["B"][0] * u)[:4], yld, atol=1e-13)
        fl = np.array(ca.DM(robot_rhs(x, u, 0.0, r))).ravel()
        np.testing.assert_allclose((m["A"][2] @ z + m["B"][2] * u)[:4], fl, atol=1e-13)
        # static: support force 1/(1+r) + u keeps the foot still
        freq = m["Fz"] @ z + m["Fu"] * u
        assert freq == pytest.approx(1 / (1 + r) + u, abs=1e-13)
        st = np.array(ca.DM(robot_rhs(x, u, freq, r))).ravel()
        assert st[3] == pytest.approx(0.0, abs=1e-13)
        assert np.all((m["A"][1] @ z + m["B"][1] * u)[2:4] == 0.0)
