"""A ground K times as stiff (f = K d) against the paper's ground in other units.

Independent check: with k_g' = K k_g the paper's scales become x_s' = x_s / K and
tau_s' = tau_s / sqrt(K), so a landing on the K ground of robot (r_m, s, u_max, l0) at v0 is
the landing on the paper's ground of robot (r_m, K s, u_max, K l0) at sqrt(K) v0, with gains
k_p' = k_p / K, k_d' = k_d / sqrt(K); its depth is K times as large and its times sqrt(K)
times as long.
"""

import math

import pytest

from softlanding import PAPER_ROBOT, simulate, solve_landing
from softlanding.cli import main
from softlanding.errors import ParameterError
from softlanding.model import Impedance, Rigid
from softlanding.model.ground import LINEAR_GROUND, DragGround, LinearGround


def _scaled(robot, k):
    return robot.replace(s=robot.s * k, l0=robot.rest_length * k)


@pytest.mark.parametrize("k", [0.5, 2.0])
def test_optimal_landing_on_a_stiffer_ground_is_the_paper_landing_rescaled(k):
    res = solve_landing(-3, ground=LinearGround(k))
    ref = solve_landing(-3 * math.sqrt(k), robot=_scaled(PAPER_ROBOT, k))
    assert res.unverified_reasons() == [] and res.arrest_active
    assert res.depth == pytest.approx(ref.depth / k, rel=1e-12)
    assert res.switch_times[0] == pytest.approx(ref.switch_times[0] / math.sqrt(k), rel=1e-9)


@pytest.mark.parametrize("k", [0.5, 2.0])
@pytest.mark.parametrize("gains", [(0.2, 0.3), (0.5, 0.05)])
def test_simulated_landing_on_a_stiffer_ground_is_the_paper_landing_rescaled(k, gains):
    robot = PAPER_ROBOT.without_force_limit()
    a = simulate(robot, -3, Impedance(*gains), LinearGround(k))
    b = simulate(_scaled(robot, k), -3 * math.sqrt(k),
                 Impedance(gains[0] / k, gains[1] / math.sqrt(k)))
    assert a.status == b.status and a.steps == b.steps
    assert a.depth == pytest.approx(b.depth / k, rel=1e-9)


def test_drag_on_a_stiffer_ground_adds_the_factor_to_the_spring_only():
    g = DragGround(0.2, 2.0)
    assert g.yield_force(1.5, -2.0) == pytest.approx(2.0 * 1.5 + 0.2 * 4.0)
    assert g.yield_force(1.5, 0.0) == pytest.approx(3.0)  # the crater's hold
    res = simulate(PAPER_ROBOT.without_force_limit(), -3, Rigid(), g)
    assert res.rest_proven and res.depth < simulate(
        PAPER_ROBOT.without_force_limit(), -3, Rigid(), DragGround(0.2)).depth


def test_the_paper_ground_is_unchanged():
    assert LinearGround() == LINEAR_GROUND and LinearGround(1.0).to_dict() == {"model": "linear"}
    assert LinearGround(2.0).to_dict() == {"model": "linear", "stiffness": 2.0}
    with pytest.raises(ParameterError, match="stiffness"):
        LinearGround(0.0)


def test_cli_takes_the_stiffness_where_it_takes_a_ground(capsys):
    assert main(["solve", "--v0", "-3", "--stiffness", "2", "--json"]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["ground"] == {"model": "linear", "stiffness": 2.0}
    assert d["depth"] == pytest.approx(solve_landing(-3, ground=LinearGround(2.0)).depth)
    assert main(["simulate", "--v0", "-3", "--rigid", "--ground", "added-mass",
                 "--stiffness", "2"]) == 2
