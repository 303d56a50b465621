"""The exact path on a ground of stiffness K (f = K d): every mode is still affine.

Three independent references:

* the paper's ground (K = 1) is unchanged bit for bit: outputs recorded before the kernel
  took K (:mod:`k1_landings`);
* the integrated path (DOP853, the law compiled from the ground's own ``yield_force``);
* the paper's ground in rescaled units. With ``x = X / K``, ``t = T / sqrt(K)`` the equations
  ``x_b'' = -1 + u / m_b``, ``x_f'' = -1 + (K d - u) / m_f`` become the paper's in ``X``, ``T``
  with the same forces (``K d = D``): a landing on the K ground of robot ``(r_m, s, u_max,
  l0)`` at ``v0`` is the paper's landing of robot ``(r_m, K s, u_max, K l0)`` at
  ``sqrt(K) v0``, with gains ``k_p / K``, ``k_d / sqrt(K)`` and schedule times ``sqrt(K) t_i``;
  its depth is ``D / K``, its times ``T / sqrt(K)``. A rigid leg (one mass, energy
  ``v0^2 / 2 + d = K d^2 / 2``) penetrates ``(1 + sqrt(1 + K v0^2)) / K``.
"""

import math

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, simulate, simulate_batch
from softlanding.errors import ParameterError
from softlanding.model import CustomGround, ForceSchedule, Impedance, Rigid
from softlanding.model.ground import DragGround, LinearGround
from softlanding.simulation import kernel as K
from softlanding.simulation.groundcode import hold_stiffness, needs_integration
from softlanding.simulation.simulator import integrated

from .k1_landings import REFERENCE, fingerprints

FREE = PAPER_ROBOT.without_force_limit()
STIFFNESSES = (0.5, 0.75, 1.5, 2.0)
SPEEDS = (-1.0, -3.0, -6.0)
CONTROLLERS = (Rigid(), Impedance(0.2, 0.4), Impedance(0.2, 0.18), Impedance(0.5, 0.05),
               Impedance(0.1, 0.3), ForceSchedule((0.1, 0.3), (8.0, -8.0, 1.0)),
               ForceSchedule((), (0.6,)))


def test_the_paper_ground_is_unchanged_bit_for_bit():
    ref = np.load(REFERENCE)
    new = fingerprints()
    assert sorted(ref) == sorted(new)
    moved = [k for k in ref if not np.array_equal(ref[k], new[k], equal_nan=True)]
    assert moved == []


@pytest.mark.parametrize("k", [*STIFFNESSES, 1.0])
def test_a_linear_ground_of_any_stiffness_is_exact(k):
    g = LinearGround(k)
    assert hold_stiffness(g) == k and not needs_integration(g) and not integrated(g)
    assert integrated(g, "integrate")
    assert simulate(FREE, -3, Impedance(0.2, 0.3), g, method="exact").rest_proven


def test_drag_stays_integrated_and_affine_laws_hold_in_proportion():
    assert needs_integration(DragGround(0.2, 2.0)) and needs_integration(DragGround(0.2))
    with pytest.raises(ParameterError, match="no exact path"):
        simulate(FREE, -3, Rigid(), DragGround(0.2, 2.0), method="exact")
    assert not needs_integration(DragGround(0.0, 2.0))  # no drag: the linear ground
    assert hold_stiffness(CustomGround("twice", lambda d, v: 2 * d)) == 2.0
    assert hold_stiffness(CustomGround("damped", lambda d, v: 1.5 * d - 0.3 * v)) == 1.5
    offset = CustomGround("offset", lambda d, v: d + 0.5)  # affine, hold not K d
    assert hold_stiffness(offset) is None and needs_integration(offset)


def _agree(a, b, tol=1e-9):
    assert a.status == b.status and a.steps == b.steps and a.n_segments == b.n_segments
    assert a.feasible == b.feasible and a.foot_rest == b.foot_rest
    for f in ("depth", "t_first_stop", "T", "stroke_min", "stroke_max", "u_peak",
              "depth_limit"):
        x, y = getattr(a, f), getattr(b, f)
        assert (x == y or (math.isnan(x) and math.isnan(y))
                or abs(x - y) <= tol * max(1.0, abs(y))), f
    return abs(a.depth - b.depth)


@pytest.mark.parametrize("k", STIFFNESSES)
@pytest.mark.parametrize("robot", [PAPER_ROBOT, FREE], ids=["paper", "free"])
def test_exact_agrees_with_the_integrated_path(k, robot):
    g = LinearGround(k)
    rests = 0
    for c in CONTROLLERS:
        for v0 in SPEEDS:
            a = simulate(robot, v0, c, g, method="exact")
            b = simulate(robot, v0, c, g, method="integrate", rtol=1e-13)
            _agree(a, b)
            rests += a.rest_proven
    assert rests >= 12


@pytest.mark.parametrize("k", STIFFNESSES)
def test_undamped_hops_and_creep_agree_with_the_integrated_path(k):
    # the integrated path has no hop or creep proof: compare the same number of segments
    g = LinearGround(k)
    for v0 in SPEEDS:
        a = simulate(FREE, v0, Impedance(0.2, 0.0), g, method="exact", max_segments=20)
        b = simulate(FREE, v0, Impedance(0.2, 0.0), g, method="integrate", rtol=1e-13,
                     max_segments=20)
        _agree(a, b)
    # no leg spring: the foot creeps toward the static depth 1 / K (mass 1, weight 1)
    a = simulate(FREE, -1.0, Impedance(0.0, 0.3), g, method="exact")
    b = simulate(FREE, -1.0, Impedance(0.0, 0.3), g, method="integrate", rtol=1e-13)
    assert a.status == K.STATUS_NAMES[K.NEVER_RESTS_CREEP]
    assert a.depth == pytest.approx(1.0 / k, rel=1e-14) == pytest.approx(b.depth, rel=1e-12)


def _rescaled(robot, k):
    return robot.replace(s=robot.s * k, l0=robot.rest_length * k)


def _rescaled_controller(c, k):
    if isinstance(c, Impedance):
        return Impedance(c.k_p / k, c.k_d / math.sqrt(k))
    if isinstance(c, ForceSchedule):
        return ForceSchedule(tuple(t * math.sqrt(k) for t in c.times), c.values)
    return c


@pytest.mark.parametrize("k", [0.25, 0.5, 2.0, 4.0, 0.75])
@pytest.mark.parametrize("robot", [PAPER_ROBOT, FREE], ids=["paper", "free"])
def test_a_stiffer_ground_is_the_paper_ground_rescaled(k, robot):
    g = LinearGround(k)
    controllers = (*CONTROLLERS, Impedance(0.2, 0.0), Impedance(0.0, 0.3), Impedance(0.3, 0.0))
    for c in controllers:
        for v0 in SPEEDS:
            # undamped hops run up to the segment limit: 100 keeps their rounding below 1e-12
            a = simulate(robot, v0, c, g, max_segments=100)
            b = simulate(_rescaled(robot, k), v0 * math.sqrt(k), _rescaled_controller(c, k),
                         max_segments=100)
            assert a.status == b.status and a.steps == b.steps
            assert a.n_segments == b.n_segments
            assert a.depth == pytest.approx(b.depth / k, rel=1e-12, abs=1e-12)
            assert a.stroke_min == pytest.approx(b.stroke_min / k, rel=1e-12, abs=1e-12)
            assert a.u_peak == pytest.approx(b.u_peak, rel=1e-12)
            assert a.stroke_max == pytest.approx(b.stroke_max / k, rel=1e-12, abs=1e-12)
            if a.rest_proven:
                assert a.T == pytest.approx(b.T / math.sqrt(k), rel=1e-12)
                assert a.t_first_stop == pytest.approx(b.t_first_stop / math.sqrt(k), rel=1e-12)


def test_a_stroke_maximum_inside_the_first_step_is_found():
    # the stroke rate is exactly 0 at impact: the turning point inside the first marching
    # step was missed when a strict sign change was required from the step's start
    r = simulate(_rescaled(PAPER_ROBOT, 4.0), -12.0, ForceSchedule((), (0.6,)))
    s = r.trajectory(n=100_001).x
    assert r.stroke_max == pytest.approx(np.max(s[:, 0] - s[:, 2]), rel=1e-9)


@pytest.mark.parametrize("k", [0.5, 0.75, 1.0, 1.5, 2.0, 7.0])
def test_a_rigid_leg_penetrates_the_closed_form_depth(k):
    for v0 in (0.0, -0.5, -1.0, -3.0, -6.0, -10.0):
        r = simulate(FREE, v0, Rigid(), LinearGround(k))
        assert r.rest_proven
        assert r.depth == pytest.approx((1 + math.sqrt(1 + k * v0 * v0)) / k, rel=1e-12)
        assert r.energy.ground == pytest.approx(k * r.depth**2 / 2, rel=1e-12)


@pytest.mark.parametrize("k", [0.5, 2.0])
def test_undamped_hops_stop_at_the_rescaled_closed_form_limit(k):
    # tests/softlanding/simulation/test_kernel_hops.py's limit in the rescaled units
    r_m, kp, v0 = 5.0, 0.5, -3.0
    m_b, m_f = r_m / (1 + r_m), 1 / (1 + r_m)
    limit = (1 + math.sqrt(1 + k * v0 * v0 - k * m_f * (2 * m_b + m_f) / kp)) / k
    from softlanding import Robot

    r = simulate(Robot(5, 20), v0, Impedance(kp, 0.0), LinearGround(k))
    assert r.status == K.STATUS_NAMES[K.HOPS_TO_LIMIT]
    assert r.depth == pytest.approx(limit, rel=1e-9)


def test_batch_exact_agrees_with_the_integrated_path():
    g = LinearGround(2.0)
    kp, kd = np.linspace(0.0, 1.0, 11), np.linspace(0.05, 1.0, 11)
    a = simulate_batch(PAPER_ROBOT, -3.0, kp[:, None], kd[None, :], g)
    b = simulate_batch(PAPER_ROBOT, -3.0, kp[:, None], kd[None, :], g, method="integrate",
                       rtol=1e-13)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.steps, b.steps)
    assert np.array_equal(a.feasible, b.feasible)
    assert np.nanmax(np.abs(a.depth - b.depth)) < 1e-9
    one = simulate(PAPER_ROBOT, -3.0, Impedance(kp[3], kd[4]), g)
    assert a.depth[3, 4] == one.depth and a.T[3, 4] == one.T
