"""The min-peak-force variant says whether its depth budget binds (issue 44): with a slack
budget its peak is the least force that lands at all, not the force limit whose two-phase
least depth is the budget."""

import json

import pytest

from softlanding import PAPER_ROBOT
from softlanding.optimal import solve_two_phase
from softlanding.optimal.min_peak_force import solve_min_peak_force

LEAST = 1.516295632282  # the two-phase least depth at v0 = -3 (tests/softlanding/cli)


@pytest.mark.slow  # two solves (1.5 s CPU, issue 46); the binding budget's is fast
def test_a_slack_budget_is_reported_and_its_peak_is_the_least_that_lands():
    budget = LEAST + 2.0
    r = solve_min_peak_force(-3, depth_max=budget)
    assert not r.budget_active and not r.unverified_reasons()
    assert r.depth_max - r.depth == pytest.approx(0.45258399226, abs=1e-9)
    assert r.peak == pytest.approx(1.12038804667, abs=1e-9)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["budget_active"] is False and d["budget_slack"] == pytest.approx(0.452583992, 1e-8)
    assert dict(r.rows())["depth budget"].startswith("slack")
    # independently: the two-phase landing with u_max just above P lands near this depth,
    # 0.45 short of the budget (at P itself the arrest is at the edge of the force limit)
    above = solve_two_phase(-3, PAPER_ROBOT.replace(u_max=r.peak * (1 + 1e-6)), replay=False)
    assert above.depth == pytest.approx(r.depth, abs=1e-4) and above.depth < budget - 0.45


@pytest.mark.slow  # proving a landing infeasible takes Ipopt ~9 s of CPU
def test_with_a_slack_budget_no_smaller_force_limit_lands():
    from softlanding.errors import InfeasibleLandingError

    r = solve_min_peak_force(-3, depth_max=LEAST + 2.0)
    at_p = solve_two_phase(-3, PAPER_ROBOT.replace(u_max=r.peak * (1 + 1e-12)), replay=False)
    assert at_p.depth == pytest.approx(r.depth, abs=1e-9)
    with pytest.raises(InfeasibleLandingError):
        solve_two_phase(-3, PAPER_ROBOT.replace(u_max=r.peak * (1 - 1e-4)), replay=False)


def test_a_binding_budget_is_reported_active():
    r = solve_min_peak_force(-3, depth_max=LEAST + 0.5, refine=False)
    assert r.budget_active and r.to_dict()["budget_active"] is True
    assert abs(r.to_dict()["budget_slack"]) < 1e-7
    assert dict(r.rows())["depth budget"].startswith("active")
