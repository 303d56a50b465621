"""An undamped leg (k_d = 0) that keeps hopping: the march stops at the limit depth.

The limit is checked against a closed form written from the paper's equations
(not from the kernel): with the foot pinned at depth D and the body at rest at
the lift-off threshold (support force 1/(1+r_m) + u = 0), energy conservation
from impact gives

    D = 1 + sqrt(1 + v0^2 - m_f (2 m_b + m_f) / k_p),   m_b = r_m/(1+r_m), m_f = 1/(1+r_m),

and against long runs of the same landing with the early stop disabled (a force
limit far above any force reached makes the landing ineligible), which approach
the limit from below.
"""

import math

import numpy as np
import pytest

from softlanding import Impact, Impedance, Robot, simulate, simulate_batch
from softlanding.model.dynamics import mode_matrices
from softlanding.simulation import kernel as K
from softlanding.simulation.kernel.hops import first_symmetric_hop, hop_eligible
from softlanding.simulation.kernel.model import pack_model

ROBOT = Robot(5, 20)
NO_STOP = Robot(5, 20, 1e4)  # same landing, early stop off (forces stay far below 1e4)


def closed_form_limit(kp, v0, r_m=5.0):
    m_b, m_f = r_m / (1 + r_m), 1 / (1 + r_m)
    return 1 + math.sqrt(1 + v0 * v0 - m_f * (2 * m_b + m_f) / kp)


@pytest.mark.parametrize("kp,v0", [(0.5, -3.0), (0.87, -8.0), (0.08, -9.5), (0.44, -1.0),
                                   (0.7, -8.0)])
def test_shrinking_hops_stop_at_the_closed_form_limit(kp, v0):
    r = simulate(ROBOT, Impact(v0), Impedance(kp, 0.0))
    assert r.status == K.STATUS_NAMES[K.HOPS_TO_LIMIT]
    assert "rest not proven" in r.status and not r.rest_proven and not r.feasible
    assert r.depth == pytest.approx(closed_form_limit(kp, v0), abs=1e-10)
    assert r.n_segments < 500  # the default segment limit


def test_long_runs_approach_the_limit_from_below():
    kp, v0 = 0.5, -3.0
    lim = simulate(ROBOT, Impact(v0), Impedance(kp, 0.0)).depth
    gaps = [lim - simulate(NO_STOP, Impact(v0), Impedance(kp, 0.0), max_segments=n,
                           t_max=1e12).depth for n in (500, 2000, 8000)]
    assert all(g > 0 for g in gaps)
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 0.6 * gaps[0]


def test_the_stop_changes_nothing_but_the_stopped_landings():
    kp = np.linspace(0.0, 1.0, 21)
    v0 = np.full(21, -6.0)
    a = simulate_batch(ROBOT, v0, kp, np.zeros(21)).data
    b = simulate_batch(NO_STOP, v0, kp, np.zeros(21)).data
    stopped = a["status"] == K.HOPS_TO_LIMIT
    assert 0 < stopped.sum() < 21
    for key in a:
        assert np.array_equal(a[key][~stopped], b[key][~stopped], equal_nan=True), key
    assert np.all(a["depth"][stopped] > b["depth"][stopped])
    assert np.array_equal(a["depth_limit"][stopped], a["depth"][stopped])
    for key in ("stroke_min", "stroke_max", "u_peak"):  # later hops are smaller
        assert np.array_equal(a[key][stopped], b[key][stopped]), key


def test_symmetric_periodic_hops_are_not_taken_for_the_threshold():
    # k_p = 0.26, v0 = -6: the hops approach a symmetric hop (landing at rest after
    # 2 tau = 6.5683) whose depth 5.7835145666 long runs confirm; no stop is made
    r = simulate(ROBOT, Impact(-6.0), Impedance(0.26, 0.0))
    assert r.status == K.STATUS_NAMES[K.TOO_MANY_SEGMENTS]
    mats = mode_matrices(5.0)
    Kf, _, _ = Impedance(0.26, 0.0).kernel_arrays(mats, ROBOT)
    cu = Kf[0]
    s_lift = 10.0 + (1 / 6) / 0.26  # support 1/(1+r_m) + u = 0 at stroke l0 + m_f / k_p
    tau = first_symmetric_hop(pack_model(mats), cu, s_lift, 7.0)
    assert 3.2 < tau <= 3.2842  # bracket of the root 3.28415 (scan step below 0.01)
    assert first_symmetric_hop(pack_model(mats), cu, s_lift, 6.0) == math.inf


def test_only_a_conservative_spring_leg_is_eligible():
    mats = mode_matrices(5.0)
    spring, _, _ = Impedance(0.5, 0.0).kernel_arrays(mats, ROBOT)
    damped, _, _ = Impedance(0.5, 0.1).kernel_arrays(mats, ROBOT)
    assert hop_eligible(spring, math.inf, False)
    assert not hop_eligible(damped, math.inf, False)
    assert not hop_eligible(spring, 8.2, False)
    assert not hop_eligible(spring, math.inf, True)


def test_results_say_what_their_depth_is():
    hops = simulate(ROBOT, Impact(-3.0), Impedance(0.5, 0.0))
    periodic = simulate(ROBOT, Impact(-6.0), Impedance(0.26, 0.0))
    rests = simulate(ROBOT, Impact(-3.0), Impedance(0.5, 0.5))
    assert (hops.depth_kind, periodic.depth_kind, rests.depth_kind) == ("limit", "reached", "final")
    assert hops.to_dict()["depth_kind"] == "limit"
