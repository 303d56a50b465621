"""A researcher's smooth variant (docs/examples/min_energy.py): the least actuator energy
∫u² dt within a depth budget. Its force is continuous (interior arcs), so the pipeline
converges it on a refined collocation mesh and certifies it arc by arc; checked against
the closed form and against other discretisations."""

import importlib.util
import json
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from softlanding import PAPER_ROBOT

EXAMPLES = Path(__file__).resolve().parents[3] / "docs" / "examples"
V0 = -3.0


def closed_form(v0: float, r_m: float) -> tuple[float, float, float]:
    """Energy, rest time and depth of the budget-free optimum, derived here on their own.

    The body's law ``v_b' = -1 + a u`` (``a = (1 + r_m)/r_m``) in every ground mode takes
    it from ``v0`` to rest: ``a ∫u = |v0| + T``, so ``∫u² >= (|v0| + T)² / (a² T)``
    (Cauchy–Schwarz), least ``4 |v0| / a²`` at ``T = |v0|`` with ``u = 2/a``. Under that
    force the yielding foot (``d'' = 1 + (1 + r_m)(u - d)``, ``d'(0) = |v0|``) stops where
    ``(1 + r_m) D²/2 - (1 + (1 + r_m) u) D = v0²/2``.
    """
    a = (1 + r_m) / r_m
    u = 2 / a
    k, A = 1 + r_m, 1 + (1 + r_m) * u
    depth = (A + math.sqrt(A * A + k * v0 * v0)) / k
    return 4 * abs(v0) / a ** 2, abs(v0), depth


@pytest.fixture(scope="module")
def min_energy():
    spec = importlib.util.spec_from_file_location("min_energy", EXAMPLES / "min_energy.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["min_energy"] = mod  # dataclasses look their module up there
    spec.loader.exec_module(mod)
    yield mod
    del sys.modules["min_energy"]


@pytest.fixture(scope="module")
def slack(min_energy):
    return min_energy.solve_min_energy(V0, depth_max=5.0)


def test_a_slack_budget_gives_the_closed_form_verified_and_certified(slack):
    """The default run of a smooth optimum: no "switching times not refined"; the mesh
    converged with an error estimate; every arc certified (interior); verified."""
    energy, T, depth = closed_form(V0, PAPER_ROBOT.r_m)
    assert energy == pytest.approx(25 / 3, abs=1e-15)  # the case
    assert T == 3.0 and depth == pytest.approx((11 + math.sqrt(175)) / 6, abs=1e-15)
    assert slack.energy == pytest.approx(energy, abs=1e-8)
    assert slack.T == pytest.approx(T, abs=1e-7)
    assert slack.depth == pytest.approx(depth, abs=1e-7) and not slack.budget_active
    assert slack.smooth is not None and slack.smooth.mesh_converged
    assert slack.smooth.objective_error < 1e-6
    assert abs(slack.energy - energy) <= slack.smooth.objective_error  # not optimistic
    assert slack.smooth.convergence.startswith("converged (mesh, estimated error")
    cert = slack.certify()
    assert cert.verdict == "certified (interior)" and cert.certified
    assert slack.unverified_reasons(cert) == []
    assert slack.replay_difference < 1e-6
    rows = dict(slack.rows())
    assert rows["mesh"] == slack.smooth.convergence and "objective error estimate" in rows


def test_a_bang_bang_problem_is_not_routed_to_the_smooth_path(slack):
    """The route is chosen by the cost (curved in the force), not by a grid's look: the
    depth-optimal two-phase landing's transcription is never a smooth optimum."""
    from softlanding.optimal.smooth import convex_in_control
    from softlanding.optimal.two_phase_problem import two_phase_transcription

    assert convex_in_control(slack.transcribed)
    depth_optimal = SimpleNamespace(phases=[SimpleNamespace(problem=p) for p in
                                            two_phase_transcription().problem.phases])
    assert not convex_in_control(depth_optimal)


@pytest.mark.slow
def test_an_active_budget_converges_and_agrees_with_finer_discretisations(min_energy):
    """Budget binds: depth D; the energy falls as D loosens and stays above 25/3; a finer
    collocation mesh and multiple shooting on two grids agree within the estimate."""
    from ocp import Collocation

    r3 = min_energy.solve_min_energy(V0, depth_max=3.0)
    r35 = min_energy.solve_min_energy(V0, depth_max=3.5)
    for r, d in ((r3, 3.0), (r35, 3.5)):
        assert r.depth == pytest.approx(d, abs=1e-8) and r.budget_active
        assert r.unverified_reasons(r.certify()) == []
    assert 25 / 3 < r35.energy < r3.energy
    params = min_energy.MinEnergy(PAPER_ROBOT, r3.impact, r3.ground, 3.0, 0.0).parameters()
    fine = Collocation(r3.transcribed.transcription.problem, intervals=[200, 40])
    finer = fine.solve(params, guess=r3.transcribed.trajectory(400))
    assert abs(finer.objective - r3.energy) <= r3.smooth.objective_error
    assert abs(finer.objective - r3.energy) < 1e-7
    ms = min_energy.min_energy_transcription()
    j = [ms.solve(params).objective]
    from ocp import MultipleShooting
    j.append(MultipleShooting(ms.problem, nodes=[160, 80], integrator="rk4",
                              substeps=4).solve(params).objective)
    # first-order in h: the shooting grids close in on the converged energy
    assert abs(j[1] - r3.energy) < abs(j[0] - r3.energy) and abs(j[1] - r3.energy) < 3e-5


@pytest.mark.slow
def test_the_cli_runs_the_variant_from_its_file_with_the_same_verdict(cli, tmp_path,
                                                                      monkeypatch):
    """`solve --variant min_energy:VARIANT`, the budget from a TOML file: verified, exit 0,
    with and without --no-refine (the same numbers); --pmp prints every arc's rows."""
    monkeypatch.syspath_prepend(str(EXAMPLES))
    toml = tmp_path / "budget.toml"
    toml.write_text("depth_max = 3.0\n")
    runs = {}
    for extra in ([], ["--no-refine"]):
        code, out, err = cli("solve", "--variant", "min_energy:VARIANT", "--v0", V0,
                             "--config", toml, "--json", *extra)
        assert code == 0, err
        runs[bool(extra)] = json.loads(out)
    assert runs[False]["verified"] is runs[True]["verified"] is True
    assert runs[False]["energy"] == pytest.approx(runs[True]["energy"], abs=1e-12)
    assert runs[False]["smooth"]["mesh_converged"] is True
    assert runs[False]["smooth"]["objective_error"] < 1e-6
    code, out, err = cli("solve", "--variant", "min_energy:VARIANT", "--v0", V0,
                         "--config", toml, "--pmp")
    assert code == 0, err
    assert "certified (interior)" in out and "arc (yielding) interior" in out
    assert "stationarity |H_u|" in out and "switching times not refined" not in out
    code, out, err = cli("solve", "--variant", "min_energy:VARIANT", "--v0", V0,
                         "--config", toml, "--depth-max", "3")
    assert code == 2 and "not both" in err
    code, out, err = cli("solve", "--variant", "min_energy:VARIANT", "--v0", V0,
                         "--depth-max", "3", "--stroke-margin", "10")
    assert code == 2 and "--stroke-margin" in err and out == ""


@pytest.mark.slow
def test_a_stroke_margin_is_verified_or_inconclusive_with_its_reason(min_energy):
    """The margin binds on a short boundary arc: never "verified" on a certificate that
    doubts it; the reason names the arc."""
    r = min_energy.solve_min_energy(V0, depth_max=5.0, stroke_margin=8.6)
    reasons = r.unverified_reasons(r.certify())
    assert r.smooth.mesh_converged and r.energy > 25 / 3
    if reasons:
        assert r.certify().verdict == "inconclusive"
        assert any("state boundary arc of margin" in x for x in reasons)
