"""`softlanding solve --variant ...` and `softlanding hop`: JSON, tables, figures, errors."""

import json

import pytest


def test_two_phase_json(cli):
    code, out, _ = cli("solve", "--v0", "-3", "--variant", "two-phase", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["verified"] is True and d["variant"] == "two-phase"
    assert d["depth"] == pytest.approx(1.516295632282, abs=1e-9)
    assert d["depth"] == pytest.approx(d["paper_depth"], abs=1e-9)
    assert d["replay"]["difference"] < 1e-9


def test_two_phase_table_pmp_and_plot(cli, tmp_path):
    png = tmp_path / "two.png"
    code, out, _ = cli("solve", "--v0", "-2", "--variant", "two-phase", "--pmp", "--plot", png)
    assert code == 0
    assert "bang-bang certified" in out and "arrest force" in out
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_two_steps(cli):
    code, out, _ = cli("solve", "--v0", "-1", "--variant", "two-phase", "--steps", "2",
                       "--json")
    d = json.loads(out)
    assert code == 0 and d["collapsed"] is True and d["gain"] <= 1e-9


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_leg_extension_fixed_and_free(cli):
    code, out, _ = cli("solve", "--v0", "-1", "--variant", "leg-extension", "--extension",
                       "10", "--json")
    d = json.loads(out)
    assert code == 0 and d["depth"] == pytest.approx(d["paper_depth"], abs=1e-9)
    code, out, _ = cli("solve", "--v0", "-1", "--variant", "leg-extension", "--json")
    d = json.loads(out)
    assert code == 0 and d["gain"] > 0 and d["extension"] > 10


@pytest.mark.slow  # reads the session's hop (4.6 s CPU, issue 46)
def test_hop_json_and_plot(cli, tmp_path, monkeypatch, grid_hop):
    # the CLI's rendering of a one-grid cycle (the solve is the shared fixture's; the
    # command end to end, Ipopt's starts and grids included, is the hybrid guide's
    # `softlanding hop --v0 -3 --leg all` and `--eta 0.9`, run by tests/test_docs_commands.py)
    import softlanding.optimal.hopping as hopping

    def solve_hop(impact, robot, eta, *, doublings):
        assert (impact.v0, eta, doublings) == (-2.0, 0.0, 0)
        return grid_hop

    monkeypatch.setattr(hopping, "solve_hop", solve_hop)
    png = tmp_path / "hop.png"
    code, out, _ = cli("hop", "--v0", "-2", "--doublings", "0", "--json", "--plot", png,
                       "--pmp")
    _check_hop_json(code, out, png)


@pytest.mark.slow  # reads the session's hop (4.6 s CPU, issue 46)
def test_an_impedance_hop_prints_no_optimiser_figure(cli, monkeypatch, grid_hop):
    # an impedance cycle has no optimiser's energy (NaN): its row is left out, not "nan"
    import copy
    import math

    import softlanding.optimal.hopping as hopping

    cycle = copy.copy(grid_hop)
    cycle.energy_transcribed = math.nan
    monkeypatch.setattr(hopping, "best_impedance_hop", lambda *a, **k: cycle)
    code, out, _ = cli("hop", "--v0", "-2", "--leg", "impedance")
    assert code in (0, 1) and "energy per cycle" in out
    assert "optimiser's slack" not in out and "nan" not in out.lower(), out
    monkeypatch.setattr(hopping, "best_impedance_hop", lambda *a, **k: grid_hop)
    assert "optimiser's slack" in cli("hop", "--v0", "-2", "--leg", "impedance")[1]


def _check_hop_json(code, out, png):
    # issue 34: one grid's energy is a discretised value, not a verified optimum: exit 1
    assert code == 1
    d = json.loads(out)
    assert d["verified"] is False and d["optimum"] == "discretised" and d["leg"] == "free"
    assert d["cycles"]["free"]["replay_verified"] is True  # its replay closes all the same
    assert "discretised" in d["unverified_reasons"]["free"][0]
    # issue 47, defect 11: a cycle said verified: false with unverified_reasons: []
    for c in d["cycles"].values():
        assert c["verified"] is (not c["unverified_reasons"]), c["unverified_reasons"]
    assert "discretised" in d["cycles"]["free"]["unverified_reasons"][0]
    assert d["energy"] > 0 and d["energy"] == d["cycles"]["free"]["energy"]
    assert d["cycles"]["free"]["net_work"] == pytest.approx(
        d["cycles"]["free"]["ground_loss"], rel=1e-6)
    assert png.stat().st_size > 1000
    # issue 32: no certificate, and one line naming why (the structure ocp detects)
    pmp = d["pmp"]["free"]
    assert pmp["verdict"] is None and "not bang-bang" in pmp["why_none"], pmp


def test_bad_input_exit_2(cli):
    assert cli("hop", "--v0", "-1", "--eta", "1.5")[0] == 2
    assert cli("solve", "--v0", "-1", "--variant", "leg-extension", "--extension", "30")[0] == 2
    assert cli("solve", "--v0", "-1", "--variant", "nope")[0] == 2


def test_infeasible_exit_1(cli, monkeypatch, arrest_infeasible):
    # the paper's infeasible solve is the session's (test_landing checks it); the two-phase
    # variant's wrapping of it and the CLI's exit code are what is tested here
    import softlanding.optimal.two_phase as two_phase
    from softlanding import PAPER_ROBOT
    from softlanding.model.ground import LINEAR_GROUND

    def solve_landing(impact, robot, ground):  # the session's request, nothing else
        assert impact.v0 == -10.0 and robot == PAPER_ROBOT.replace(u_max=2.0)
        assert ground == LINEAR_GROUND
        raise arrest_infeasible

    monkeypatch.setattr(two_phase, "solve_landing", solve_landing)
    code, _, err = cli("solve", "--v0", "-10", "--umax", "2", "--variant", "two-phase")
    assert code == 1 and "u_b <= u_max" in err and "no two-phase landing either" in err
