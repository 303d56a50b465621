"""Pontryagin certificate: analytic costates, a singular arc (the landing's certificate is
tested in tests/softlanding/optimal/test_landing_certificate.py)."""

import math

import numpy as np
import pytest

from ocp import MultipleShooting, OptimalControlProblem, certify
from ocp.certificate.certify import (
    CERTIFIED,
    costates_from_multipliers,
)
from ocp.structure.switching import refine_switching
from tests.oracles.problems import min_time_double_integrator


@pytest.mark.parametrize("d", [1.0, 2.5])
def test_double_integrator_analytic_costates_and_certificate(d):
    # minimum principle, phi = T: H = lam_x v + lam_v u = -1, lam_x = -1/sqrt(d),
    # lam_v = t/sqrt(d) - 1 (zero at the switch t = sqrt(d))
    sol = MultipleShooting(min_time_double_integrator(mayer=True), nodes=40).solve({"d": d})
    ref = refine_switching(sol)
    c = certify(sol, ref)
    assert c.verdict == CERTIFIED, c.reasons
    rd = math.sqrt(d)
    np.testing.assert_allclose(c.lam[:, 0], -1 / rd, atol=1e-9)
    np.testing.assert_allclose(c.lam[:, 1], c.t / rd - 1, atol=1e-9)
    assert c.H_expected == pytest.approx(-1.0)
    assert c.H_max_abs < 1e-12
    assert c.switch_sigma_gap < 1e-9
    # the multiplier-based estimate agrees to the grid's accuracy
    t, lam = costates_from_multipliers(sol)
    np.testing.assert_allclose(lam[:, 0], -1 / rd, atol=1e-6)
    np.testing.assert_allclose(lam[:, 1], t / rd - 1, atol=1e-6)
    assert c.costate_estimates_gap < 1e-6


def test_free_time_with_running_cost_has_zero_hamiltonian():
    sol = MultipleShooting(min_time_double_integrator(mayer=False), nodes=40).solve({"d": 1.0})
    ref = refine_switching(sol)
    c = certify(sol, ref)
    assert c.verdict == CERTIFIED
    assert c.H_expected == 0.0
    assert np.max(np.abs(c.H)) < 1e-12
    # from the transcription alone: certified with grid-level tolerances
    c2 = certify(sol)
    assert c2.verdict == CERTIFIED, c2.reasons
    assert c2.H_max_abs < 1e-6


def test_singular_arc_is_certified_with_its_order():
    # min int x^2, x' = u, |u| <= 1, x(0) = 1, T = 3: u = -1 until t = 1, then u = 0 (singular).
    # This test asserted the old limitation ("not bang-bang", a singular arc refuting the
    # bang-bang certificate); the certificate now checks the singular arc's own conditions.
    p = OptimalControlProblem()
    x = p.state("x")
    u = p.control("u", lower=-1, upper=1)
    p.set_dynamics([u])
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(3.0)
    p.minimize_integral(x**2)
    sol = MultipleShooting(p, nodes=60).solve({})
    c = certify(sol)
    assert c.verdict == "certified (bang, singular order 1)", c.reasons
    (arc,) = [a for a in c.arcs if a.kind == "singular"]
    assert arc.start == pytest.approx(1.0, abs=0.1) and arc.end == pytest.approx(3.0)
    assert arc.order == 1 and arc.residuals["Kelley (-1)^k b min"] == pytest.approx(2.0)

