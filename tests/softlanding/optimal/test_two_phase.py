"""The full landing as a two-phase problem (softlanding.optimal.two_phase): the arrest optimised
reduces to the paper's; the exact simulator agrees; a second yielding step never helps."""

import time

import numpy as np
import pytest

from ocp import InfeasibleError, SolveError
from softlanding import PAPER_ROBOT, Impact, Robot
from softlanding.errors import InfeasibleLandingError
from softlanding.model.ground import DragGround
from softlanding.optimal.landing import solve_landing
from softlanding.optimal.phase_schedule import arc_laws
from softlanding.optimal.two_phase import solve_two_phase, sweep_two_phase, two_step_check


@pytest.fixture(scope="module")
def sweep():  # 41 landings, 2.3 s CPU: its tests are in the second test command (issue 46)
    v0 = np.linspace(-0.5, -10.0, 41)
    t0 = time.perf_counter()
    rows = sweep_two_phase(v0, PAPER_ROBOT)
    return rows, time.perf_counter() - t0


@pytest.mark.slow
def test_two_phase_never_worse_than_the_paper_and_equal_to_it(sweep):
    rows, elapsed = sweep
    assert len(rows) == 41
    for r in rows:
        assert r.depth <= r.paper_depth + 1e-9  # a relaxation of the paper's problem
        assert r.depth == pytest.approx(r.paper_depth, abs=1e-9)  # and it is tight
    assert elapsed < 60


@pytest.mark.slow
def test_every_landing_of_the_sweep_is_refined_and_replayed_exactly(sweep):
    for r in sweep[0]:
        assert r.unverified_reasons() == [], (r.impact.v0, r.unverified_reasons())
        assert r.replay_difference <= 1e-9
        assert r.arcs == [["max", "min"], ["boundary"]]


@pytest.mark.slow
def test_the_optimal_arrest_is_the_constant_crater_capacity(sweep):
    for r in sweep[0]:
        lo, hi = r.arrest_force_range
        assert hi - lo <= 1e-12 * max(1.0, hi)
        # the support force 1/(1+r_m) + u equals the crater depth: u = depth - m_f
        assert r.arrest_force == pytest.approx(r.depth - PAPER_ROBOT.foot_mass, abs=1e-10)
        # ... which is the paper's u_b with its arrest condition active
        law = [a for a in arc_laws(r.refined) if a.phase == 1]
        assert len(law) == 1 and law[0].constant == pytest.approx(r.arrest_force, abs=1e-12)


def test_certified_across_both_phases():
    r = solve_two_phase(-3.0)
    c = r.certify()
    assert c.verdict == "bang-bang certified", c.reasons
    assert max(c.junction_gaps) < 1e-9
    assert r.unverified_reasons(c) == []


def test_matches_the_paper_with_another_robot():
    robot = Robot(r_m=3.0, s=12.0, u_max=5.0)
    r = solve_two_phase(-4.0, robot)
    assert r.depth == pytest.approx(solve_landing(-4.0, robot).depth, abs=1e-9)
    assert r.unverified_reasons() == []


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_a_second_yielding_step_does_not_lower_the_depth():
    c = two_step_check(-1.0)
    assert c.collapsed
    # the four-phase transcription can only be worse by its grid error, never better
    assert c.gain <= 1e-9
    assert c.gain > -1e-4
    assert any(s["start"] == "collapsed" for s in c.starts)


def test_infeasible_request_names_the_condition():
    with pytest.raises(InfeasibleLandingError, match="u_max"):
        solve_two_phase(Impact(-10.0), Robot(r_m=5, s=20, u_max=0.5))


@pytest.mark.slow  # four relaxed solves (1.7 s); the CLI's twin in test_phased_cli is fast
def test_infeasible_arrest_is_named():
    with pytest.raises(InfeasibleLandingError, match="u_b <= u_max cannot be met"):
        solve_two_phase(Impact(-10.0), Robot(r_m=5, s=20, u_max=2.0))


@pytest.mark.parametrize("error", [SolveError, InfeasibleError])
def test_a_failure_at_the_static_depth_says_no_two_phase_landing_stops_shallower(
        monkeypatch, error):
    # (by hand: --variant two-phase on a drag ground of stiffness 0.5 at v0 = -3 ends in
    # Ipopt's iteration limit after 30 s, the last iterate badly scaled)
    import softlanding.optimal.two_phase as tp

    def fails(*a, **k):
        raise error("Maximum_Iterations_Exceeded", None, "Ipopt failed: it stopped")

    monkeypatch.setattr(tp, "solve_phased", fails)
    ground = DragGround(1.0, 0.5)
    at = solve_landing(-1, PAPER_ROBOT, ground, replay=False)  # stops at W/K = 2
    with pytest.raises(error) as info:
        solve_two_phase(-1, PAPER_ROBOT, ground, paper=at)
    assert info.value.status == "Maximum_Iterations_Exceeded"
    assert str(info.value).startswith("Ipopt failed: it stopped; the single-phase landing "
                                      "already stops at the static depth W/K = 2,")
    with pytest.raises(error) as info:  # elsewhere: Ipopt's word only
        solve_two_phase(-1, PAPER_ROBOT, paper=solve_landing(-1, replay=False))
    assert str(info.value) == "Ipopt failed: it stopped"


def test_json_dict_has_the_figures():
    d = solve_two_phase(-2.0).to_dict()
    for k in ("depth", "paper_depth", "arrest_force", "arcs", "replay", "refined"):
        assert k in d
