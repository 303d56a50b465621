"""A transcription meets its force bound to Ipopt's tolerance, an actuator exactly (issue 47:
an unrefined replay applied a force 1.2e-8 above the limit, unflagged): forces beyond it by
at most FORCE_TOLERANCE are clipped and the replay says so; a larger excess is replayed as
it is and flagged."""

from types import SimpleNamespace

import numpy as np
import pytest

from softlanding.model.robot import PAPER_ROBOT
from softlanding.optimal.phase_schedule import FORCE_TOLERANCE, transcribed_controller
from softlanding.optimal.verification import replay_reasons

U_MAX = PAPER_ROBOT.u_max


def _transcription(forces):
    phase = SimpleNamespace(t0=0.0, T=0.1 * len(forces), N=len(forces),
                            u=np.array(forces, float)[:, None])
    return SimpleNamespace(phases=[phase])


def _forces(ctrl):
    if hasattr(ctrl, "values"):
        return np.asarray(ctrl.values, float)[:-1]
    return np.array([g[4] for g in ctrl.gains])[:-1]  # the constant of each law


def test_a_force_within_the_tolerance_is_clipped_and_said():
    excess = 0.5 * FORCE_TOLERANCE * U_MAX
    ctrl, kind = transcribed_controller(_transcription([U_MAX + excess, 1.0, -U_MAX - excess]),
                                        0.8, u_max=U_MAX)
    assert list(_forces(ctrl)) == [U_MAX, 1.0, -U_MAX]
    assert f"forces up to {excess:.1e} beyond the force limit" in kind
    ctrl, kind = transcribed_controller(_transcription([U_MAX, 1.0]), 0.8, u_max=U_MAX)
    assert list(_forces(ctrl)) == [U_MAX, 1.0] and "clipped" not in kind


def test_a_larger_excess_is_kept_and_the_replay_flags_it():
    over = U_MAX * (1 + 10 * FORCE_TOLERANCE)
    ctrl, kind = transcribed_controller(_transcription([over, 1.0]), 0.8, u_max=U_MAX)
    assert _forces(ctrl)[0] == over and "clipped" not in kind
    replay = SimpleNamespace(robot=PAPER_ROBOT, u_peak=U_MAX + 1.2e-8, rest_proven=True,
                             feasible=True, stroke_min=1.0, stroke_max=2.0, depth=1.5)
    reasons = replay_reasons(replay, 1.5, refined=False)
    assert reasons == [f"the replay applies a force {1.2e-8:.1e} beyond the force limit "
                       f"u_max = {U_MAX:g}"]
    assert replay_reasons(SimpleNamespace(**{**vars(replay), "u_peak": U_MAX}), 1.5,
                          refined=False) == []


@pytest.mark.slow  # one min-peak-force transcription: about 3 s CPU
def test_an_unrefined_min_peak_force_replay_stays_within_its_peak():
    from softlanding.optimal.min_peak_force import solve_min_peak_force

    r = solve_min_peak_force(-3.0, depth_max=2.0163, refine=False)
    assert r.replay.u_peak <= r.peak and not r.unverified_reasons()
