"""Impedance gains tuned for the worst case over several grounds (issue 25: unknown ground)."""

import json

import numpy as np
import pytest

from softlanding import PAPER_ROBOT as R
from softlanding import Impact, Impedance, ParameterError, simulate, simulate_batch
from softlanding.model.ground import LINEAR_GROUND, DragGround, LinearGround
from softlanding.studies.impedance import optimize_impedance

V0, GRID = -10.0, 41
SOFT, STIFF = LinearGround(0.5), LinearGround(2.0)


def feasible(res):
    return bool(res.rest_proven and res.stroke_min >= 0.0 and res.stroke_max <= R.s)


@pytest.fixture(scope="module")
def optima():
    """At v0 = -10 the soft ground's optimum leaves the stroke on the stiff ground and the stiff
    ground's is deep on the soft one: the worst-case gains are neither."""
    soft = optimize_impedance(V0, R, SOFT, grid=GRID)
    stiff = optimize_impedance(V0, R, STIFF, grid=GRID)
    worst = optimize_impedance(V0, R, [SOFT, STIFF], grid=GRID)
    return soft, stiff, worst


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_one_ground_in_a_sequence_is_that_ground_bitwise(optima):
    soft = optima[0]
    for seq in ([SOFT], (SOFT,)):
        again = optimize_impedance(V0, R, seq, grid=GRID)
        assert again.to_dict() == soft.to_dict()
        assert (again.k_p, again.k_d, again.value, again.evaluations) == \
            (soft.k_p, soft.k_d, soft.value, soft.evaluations)
    assert soft.grounds == (SOFT,) and soft.worst == (0,) and soft.ground == SOFT
    assert soft.ground_depths == (soft.depth,) and soft.ground_values == (soft.value,)


def test_single_ground_result_is_unchanged(paper_impedance_optimum):
    """Recorded when the boundary's bracket was closed by Chandrupatla's method on the stroke
    margin (before: halving, 22208 landings, k_p = 0.13598202189472736, k_d = 0.2577415,
    depth 1.7281126525126347, 2e-14 deeper; before that, rounds of 32 points, 41822
    landings: the optimum is that flat along the stroke limit): the single ground path is
    the same computation as the one-ground sequence's (``optimize_impedance(-3.0, R)``, the
    session's)."""
    o = paper_impedance_optimum(-3.0)  # (R is the paper's robot)
    assert o.evaluations == 18930
    assert (o.k_p, o.k_d) == pytest.approx((0.13598202294788067, 0.257741497), rel=1e-12)
    assert o.depth == pytest.approx(1.728112652512615, rel=1e-12)
    assert 0.0 <= o.stroke_min <= 1e-13  # on the stroke limit, feasible


@pytest.mark.slow  # reads the three optimisations (3.9 s CPU, issue 46)
def test_worst_case_lies_between_the_single_ground_optima_and_their_cross_values(optima):
    soft, stiff, worst = optima
    assert worst.value >= soft.value and worst.value >= stiff.value
    crossed = []
    for o in (soft, stiff):
        runs = [simulate(R, Impact(V0), Impedance(o.k_p, o.k_d), g) for g in (SOFT, STIFF)]
        if all(feasible(r) for r in runs):
            crossed.append(max(r.depth for r in runs))
    assert crossed  # the stiff ground's gains are feasible on both (the soft one's are not)
    assert worst.value <= min(crossed)
    assert (worst.k_p, worst.k_d) not in {(soft.k_p, soft.k_d), (stiff.k_p, stiff.k_d)}


@pytest.mark.slow  # reads the three optimisations (3.9 s CPU, issue 46)
def test_worst_case_gains_are_feasible_on_every_ground_and_described(optima):
    worst = optima[2]
    runs = [simulate(R, Impact(V0), worst.controller, g) for g in (SOFT, STIFF)]
    assert all(feasible(r) for r in runs)
    assert worst.grounds == (SOFT, STIFF)
    assert worst.ground_depths == tuple(r.depth for r in runs)
    assert worst.value == pytest.approx(max(worst.ground_values), rel=1e-12)
    assert worst.worst[0] == int(np.argmax(worst.ground_depths))
    assert worst.ground == worst.grounds[worst.worst[0]] and worst.depth == max(worst.ground_depths)
    assert worst.on_stroke_boundary and min(worst.ground_margins) <= 1e-6
    d = json.loads(json.dumps(worst.to_dict()))
    assert d["grounds"] == [SOFT.to_dict(), STIFF.to_dict()] and d["worst"] == list(worst.worst)
    assert d["ground"] == d["grounds"][d["worst"][0]] and len(d["ground_depths"]) == 2


@pytest.mark.slow  # ~13 s: in the second test command
def test_no_point_of_a_fine_grid_beats_the_worst_case_optimum(optima):
    """Brute force: the worst case over both grounds on a 201 x 201 grid (10x finer than the
    starting grid); the refined optimum is at least as good as every feasible point."""
    worst = optima[2]
    g = np.linspace(0.0, 1.0, 201)
    J = np.full((g.size, g.size), -np.inf)
    for ground in (SOFT, STIFF):
        b = simulate_batch(R, V0, g[:, None], g[None, :], ground)
        J = np.maximum(J, np.where(b.strictly_feasible, b.depth, np.inf))
    assert np.isfinite(J).any()
    assert worst.value <= J.min()


@pytest.mark.parametrize("bad, match", [
    ([], "empty sequence of grounds"),
    ((), "empty sequence of grounds"),
    ([LINEAR_GROUND, "drag"], "item 1 of the sequence must be a Ground, got str"),
    ([LINEAR_GROUND, DragGround(0.2).to_dict()], "item 1 .* got dict"),
    ("linear", "must be a Ground or a non-empty list or tuple of Grounds, got str"),
    ({LINEAR_GROUND}, "got set"),
    (1.0, "got float"),
])
def test_bad_grounds_are_parameter_errors(bad, match):
    with pytest.raises(ParameterError, match=match) as e:
        optimize_impedance(-3.0, R, bad, grid=3)
    assert e.value.parameter == "ground"


def _ground_options(*args):
    import argparse

    from softlanding.cli.ground import ground_args, grounds_of

    p = argparse.ArgumentParser()
    ground_args(p, several=True)
    return grounds_of(p.parse_args(list(args)))


def test_cli_ground_lists_name_every_combination():
    assert _ground_options() == LINEAR_GROUND
    assert _ground_options("--stiffness", "0.5") == LinearGround(0.5)  # one ground, as before
    assert _ground_options("--stiffness", "0.5,2") == [SOFT, STIFF]
    assert _ground_options("--ground", "drag", "--stiffness", "0.5,1", "--cd", "0,0.2") == [
        DragGround(0.0, 0.5), DragGround(0.2, 0.5), DragGround(0.0, 1.0), DragGround(0.2, 1.0)]


@pytest.mark.slow  # ~13 s: in the second test command
def test_cli_impedance_worst_case_json(cli, optima):
    code, out, err = cli("impedance", "--v0", V0, "--umax", R.u_max, "--grid", GRID,
                         "--stiffness", "0.5,2", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d == json.loads(json.dumps(optima[2].to_dict()))  # the API's worst-case optimum
    code, out, err = cli("impedance", "--v0", V0, "--umax", R.u_max, "--grid", GRID,
                         "--stiffness", "0.5,2")
    assert code == 0, err
    assert "worst ground(s)" in out and "depth on linear, stiffness = 2" in out


@pytest.mark.parametrize("args, match", [
    (["--stiffness", "0.5,x"], "comma-separated numbers"),
    (["--stiffness", "0.5,,1"], "comma-separated numbers"),
    (["--cd", "nan"], "comma-separated numbers"),
    (["--stiffness", "0.5,-1"], "stiffness"),
    (["--cd", "0,1"], "--cd does not apply to --ground linear"),
    (["--ground", "drag", "--stiffness", "1,2"], "needs the drag number --cd"),
])
def test_cli_bad_ground_lists_are_one_line_errors(cli, args, match):
    code, out, err = cli("impedance", "--v0", "-3", "--grid", "3", *args)
    assert code == 2 and "Traceback" not in err
    assert match in err and len(err.strip().splitlines()) == 1


def test_cli_a_ground_named_twice_is_refused(cli):
    code, _, err = cli("impedance", "--v0", "-3", "--stiffness", "1,1")
    assert code == 2 and "stiffness: lists a value twice" in err and err.count("\n") == 1



@pytest.mark.slow  # two worst-case searches with a drag ground (3 s CPU, issue 46)
def test_a_ground_is_skipped_where_the_gains_already_fail_in_any_order(monkeypatch):
    """A further ground is simulated only at gains feasible on the grounds before it (inf on
    one ground is inf in the worst case): the grounds in either order give the same optimum
    bitwise (each order skips other landings), ``worst`` names the grounds as given, and
    ``evaluations`` counts the landings the simulator ran, fewer than every ground at every
    point."""
    import softlanding.studies.impedance as imp

    ran, real = [], imp.simulate_batch

    def counting(robot, v0, kp, kd, ground, energy=False):
        out = real(robot, v0, kp, kd, ground, energy=energy)
        ran.append((ground, out.depth.size, int(np.isfinite(out.depth).sum())))
        return out

    monkeypatch.setattr(imp, "simulate_batch", counting)
    drag = DragGround(c_d=1.0, stiffness=2.0)
    a = optimize_impedance(-3.0, R, [SOFT, drag], grid=11)
    n_a, on_soft = sum(n for _, n, _ in ran), sum(n for g, n, _ in ran if g == SOFT)
    ran.clear()
    b = optimize_impedance(-3.0, R, [drag, SOFT], grid=11)
    assert (a.k_p, a.k_d, a.value) == (b.k_p, b.k_d, b.value)
    assert a.worst == tuple(1 - i for i in b.worst) and a.grounds == b.grounds[::-1]
    assert a.evaluations == n_a and b.evaluations == sum(n for _, n, _ in ran)
    # the affine ground runs first and everywhere; the drag ground only where it was feasible
    assert ran[0][0] == SOFT and n_a == b.evaluations
    assert n_a - on_soft < on_soft
