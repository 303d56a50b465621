"""The compiled controller's samples replayed as a control loop (``loop_replay``), and the
fused filtered sample against its parts."""

import dataclasses

import numpy as np
import pytest

from softlanding.control import bangbang as bb
from softlanding.control import mpc_landing
from softlanding.control.foot_filter import filter_step
from softlanding.control.loop_replay import ReplayMismatch, replay
from softlanding.control.recovery import filtered_sample, filtered_step, sample_weight
from softlanding.model.ground import LinearGround
from softlanding.model.robot import PAPER_ROBOT


@pytest.fixture(scope="module")
def landings():
    # v0 = -1, K = 0.75: a short noisy landing (about 20 samples), with each estimator
    return {e: mpc_landing(-1, PAPER_ROBOT, LinearGround(0.75), controller="bangbang",
                           noise=1e-3, delay=1, margin=2.0, estimator=e)
            for e in ("filtered", "measured")}


@pytest.mark.parametrize("estimator", ["filtered", "measured"])
def test_a_landing_replays_to_the_bit_as_a_control_loop(landings, estimator):
    landing = landings[estimator]
    rec = landing.compiled
    own = [p for p in landing.step_paths if p.startswith("bangbang")]
    assert rec is not None and len(rec.samples) == len(own) > 10
    assert (rec.F is not None) == (landing.estimator == "filtered")
    wall, cpu = replay(rec, pace_s=1e-5)  # (checks every sample's status and memory)
    assert len(wall) == len(cpu) == len(rec.samples) and min(wall) > 0
    # a recorded memory off in its last bit: the replay times another computation
    s = rec.samples[5]
    off = s.memory.copy()
    off[bb.M_TAU2] = np.nextafter(off[bb.M_TAU2], np.inf)
    bad = dataclasses.replace(rec, samples=[*rec.samples[:5], dataclasses.replace(
        s, memory=off), *rec.samples[6:]])
    with pytest.raises(ReplayMismatch, match="sample 5"):
        replay(bad)
    if rec.F is not None:  # the foot filter's memory is compared too
        f = s.filter_memory.copy()
        f[0] = np.nextafter(f[0], np.inf)
        bad = dataclasses.replace(rec, samples=[*rec.samples[:5], dataclasses.replace(
            s, filter_memory=f), *rec.samples[6:]])
        with pytest.raises(ReplayMismatch, match="sample 5"):
            replay(bad)


def test_the_fused_filtered_sample_is_its_parts(landings):
    rec = landings["filtered"].compiled
    P, M, F = rec.P.copy(), rec.M.copy(), rec.F.copy()
    P2, M2, F2 = P.copy(), M.copy(), F.copy()
    K, W = bb.workspace()
    r1 = r2 = 0
    for s in rec.samples:
        g, u1, u2, beta, noise, stop = s.filtered
        x1 = s.x.copy()
        st1, r1 = filtered_sample(P, M, F, x1, g, u1, u2, s.h, beta, noise, s.a_f, s.u,
                                  s.estimate, stop, r1, K, W)
        x2 = s.x.copy()
        filter_step(F2, x2, g, u1, u2, s.h, beta, noise)
        x2[3] = min(x2[3], -stop)
        w = sample_weight(P2, M2, F2, x2, s.a_f, s.u) if s.estimate else 1.0
        st2, r2 = filtered_step(P2, M2, x2, s.a_f, s.u, s.h, s.estimate, w, r2, K, W)
        assert (st1, r1) == (st2, r2) and np.array_equal(x1, x2)
        assert np.array_equal(M, M2) and np.array_equal(P, P2) and np.array_equal(F, F2)
        assert np.array_equal(M, s.memory)  # (and the landing's own)
