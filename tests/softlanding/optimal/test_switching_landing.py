"""The soft landing at short strokes: boundary arcs on the stroke limit, refined.

At short strokes the transcription rides the stroke limit ``x_b - x_f <= s``
(relative degree 2 in u) for most of the landing, zig-zagging along it. The
refinement replaces that with a boundary arc whose control keeps the stroke at
its limit, ``u = -x_f r_m / (1 + r_m)``, with the arc's entry and exit times as
unknowns. Checked here: the refined depth is no worse than the transcription's
(beyond the transcription's own relaxation of the constraint between nodes),
every constraint holds along the refined arcs, an independent scipy
integration of the reported schedule and control laws lands on the refined
final state, and the certificate reports the state-constrained interval.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.certificate.certify import CERTIFIED, INCONCLUSIVE, certify
from ocp.structure.switching import detect_arcs, refine_switching
from softlanding import Robot
from softlanding.optimal.landing import STROKE, arrest_force, solve_landing

R_M, U_MAX = 5.0, 8.2
CASES = [(s, v0) for s in (0.5, 1.0, 2.0, 5.0) for v0 in (-1.0, -3.0, -10.0)]
UNCONSTRAINED = {(5.0, -1.0), (5.0, -3.0)}  # the stroke limit is never reached


def replay(ref, s):
    """Integrate the refined schedule with scipy: bang values, or the reported law
    ``u = K x + k0`` on boundary arcs. Returns the final state and the stroke range."""
    x = np.array(ref.x0, dtype=float)
    lo, hi = math.inf, -math.inf
    for tau, val, law in zip(ref.durations, ref.values, ref.control_laws, strict=True):
        if law is None:
            def u(x, v=val):
                return v
        else:
            K, k0 = np.array(law["gain"][0]), law["offset"][0]

            def u(x, K=K, k0=k0):
                return K @ x + k0
        def rhs(t, x, u=u):
            f = u(x)
            return [x[1], -1 + (1 + R_M) / R_M * f, x[3], -1 - (1 + R_M) * (x[2] + f)]
        if tau > 0:
            sol = solve_ivp(rhs, (0, tau), x, method="DOP853", rtol=1e-12, atol=1e-12,
                            dense_output=True)
            xs = sol.sol(np.linspace(0, tau, 200))
            lo, hi = min(lo, np.min(xs[0] - xs[2])), max(hi, np.max(xs[0] - xs[2]))
            x = sol.y[:, -1]
    return x, lo, hi


@pytest.mark.parametrize("s,v0", [  # s = 5, v0 = -10: 1.6 s CPU (issue 46)
    pytest.param(*c, marks=pytest.mark.slow) if c == (5.0, -10.0) else c for c in CASES])
def test_short_stroke_landing_refines_with_boundary_arcs(s, v0):
    tr = solve_landing(v0, Robot(r_m=R_M, s=s, u_max=U_MAX), refine=False, replay=False)
    sol = tr.transcribed
    st = detect_arcs(sol).without_trailing_constrained()
    assert st.refinable, st.kinds
    ref = refine_switching(sol, st)
    depth, depth_tr = -ref.xT[2], -sol.x[-1, 2]
    # the transcription enforces the stroke only at its nodes and may gain a
    # little between them: allow 1e-6 relative
    assert depth <= depth_tr + 1e-6 * depth_tr
    assert abs(depth - depth_tr) <= 2e-4 * depth_tr
    assert ref.path_violation() <= 1e-9
    assert abs(ref.xT[3]) <= 1e-10  # the foot stops at T
    assert depth >= 1 / (1 + R_M) + arrest_force(R_M, ref.xT) - 1e-10  # arrest condition
    boundary = [k for k, kind in enumerate(ref.kinds) if kind == "boundary"]
    if (s, v0) in UNCONSTRAINED:
        assert ref.kinds == ["max", "min"] and not boundary
    else:
        assert ref.kinds[:3] == ["max", "min", "boundary"]
        law = ref.control_laws[boundary[0]]
        assert law["constraints"] == [{"name": STROKE, "side": "upper", "relative_degree": 2}]
        np.testing.assert_allclose(law["gain"], [[0, 0, -R_M / (1 + R_M), 0]], atol=1e-15)
        assert np.isnan(ref.values[boundary[0]])
    xT, lo, hi = replay(ref, s)
    np.testing.assert_allclose(xT, ref.xT, atol=1e-8)
    assert -1e-9 <= lo and hi <= s + 1e-9
    c = certify(sol, ref)
    if boundary:
        assert c.verdict == INCONCLUSIVE
        assert "state constraint active" in c.reasons[-1]
        a, b = c.state_constraint_active_intervals[0]
        edges = np.r_[0, np.cumsum(ref.durations)]
        assert a == pytest.approx(edges[boundary[0]], abs=1e-9)
        assert b == pytest.approx(edges[boundary[0] + 1], abs=1e-9)
    else:
        assert c.verdict == CERTIFIED, c.reasons


@pytest.mark.slow
def test_short_stroke_refined_depth_is_the_limit_of_finer_transcriptions():
    depths = []
    for nodes in (100, 200, 400):
        sol = solve_landing(-10.0, Robot(r_m=R_M, s=0.5, u_max=U_MAX), nodes=nodes, refine=False,
                            replay=False).transcribed
        ref = refine_switching(sol, detect_arcs(sol).without_trailing_constrained())
        depths.append((-sol.x[-1, 2], -ref.xT[2]))
    refined = [d[1] for d in depths]
    assert max(refined) - min(refined) <= 1e-11  # the same optimum from every grid
    errors = [abs(d[0] - refined[0]) for d in depths]
    assert errors[2] < errors[0] and errors[2] <= 2e-6
