"""The suite of published problems: each reaches its published optimum by Radau
collocation with mesh refinement, and is cross-checked against a closed form or a
second method (multiple shooting with inner-step constraints, extrapolated).

Tolerances: ``rtol`` against the published value is what its printed digits and,
for COPS and PROPT values, their own discretisation allow (see each entry in
``tests/ocp_suite/problems.py``); against a closed form we ask 1e-6 (the refinement
tolerance is 1e-7 on the states, Ipopt's bound relaxation is 1e-8).
"""

import math

import pytest

from ocp import MultipleShooting, certify
from ocp.certificate.certify import CERTIFIED
from tests.oracles.ocp_suite import PROBLEMS

BY_NAME = {p.name: p for p in PROBLEMS}


def test_suite_covers_what_the_issue_asks():
    covers = " / ".join(c for p in PROBLEMS for c in p.covers)
    for need in ("state-constrained arc", "singular arc", "bang-bang, one control",
                 "bang-bang, several controls", "mixed state-control", "integral",
                 "free initial times", "free final time", "decision parameters",
                 "phase constraint active", "between nodes", "chattering", "SI units",
                 "control-only coupling constraints (inequality)",
                 "control-only coupling constraints (equality", "several local optima",
                 "bang-bang solved by collocation and certified", "objective accuracy"):
        assert need in covers, need
    assert len(PROBLEMS) >= 20
    assert sum(math.isfinite(p.published) for p in PROBLEMS) >= 10


REACH_SLOW = {"pinene", "hanging_chain", "rayleigh_min_time", "goddard"}  # 3.7, 2.8, 3.1 s
# CPU: the README's command's budget; goddard's singular arc converges at first order, and
# its refinement to 1e-6 confirmed on the halved mesh takes ~20 s CPU (issue 44: the tree
# before stopped at 1.5 s claiming 3.9e-7 where the error was 2.7e-6)
SECOND = {"rayleigh_mixed", "orbit_raising", "pendulum_swingup", "fuller_free_end",
          "thrusters_2d", "cannonball"}
# issue 46 (the README's command at 200 s CPU): these six refined solves and their
# certificates, 0.7 to 1.9 s CPU each (9.2 s in all, with the cannonball's, which
# definition/test_scaling_ocp.py reads), run in the second command only
REACH_SLOW |= SECOND


@pytest.mark.parametrize("name", [
    pytest.param(p.name, marks=pytest.mark.slow) if p.name in REACH_SLOW else p.name
    for p in PROBLEMS])
def test_reaches_the_published_value(name, suite_refined):
    sp = BY_NAME[name]
    sol = suite_refined(name)
    assert sol.success and sol.verified and sol.mesh_converged, sol.mesh_history[-1]
    value = sp.value(sol)
    if math.isfinite(sp.published):
        assert value == pytest.approx(sp.published, rel=sp.rtol)
    if sp.exact is not None:
        assert value == pytest.approx(sp.exact(), rel=sp.exact_rtol)


# second method: multiple shooting, path constraints also at the inner RK4 steps.
# (nodes, order of convergence for a Richardson step or None, rtol)
CROSS = {
    "catalyst_mixing": ((200,), None, 2e-7),
    "goddard": ((200,), None, 3e-6),
    "teo_state_constraint": ((200, 400), 2, 1e-6),
    # the mixed constraint makes piecewise-constant controls converge at first order only
    "rayleigh_mixed": ((200, 400), 1, 5e-5),
    "robot_arm": ((200,), None, 5e-6),
}
SLOW = {"robot_arm", "teo_state_constraint", "rayleigh_mixed", "goddard"}  # goddard: 3.8 s CPU


@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in CROSS])
def test_multiple_shooting_agrees(name, suite_refined):
    sp = BY_NAME[name]
    nodes, order, rtol = CROSS[name]
    values = []
    for n in nodes:
        ms = MultipleShooting(sp.build(), nodes=n, inner_constraints=True, expand=True,
                              verify="off")
        values.append(sp.value(ms.solve(guess=suite_refined(name))))
    if order is not None:
        values.append(values[1] + (values[1] - values[0]) / (2**order - 1))
    assert values[-1] == pytest.approx(sp.value(suite_refined(name)), rel=rtol)


def test_mesh_refinement_builds_once_per_mesh_and_resolves_without_rebuild(suite_refined):
    sol = suite_refined("brachistochrone")
    rounds = sol.mesh_history
    assert len(rounds) >= 2 and rounds[-1].max_error < rounds[0].max_error
    tr = sol.transcription
    again = tr.solve(guess=sol)
    assert tr.n_builds == 1 and again.objective == pytest.approx(sol.objective, rel=1e-10)


# the certificate against the literature's verdict, on every single-phase problem with a
# control: bang-bang ones are certified from their collocation solution and its refined
# switching times; the others (singular, chattering, smooth) are never certified
CERT_SLOW = {"robot_arm", "hanging_chain", "rayleigh_min_time", "goddard"} | SECOND
# robot_arm: 2 s CPU; the others: their refined solves are REACH_SLOW


# the verdict is what is tested: a refined mesh a hair over a state limit between its points
# (teo_state_constraint, 1.6e-6) is warned and leaves the certificate uncertified, as asserted
@pytest.mark.filterwarnings("ignore::ocp.definition.errors.PathViolationWarning")
@pytest.mark.parametrize("name", [
    pytest.param(p.name, marks=pytest.mark.slow) if p.name in CERT_SLOW else p.name
    for p in PROBLEMS if not p.name.startswith(("bryson_denham_3", "pinene", "cannonball"))])
def test_certificate_agrees_with_the_literature(name, suite_refined, suite_switching):
    sp = BY_NAME[name]
    sol = suite_refined(name)
    if sp.bang_bang:
        _, cert = suite_switching(name)  # certify(sol, refine_switching(sol))
        assert cert.verdict == CERTIFIED, cert.reasons
        return
    try:
        cert = certify(sol)
    except ValueError as err:  # outside what the certificate covers: said, not guessed
        assert any(w in str(err) for w in ("affine", "convex", "autonomous")), err
        return
    assert cert.verdict != CERTIFIED, cert.reasons
