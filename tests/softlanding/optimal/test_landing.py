"""The paper's soft-landing OCP: refinement, simulator replay, the paper's claims."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from softlanding import PAPER_ROBOT, ParameterError, Robot
from softlanding.model.controllers import Rigid
from softlanding.model.ground import DragGround
from softlanding.model.robot import Impact
from softlanding.optimal.landing import (
    InfeasibleLandingError,
    landing_transcription,
    rigid_guess,
    solve_landing,
    sweep_landing,
)
from softlanding.simulation.simulator import simulate, stroke


def rigid(v0):
    return 1 + math.sqrt(1 + v0 * v0)


@pytest.mark.parametrize("v0", [0.0, -0.5, -1.0, -3.0, -6.0, -10.0])
def test_refined_depth_matches_exact_simulator_replay(v0):
    r = solve_landing(v0)
    assert r.refined is not None and r.arcs == ["max", "min"]
    assert r.arrest_active
    rp = r.replay
    assert rp.rest_proven and rp.feasible
    assert abs(rp.depth - r.depth) <= 1e-9
    # the body ends at rest at the stroke's lower end, inside the stroke
    t_end = r.schedule().times[-1]  # end of the arrest phase: then the weight is held
    tail = rp.trajectory(t_end=t_end + 1.0, n=200)
    assert abs(tail.x[-1, 1]) < 1e-9
    assert -1e-9 <= stroke(tail)[-1] <= 20.0
    # the transcription is within its discretisation error of the exact answer
    assert r.depth <= r.depth_transcribed + 1e-12
    assert abs(r.depth - r.depth_transcribed) < 1e-4


@pytest.fixture(scope="module")
def sweep():
    v = np.r_[np.linspace(-0.01, -0.2, 3), np.linspace(-0.5, -10.0, 12)]
    return v, sweep_landing(v)


def test_bang_bang_at_most_half_the_rigid_depth(sweep):
    v, res = sweep
    for v0, r in zip(v, res, strict=True):
        if v0 <= -0.2:
            assert r.depth <= 0.5 * rigid(v0)


def test_depth_decreases_toward_one_and_ratio_toward_half(sweep):
    v, res = sweep
    depth = np.array([r.depth for r in res])
    assert np.all(np.diff(depth) > 0)  # deeper as |v0| grows
    assert 1.0 < depth[0] < 1.002
    ratio = depth[0] / rigid(v[0])
    assert abs(ratio - 0.5) < 2e-3


@pytest.mark.parametrize("v0", [0.0, -0.5, -3.0, -10.0])
def test_rigid_guess_is_the_rigid_landing_in_closed_form(v0):
    """The guess's locked leg on the paper's spring (unit mass, stiffness and weight): depth
    ``1 - cos t + |v0| sin t``, the foot stopped at ``T = pi - atan|v0|``."""
    tr = landing_transcription(100)
    w = rigid_guess(tr, PAPER_ROBOT, Impact(v0))
    T, X = w[tr.layout.iT], w[tr.layout.iX].reshape(-1, 4)
    assert T == pytest.approx(math.pi - math.atan(abs(v0)), rel=1e-10)
    t = np.linspace(0.0, T, X.shape[0])
    assert np.max(np.abs(-X[:, 2] - (1 - np.cos(t) + abs(v0) * np.sin(t)))) < 1e-9
    assert -X[-1, 2] == pytest.approx(rigid(v0), rel=1e-10) and abs(X[-1, 3]) < 1e-9
    assert np.ptp(X[:, 0] - X[:, 2]) < 1e-9  # the leg locked


def test_rigid_guess_on_a_drag_ground_is_the_exact_simulators_rigid_landing():
    ground, robot, impact = DragGround(0.5), PAPER_ROBOT, Impact(-3.0)
    tr = landing_transcription(100, ground=ground)
    w = rigid_guess(tr, robot, impact, ground)
    T, X = w[tr.layout.iT], w[tr.layout.iX].reshape(-1, 4)
    res = simulate(robot.without_force_limit(), impact, Rigid(), ground)
    assert T == pytest.approx(res.t_first_stop, rel=1e-9)
    traj = res.trajectory(t_end=T, n=X.shape[0])
    t = np.linspace(0.0, T, X.shape[0])
    exact = np.column_stack([np.interp(t, traj.t, traj.x[:, i]) for i in range(4)])
    assert np.max(np.abs(X - exact)) < 1e-7


def test_a_first_sweep_loads_no_simulator_kernel():
    """Without a replay, a process's first landings use no numba kernel (loading one costs
    about 0.4 s CPU, as much as the rest of a 41-velocity sweep)."""
    code = ("import sys\n"
            "from numba.core.dispatcher import Dispatcher\n"
            "from softlanding.optimal.landing import sweep_landing\n"
            "sweep_landing([0.0, -1.0])\n"
            "print([f'{m}.{n}' for m, mod in list(sys.modules.items()) if m.startswith("
            "'softlanding') for n, f in vars(mod).items() if isinstance(f, Dispatcher) "
            "and f.signatures])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120)
    assert out.stdout.strip() == "[]"


def test_a_converged_warm_start_computes_no_cold_guess(monkeypatch):
    from softlanding.optimal.landing import PaperLanding

    calls = []
    original = PaperLanding.guess
    monkeypatch.setattr(PaperLanding, "guess", lambda self: calls.append(1) or original(self))
    res = sweep_landing([-1.0, -1.5, -2.0], refine=False)
    assert [r.iterations < 20 for r in res[1:]] == [True, True]  # warm-started
    assert len(calls) == 1  # the first landing's only


def test_resolving_does_not_rebuild_the_nlp():
    tr = landing_transcription(100)
    before = tr.n_builds
    solve_landing(-2.0, replay=False)
    solve_landing(-4.0, Robot(r_m=3.0, s=15.0, u_max=7.0), replay=False)
    assert landing_transcription(100) is tr
    assert tr.n_builds == before == 1


def test_a_ground_family_shares_one_nlp():
    """Linear grounds other than the paper's, and drag grounds, are families whose numbers
    are NLP parameters: one transcription (and its switching NLPs) serves them all."""
    from softlanding.model.ground import LinearGround
    from softlanding.optimal.landing_problem import ground_family, ground_values

    assert ground_family(LinearGround()) == () and ground_values(LinearGround()) == {}
    assert ground_family(LinearGround(2.0)) == ("stiffness",)
    assert ground_values(DragGround(0.5, stiffness=2.0)) == {"stiffness": 2.0, "c_d": 0.5}
    assert ground_family(DragGround(0.0)) == ("stiffness",)  # a spring: affine, exact arcs
    tr = landing_transcription(100, ground=LinearGround(0.5))
    assert landing_transcription(100, ground=LinearGround(2.0)) is tr
    assert landing_transcription(100) is not tr
    assert landing_transcription(100, ground=DragGround(1.0)) is \
        landing_transcription(100, ground=DragGround(0.2, stiffness=1.5))
    one = solve_landing(-3.0, PAPER_ROBOT, DragGround(0.5, stiffness=0.75), replay=False)
    other = solve_landing(-3.0, PAPER_ROBOT, DragGround(0.2, stiffness=2.0), replay=False)
    assert other.refined.problem is one.refined.problem  # the drag family's
    # a drag ground without drag is a spring (the CLI's --ground drag --cd 0): exact arcs, and
    # a boundary arc's law affine, so its schedule replays exactly (in the drag family, with
    # c_d a symbol, the replay left a short stroke by 6.7e-4)
    short = Robot(r_m=5.0, s=1.0, u_max=8.2)
    spring = solve_landing(-3.0, short, DragGround(0.0))
    assert "boundary" in spring.arcs and not spring.unverified_reasons()
    assert spring.refined.exact and spring.replay_difference < 1e-12


@pytest.mark.slow  # two more NLPs built (a custom law's own): 4 s
def test_a_family_lands_as_its_own_law():
    """A family's landing agrees with the same law as a CustomGround, whose numbers are
    constants of its own NLP (a second build, an independent check)."""
    from softlanding.model.ground import CustomGround, LinearGround

    for ground, law in ((LinearGround(2.0), lambda d, v: 2.0 * d),
                        (DragGround(0.5, stiffness=0.75),
                         lambda d, v: 0.75 * d + 0.5 * v ** 2)):
        fam = solve_landing(-3.0, PAPER_ROBOT, ground)
        own = solve_landing(-3.0, PAPER_ROBOT, CustomGround(f"own {ground.to_dict()}", law),
                            replay=False)
        assert not fam.unverified_reasons() and own.refined is not None
        assert fam.arcs == own.arcs
        assert fam.depth == pytest.approx(own.depth, rel=1e-10)
        assert fam.switch_times == pytest.approx(own.switch_times, rel=1e-8)
        assert fam.replay.depth == pytest.approx(fam.depth, rel=1e-9)


def test_the_static_depth_is_the_weight_over_the_craters_stiffness_where_it_has_one():
    # at rest the crater holds the robot's weight (1 in m_t g): f(d, 0) = K d >= 1
    import casadi as ca

    from softlanding.model.ground import AddedMassGround, CustomGround, LinearGround
    from softlanding.optimal.verification import static_depth

    assert static_depth(LinearGround(0.5)) == 2.0
    assert static_depth(DragGround(1.0, 4.0)) == 0.25
    assert static_depth(CustomGround("lin3", lambda d, v: 3 * d + 0.2 * v * v)) == \
        pytest.approx(1 / 3, rel=1e-15)  # a law whose hold is K d, whatever its drag
    assert math.isnan(static_depth(CustomGround("p", lambda d, v: ca.fmax(d, 0) ** 1.5)))
    # the grains' added mass moves only with the foot: at rest the hold is f(d, 0) still
    assert static_depth(AddedMassGround(0.5, 1.0, 1.0)) == 1.0
    assert static_depth(CustomGround("m", lambda d, v: 3 * d, mass=lambda d: 0.1 * d)) == \
        pytest.approx(1 / 3, rel=1e-15)


class _Replay:
    rest_proven = False


def test_the_static_depth_line_only_at_the_bound_and_its_replays_claim_only_with_one():
    from softlanding.optimal.verification import static_depth_reason

    at = static_depth_reason(2.0 - 2e-9, 2.0, -1e-9, 5 / 6, 5 / 6, _Replay())
    assert len(at) == 1 and "W/K = 2 (to 2.0e-09)" in at[0] and "never arrested" in at[0]
    assert static_depth_reason(2.0 + 3e-7, 2.0, -1e-9, 5 / 6, 5 / 6, _Replay()) == []
    assert static_depth_reason(2.0, math.nan, -1e-9, 5 / 6, 5 / 6, _Replay()) == []
    assert static_depth_reason(0.25 + 5e-8, 0.25, 0.0, 5 / 6, 5 / 6) != []  # (absolute tol)
    for v_b, replay in ((-1e-9, None), (0.0, _Replay())):  # no claim it cannot check
        assert "never arrested" not in static_depth_reason(2.0, 2.0, v_b, 5 / 6, 5 / 6,
                                                           replay)[0]


def test_extra_switches_change_depth_by_less_than_one_percent():
    base = solve_landing(-3.0, replay=False)
    more = solve_landing(-3.0, extra_arcs=2, replay=False)
    assert len(more.refined.kinds) == 4
    assert abs(more.depth - base.depth) <= 0.01 * base.depth


def test_infeasible_requests_name_the_condition(arrest_infeasible):
    with pytest.raises(InfeasibleLandingError, match="body weight"):
        solve_landing(-3.0, PAPER_ROBOT.replace(u_max=0.5), replay=False)
    # v0 = -10, u_max = 2: four relaxed solves name the condition (the session's one solve,
    # shared with the two-phase CLI's test; the CLI's twin in test_cli is the slow one)
    assert isinstance(arrest_infeasible, InfeasibleLandingError)
    assert "arrest force u_b <= u_max" in str(arrest_infeasible)


def test_only_the_diagnosis_solves_with_the_infeasible_problem_heuristics():
    # Ipopt's expect_infeasible_problem (restoration sooner) speeds up the relaxed problems
    # the diagnosis solves; the landing itself must keep Ipopt's default path
    from softlanding.optimal.landing_problem import ARREST, RELAXED_IPOPT, landing_transcription

    main = landing_transcription(10).ipopt_options
    relaxed = landing_transcription(10, omit=(ARREST,), expand=False).ipopt_options
    assert "expect_infeasible_problem" not in main
    assert relaxed.items() >= RELAXED_IPOPT.items() and relaxed["tol"] == main["tol"]


@pytest.mark.parametrize("kwargs,name", [({"v0": 1.0}, "v0"), ({"v0": -1, "u_max": -2}, "u_max"),
                                         ({"v0": -1, "s": math.nan}, "s")])
def test_bad_parameters(kwargs, name):
    with pytest.raises(ParameterError, match=name):
        v0 = kwargs.pop("v0")
        solve_landing(v0, PAPER_ROBOT.replace(**kwargs))


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_cli_solve_json_and_infeasible(tmp_path, cli):
    png = tmp_path / "bb.png"
    code, out, err = cli("solve", "--v0", "-3", "--json", "--plot", png)
    assert code == 0, err
    d = json.loads(out)
    for k in ("depth", "depth_transcribed", "T", "switch_times", "arcs", "u_b",
              "arrest_active", "status", "iterations", "solve_time_s"):
        assert k in d
    assert d["arcs"] == ["max", "min"] and len(d["switch_times"]) == 1
    assert d["replay"]["difference"] <= 1e-9
    assert png.stat().st_size > 10_000
    code, _, err = cli("solve", "--v0", "-10", "--umax", "2")
    assert code == 1  # well-posed but infeasible (2 is for bad input)
    assert "arrest force u_b <= u_max" in err and "Traceback" not in err
    assert err.count("\n") == 1


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_cli_compare_orders_the_three_legs(cli):
    code, out, err = cli("compare", "--n", "3", "--v0-min", "-8", "--grid", "41", "--json")
    assert code == 0, err
    rows = json.loads(out)["rows"]
    assert len(rows) == 3
    for r in rows:
        assert r["rigid"] == pytest.approx(rigid(r["v0"]))
        # bang-bang (|u| <= 8.2) beats the optimal impedance (peak force below 8.2 here),
        # which beats the rigid leg
        assert r["bang_bang"] < r["impedance"] < r["rigid"]
        assert r["impedance_u_peak"] < 8.2


def test_an_unverified_result_is_not_a_plain_success(cli, monkeypatch):
    """A refinement that fails leaves the transcribed answer: JSON says verified false with
    the reason, the table says so first, and the exit code is 1 unless accepted."""
    import softlanding.optimal.phase_solve as phase_solve
    from ocp import SolveError

    def fails(*a, **k):
        raise SolveError("Search_Direction_Becomes_Too_Small")

    # (the pipeline's one-phase refinement step, which the paper's landing runs)
    monkeypatch.setattr(phase_solve, "refine_switching", fails)
    code, out, _ = cli("solve", "--v0", "-3", "--json")
    d = json.loads(out)
    assert code == 1 and d["verified"] is False
    assert any("not refined" in r for r in d["unverified_reasons"])
    code, out, _ = cli("solve", "--v0", "-3", "--accept-unverified")
    assert code == 0 and out.splitlines()[0].startswith("verified") and "NO:" in out.splitlines()[0]
    code, out, _ = cli("solve-sweep", "--n", "2", "--v0-min", "-2", "--json")
    assert code == 1 and json.loads(out)["verified"] is False


@pytest.mark.parametrize("s,v0", [(0.5, -3.0), (1.0, -10.0), (2.0, -1.0), (5.0, -10.0)])
def test_short_strokes_refine_with_boundary_arcs_and_replay_exactly(s, v0):
    """At short strokes the stroke limit is held on an interval: the refinement has a
    boundary arc, and the exact simulator replays its state-feedback law to 1e-9."""
    r = solve_landing(v0, Robot(r_m=5.0, s=s, u_max=8.2))
    assert "boundary" in r.arcs
    assert not r.unverified_reasons(), r.unverified_reasons()
    assert r.replay.rest_proven and r.replay.feasible
    assert r.replay_difference <= 1e-9
    assert r.depth <= r.depth_transcribed + 1e-6  # the transcription relaxes between nodes


def test_feedback_schedule_generalises_force_schedule():
    from softlanding import FeedbackSchedule, ForceSchedule, Impact, simulate

    robot = Robot(5.0, 20.0)
    const = simulate(robot, Impact(-3.0), ForceSchedule((0.1, 0.3), (8.0, -8.0, 1.0)))
    rows = [[0, 0, 0, 0, 8.0], [0, 0, 0, 0, -8.0], [0, 0, 0, 0, 1.0]]
    same = simulate(robot, Impact(-3.0), FeedbackSchedule((0.1, 0.3), rows))
    assert (same.depth, same.T, same.stroke_min) == (const.depth, const.T, const.stroke_min)
    # a state-feedback piece (a spring on the leg) against an independent integration
    from scipy.integrate import solve_ivp

    k = 0.4
    law = FeedbackSchedule((), [[-k, 0, k, 0, k * 10.0]])  # u = -k (x_b - x_f - 10)
    r = simulate(robot, Impact(-1.0), law)

    def rhs(t, x):
        u = -k * (x[0] - x[2] - 10.0)
        return [x[1], -1 + 6 / 5 * u, x[3], -1 - 6 * (x[2] + u)]

    stop = lambda t, x: x[3]  # noqa: E731
    stop.terminal, stop.direction = True, 1
    ref = solve_ivp(rhs, (0, 20), [10.0, -1.0, 0.0, -1.0], events=stop, rtol=1e-12,
                    atol=1e-12, method="DOP853")
    assert r.t_first_stop == pytest.approx(ref.t_events[0][0], abs=1e-8)
    assert -r.trajectory(t_end=r.t_first_stop, n=3).state("x_f")[-1] == pytest.approx(
        -ref.y_events[0][0][2], abs=1e-8)
