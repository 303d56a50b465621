"""The landing OCP, its refinement, replay and PMP certificate on non-affine grounds; the
impedance layer and the CLI's ground options."""

import json

import pytest

from softlanding import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Impact
from softlanding.model.ground import DragGround
from softlanding.model.terrain import paper_rig_units, poppy_seed_added_mass, power_law_ground
from softlanding.optimal.landing import solve_landing
from softlanding.studies.impedance import optimize_impedance

GROUNDS = [DragGround(0.2), poppy_seed_added_mass(paper_rig_units())]


@pytest.mark.parametrize("ground", [  # the added-mass ground: 1.9 s CPU (issue 46)
    pytest.param(GROUNDS[0], id="drag"),
    pytest.param(GROUNDS[1], id="added-mass", marks=pytest.mark.slow)])
def test_refined_bang_bang_replays_and_certifies(ground):
    from ocp import certify

    r = solve_landing(Impact(-4.8), PAPER_ROBOT, ground)
    assert r.refined is not None and r.arcs == ["max", "min"]
    assert r.replay_difference < 1e-8
    assert r.arrest_active
    cert = certify(r.transcribed, r.refined)
    assert cert.verdict == "bang-bang certified", cert.reasons
    assert cert.source.startswith("refined")
    assert not r.unverified_reasons(cert)
    assert r.to_dict()["ground"]["model"] == ground.name


def test_drag_makes_the_bang_bang_landing_shallower():
    lin = solve_landing(Impact(-4.8), PAPER_ROBOT)
    drag = solve_landing(Impact(-4.8), PAPER_ROBOT, DragGround(0.2))
    assert drag.depth < lin.depth


def test_user_law_through_the_ocp():
    # n >= 2: for 1 < n < 2 the law's second derivative is unbounded at the surface, where
    # the transcription starts, and Ipopt's exact Hessian is not finite there
    r = solve_landing(Impact(-3), PAPER_ROBOT, power_law_ground(2.0))
    assert r.refined is not None and r.replay_difference < 1e-8


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_impedance_optimum_under_drag():
    o = optimize_impedance(Impact(-4.8), PAPER_IMPEDANCE_ROBOT, DragGround(0.2), grid=41)
    lin = optimize_impedance(Impact(-4.8), PAPER_IMPEDANCE_ROBOT, grid=41)
    assert o.depth < lin.depth and o.stroke_min >= 0
    assert o.to_dict()["ground"] == {"model": "drag", "c_d": 0.2}


def test_cli_ground_options(cli):
    code, out, _ = cli("simulate", "--v0", -4.8, "--kp", 0.5, "--kd", 1.5, "--ground", "drag",
                       "--cd", 0.2, "--json")
    d = json.loads(out)
    assert code == 0 and d["ground"] == {"model": "drag", "c_d": 0.2}
    assert abs(d["energy"]["E0"] - d["energy"]["ET"] - d["energy"]["ground"]
               - d["energy"]["drag"] - d["energy"]["grains"] - d["energy"]["actuator"]) < 1e-9
    for bad in (("--ground", "drag", "--cd", -0.1), ("--ground", "drag", "--cd", "inf"),
                ("--ground", "added-mass", "--pi-a", -1), ("--ground", "drag"),
                ("--cd", 0.3), ("--ground", "power", "--exponent", 0)):
        code, out, err = cli("simulate", "--v0", -1, "--rigid", *bad)
        assert code == 2 and err.count("\n") == 1, (bad, err)
    code, out, _ = cli("scale", "--preset", "paper", "--medium", "poppy-lp", "--json")
    d = json.loads(out)
    assert code == 0 and abs(d["rft"]["k_g_rft"] - 3371.4) < 0.1
    assert d["rft"]["k_g_paper"] == 4400.0
