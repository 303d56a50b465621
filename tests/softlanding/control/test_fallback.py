"""The compiled fallback: a state the push-then-pull structure does not cover is met within
the sample (the plan kept with the margin dropped, the creep law, the safe brake), never by an
NLP solve in the loop."""

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, solve_landing
from softlanding.control import bangbang as bb
from softlanding.control import mpc_landing
from softlanding.control.fallback import fallback_step
from softlanding.control.loop_replay import replay
from softlanding.errors import ParameterError
from softlanding.model.robot import Robot
from softlanding.studies.unknown_ground import true_ground


def _numbers(c_d):
    r = PAPER_ROBOT
    P = bb.robot_numbers(r.r_m, r.s, r.u_max, 0.5, c_d, 1e-3, 2.0, 0.01, creep=True)
    M = bb.new_memory(0.3, 0.05, (0.5, c_d), (1.0, 1.0), 1e-3)
    return P, M


@pytest.mark.parametrize("c_d,then", [(0.2, bb.CREEP_LAW), (0.0, bb.BRAKE)])
def test_the_fallback_keeps_the_plan_once_then_creeps_or_brakes(c_d, then):
    P, M = _numbers(c_d)
    x = np.array([9.9, -1.0, -0.2, -1.0])
    # a status that covers the state is left alone
    assert fallback_step(P, M, x, bb.CONVERGING) == bb.CONVERGING and M[bb.M_FALLBACKS] == 0
    # the first Newton failure: the plan goes on, the margin dropped for the rest
    assert fallback_step(P, M, x, bb.NEWTON_FAILED) == bb.KEPT
    assert P[bb.P_MARGIN] == 0.0 and M[bb.M_PHASE] == bb.PUSH and M[bb.M_FALLBACKS] == 1
    # the next: the creep law where there is drag, else the brake (the pull at the limit)
    assert fallback_step(P, M, x, bb.NEWTON_FAILED) == then and M[bb.M_FALLBACKS] == 2
    assert M[bb.M_WHY] == bb.NEWTON_FAILED and abs(M[bb.M_UCREEP]) <= P[bb.P_UMAX]
    if then == bb.BRAKE:
        assert M[bb.M_PHASE] == bb.BRAKING and M[bb.M_UCREEP] == -P[bb.P_UMAX]
        # braking goes on every sample to the foot's stop, in the step itself
        st = bb.control_step(P, M, x, 0.0, 0.0, 0.01, False, *bb.workspace())
        assert st == bb.BRAKE and M[bb.M_FALLBACKS] == 2


def test_a_noisy_landing_the_structure_does_not_cover_stays_compiled():
    # noise 1e-2 (ten times the study's), a soft draggy ground at v0 = -1: the real-time
    # iteration is not covered at one sample, which re-planned by transcription (0.65 s CPU)
    ground = true_ground(0.5, 0.2)
    m = mpc_landing(-1, PAPER_ROBOT, ground, noise=1e-2, delay=1, seed=0, margin=2.0)
    assert m.uncovered >= 1 and m.replans == m.fallbacks == 0
    assert all(p.startswith("bangbang") for p in m.step_paths)
    assert any(p.startswith("bangbang (kept") for p in m.step_paths)
    assert max(m.step_work) <= 2 * bb.WORK  # (the bound on a sample's work, recovery's too)
    assert m.feasible and m.force_held
    assert m.depth <= 1.03 * solve_landing(-1, PAPER_ROBOT, ground).depth
    replay(m.compiled)  # every sample one compiled call, identical replayed


def test_an_arrest_beyond_the_force_limit_is_not_covered_and_the_brake_holds_the_stroke():
    # issue 46: a random robot of benchmarks/study_realtime.py (random_cases(20), seed 46)
    # whose optimum ends with the body's arrest at the force limit (max, min, max; the
    # crater's hold not reached). The push-then-pull plan with the crater's arrest active
    # asked u_b = 2.09 > u_max after the foot's stop; every sample reported itself covered
    # and the body fell 5.1 through the stroke's lower limit.
    robot = Robot(r_m=2.053079550909057, s=36.11807491623654, u_max=1.7290374640558328)
    v0, k = -5.974298913968741, 1.3090263736077439
    P = bb.robot_numbers(robot.r_m, robot.s, robot.u_max, k, 0.0, creep=True)
    M = bb.new_memory(0.05, 0.5, (k, 0.0), (1.0, 1.0), 1e-6)
    x0 = np.array([0.5 * robot.s, v0, 0.0, v0])
    assert bb.solve_plan(P, M, x0, *bb.workspace(), np.inf) == bb.PATH_LIMIT
    S, c = M[bb.M_XBT] - M[bb.M_XFT], robot.r_m / (1 + robot.r_m)
    assert c * (S + 0.5 * M[bb.M_VBT] ** 2) / S > 1.2 * robot.u_max  # (the plan's u_b)
    m = mpc_landing(v0, robot, true_ground(k, 0.0), noise=1e-3, delay=1, margin=0)
    assert m.uncovered >= 1 and m.replans == 0
    # the pull's plan is not covered: the safe brake from that sample to the foot's stop
    assert "bangbang (brake: path limit)" in m.step_paths
    assert m.step_paths[-1] == "bangbang (brake)"
    assert m.stroke_held and m.force_held and m.feasible, m.failure()
    assert m.stroke_min >= 0.0
    # (the brake is not the optimum, which touches the stroke's lower limit: deeper by 3.8 %)
    assert m.depth <= 1.05 * solve_landing(v0, robot, true_ground(k, 0.0)).depth


def test_the_margin_is_refused_for_the_replanning_mpc():
    with pytest.raises(ParameterError, match="margin"):
        mpc_landing(-1, PAPER_ROBOT, true_ground(1.0, 0.0), margin=2.0, controller="replan")
