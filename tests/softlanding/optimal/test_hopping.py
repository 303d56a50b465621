"""Minimum-energy hopping (softlanding.optimal.hopping): the cycle closes on the exact replay, the
energy bookkeeping is exact, and the three legs compare as they must."""

import math

import numpy as np
import pytest

from softlanding import PAPER_ROBOT
from softlanding.errors import ParameterError
from softlanding.model.dynamics import mode_matrices
from softlanding.optimal.hopping import best_impedance_hop, impedance_hop, rigid_hop, solve_hop
from softlanding.simulation.actuator_work import segment_work


@pytest.fixture(scope="module")
def free():
    return solve_hop(-2.0, PAPER_ROBOT, eta=0.0)


def test_segment_work_is_exact_on_a_flight_arc():
    # flight with a constant force: the leg rate w(t) = w0 + u t / mu (mu = r_m/(1+r_m)^2),
    # so P = u w is linear and its positive and negative parts integrate in closed form
    r_m, u, w0, tau = 5.0, 2.0, -1.5, 0.8
    mats = mode_matrices(r_m)
    A = mats["A"][2] + np.outer(mats["B"][2], [0, 0, 0, 0, u])
    z0 = np.array([3.0, w0, 1.0, 0.0, 1.0])
    mu = r_m / (1 + r_m) ** 2
    a = u / mu
    t0 = -w0 / a  # the rate crosses zero here
    neg = -u * (w0 * t0 + a * t0**2 / 2)
    pos = u * (w0 * (tau - t0) + a * (tau**2 - t0**2) / 2)
    w = segment_work(A, z0, np.array([0, 0, 0, 0, u]), tau)
    assert w.negative == pytest.approx(neg, rel=1e-12)
    assert w.positive == pytest.approx(pos, rel=1e-12)


def test_the_optimal_cycle_closes_and_balances(free):
    assert free.unverified_reasons() == []
    assert free.apex_error < 1e-5 and free.balance_error < 1e-9
    # over a periodic cycle the actuator's net work is the crater's loss d^2/2
    assert free.work.net == pytest.approx(free.depth ** 2 / 2, rel=1e-6)
    assert free.energy == pytest.approx(free.work.positive, rel=1e-14)  # eta = 0
    assert free.energy >= free.depth ** 2 / 2
    assert free.times["touchdown"] < free.times["foot_stop"] < free.times["lift_off"] \
        < free.times["apex"]


def test_regeneration_lowers_the_energy(free):
    half = solve_hop(-2.0, PAPER_ROBOT, eta=0.5)
    assert half.unverified_reasons() == []
    assert half.energy < free.energy
    assert half.energy == pytest.approx(half.work.positive - 0.5 * half.work.negative)


def test_rigid_and_impedance_cycles_close_too(free):
    rig = rigid_hop(-2.0)
    assert rig.unverified_reasons() == []
    assert rig.depth == pytest.approx(1 + math.sqrt(1 + 4.0), rel=1e-12)  # the rigid crater
    assert rig.energy > free.energy  # the optimum is at least as good as a rigid landing
    imp = best_impedance_hop(-2.0, grid=5)
    assert imp is not None and imp.unverified_reasons() == []
    assert imp.energy > free.energy
    assert set(imp.gains) == {"k_p", "k_d", "u_t"}
    again = impedance_hop(-2.0, imp.gains["k_p"], imp.gains["k_d"])
    assert again is not None and again.gains["u_t"] == pytest.approx(imp.gains["u_t"])


def test_bad_requests():
    with pytest.raises(ParameterError, match="eta"):
        solve_hop(-2.0, eta=1.0)
    with pytest.raises(ParameterError, match="v0"):
        rigid_hop(0.0)
