"""The unknown-ground study on one case: every controller reported, the goals checked."""

import pytest

from softlanding.studies.unknown_ground import study_summary, true_ground, unknown_ground_case


@pytest.mark.slow  # a case of the study: six controllers on one ground (1.8 s CPU, issue 46)
def test_one_case_of_the_study():
    row = unknown_ground_case(-3.0, true_ground(2.0, 0.0))
    assert row["clairvoyant_verified"]
    assert row["mpc"]["ratio"] == pytest.approx(1.0, abs=1e-8) and row["mpc"]["feasible"]
    assert not row["open_loop"]["feasible"]  # the nominal plan breaks a limit on stiff ground
    assert row["impedance_nominal"]["ratio"] > 1.0
    s = study_summary([row])
    assert s["mpc_within_2_percent"] == 1 and s["cases"] == 1


def test_true_ground_is_linear_without_drag():
    assert true_ground(1.5, 0.0).to_dict() == {"model": "linear", "stiffness": 1.5}
    assert true_ground(1.0, 0.2).to_dict() == {"model": "drag", "c_d": 0.2}
