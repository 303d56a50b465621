"""Collocation solutions through detect_structure, refine_switching and certify.

On today's tree before this change every one of these failed: ``certify`` crashed
on any collocation solution (``operands could not be broadcast together with
shapes (20,2) (60,2)``: the costates were the N mesh continuity multipliers on
the N d collocation times), ``costates_from_multipliers`` returned times and
costates of different lengths, and ``detect_structure`` read the N d collocation
points as an even grid with one control per point, so a switch spread over a
mesh interval's points (the moon lander) became an "interior" arc and
``refine_switching`` refused it.

References are independent of the code under test: closed forms (double
integrator, moon lander, harmonic oscillator), Pontryagin's boundary-value
problem solved with scipy (Rayleigh, ``ocp_suite.rayleigh_min_time``), scipy
``solve_ivp`` re-integrations of the bang-bang controls, and COPS' published
value (robot arm).
"""

import math
import warnings
from functools import cache

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from ocp import (
    Collocation,
    MultipleShooting,
    OptimalControlProblem,
    PathViolationWarning,
    Trajectory,
    certify,
)
from ocp.certificate.certify import CERTIFIED, INCONCLUSIVE, UNVERIFIED, finer_transcription
from ocp.certificate.costates import costates_from_multipliers
from ocp.structure.switching import detect_structure, refine_switching
from tests.oracles.ocp_suite import PROBLEMS
from tests.oracles.ocp_suite import problems as P
from tests.oracles.ocp_suite.oscillator_min_time import (
    T_FINAL,
    T_SWITCH,
    oscillator_min_time,
    oscillator_min_time_check,
)
from tests.oracles.ocp_suite.rayleigh_min_time import (
    rayleigh_min_time,
    rayleigh_min_time_guess,
    rayleigh_min_time_pmp,
)
from tests.oracles.problems import min_time_double_integrator
from tests.oracles.switching_problems import ceiling, speed_limited

IVP = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}


def suite_settings(name: str) -> tuple:
    """A suite entry's (intervals, degree, tol, guess): a test reading the suite's shared
    solve (tests/ocp/conftest.py) checks they are its own."""
    sp = next(p for p in PROBLEMS if p.name == name)
    return sp.intervals, sp.degree, sp.tol, sp.guess


def kinds(st):
    return [s.kinds for s in st.per_control]


def quiet(fn, *a, **k):
    """A coarse grid may miss a state bound between points; that is not under test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PathViolationWarning)
        return fn(*a, **k)


# ------------------------------------------------------------ double integrator
def double_integrator() -> OptimalControlProblem:
    """The README's minimum-time double integrator (its default guess of T)."""
    return min_time_double_integrator(T_guess=None, name="double_integrator")


@cache
def di_collocation(d: float, refine: bool):
    """The double integrator by collocation on 21 intervals, solved or refined to 1e-8,
    once per module (read by the two tests below; each builds its own problem object's
    transcription, so the refinement's NLP cache starts empty for every (d, refine))."""
    tr = Collocation(double_integrator(), intervals=21)
    return tr.refine({"d": d}, tol=1e-8) if refine else tr.solve({"d": d})


@pytest.mark.parametrize("refine", [False, True])
@pytest.mark.parametrize("d", [2.0, 2.5])
def test_double_integrator_collocation_structure_refinement_and_certificate(d, refine):
    sol = di_collocation(d, refine)
    ms = MultipleShooting(sol.problem, nodes=41).solve({"d": d})  # the same problem object
    st, st_ms = detect_structure(sol), detect_structure(ms)
    assert kinds(st) == kinds(st_ms) == [["max", "min"]]
    # closed form: full thrust to sqrt(d), full brake to 2 sqrt(d)
    assert st.switch_times[0] == pytest.approx(math.sqrt(d), abs=0.5 * sol.T / 21)
    r = refine_switching(sol, st)
    assert r.switch_times == pytest.approx([math.sqrt(d)], abs=1e-12)
    assert r.T == pytest.approx(2 * math.sqrt(d), abs=1e-12)
    c0, c1 = certify(sol), certify(sol, r)
    # 20 unrefined intervals leave the mass bound violated between the points by ~4e-5:
    # that transcription is no verified candidate, the refined solution is
    assert c0.verdict == (CERTIFIED if sol.verified else UNVERIFIED), c0.reasons
    assert c1.verdict == CERTIFIED, c1.reasons
    assert c1.H_max_abs < 1e-12
    gap_ms = certify(ms, refine_switching(ms)).costate_estimates_gap
    assert c1.costate_estimates_gap < max(10 * gap_ms, 2e-2)


@pytest.mark.parametrize("refine", [False, True])
def test_collocation_costates_are_the_analytic_ones(refine):
    """lambda = (-1/sqrt(d), -1 + t/sqrt(d)) (H = -1, sigma = lambda_2 = 0 at sqrt(d)),
    from the defect multipliers divided by the Radau weights, at every collocation point."""
    d = 2.5
    sol = di_collocation(d, refine)
    t, lam = costates_from_multipliers(sol)
    assert t.shape == (sol.N,) and lam.shape == (sol.N, 2)
    exact = np.column_stack([np.full_like(t, -1 / math.sqrt(d)), -1 + t / math.sqrt(d)])
    # the discrete dual is pinned by the points whose control is inside its bounds
    # (next to the switch): an error of the order of one mesh interval
    err = np.max(np.abs(lam - exact))
    assert err < (2e-3 if refine else 2e-2)
    # the continuity multipliers are the same costate at the mesh points
    mesh_t = sol.mesh[1:]
    cont = sol.multipliers["continuity"]
    at_mesh = np.column_stack([np.interp(mesh_t, t, lam[:, j]) for j in range(2)])
    np.testing.assert_allclose(cont, at_mesh, atol=1e-9)


# ------------------------------------------------------------------ moon lander
def moon_lander_switch() -> float:
    """Meditch's free fall until s, then full thrust to touchdown (closed-form arcs)."""
    c = P.MOON
    g, E, U, h0, v0 = c["g"], c["E"], c["umax"], c["h0"], c["v0"]

    def burn(tau, hs, vs):
        m = 1 - U * tau / E
        return (hs + vs * tau - g * tau**2 / 2 + E * (tau + (E / U) * m * math.log(m)),
                vs - g * tau - E * math.log(m))

    def end_height(s):
        hs, vs = h0 + v0 * s - g * s**2 / 2, v0 - g * s
        tau = brentq(lambda t: burn(t, hs, vs)[1], 1e-9, E / U * (1 - 1e-9), xtol=1e-15)
        return burn(tau, hs, vs)[0]

    return brentq(end_height, 0.0, 1.0, xtol=1e-15)


@pytest.mark.parametrize("refine", [False, True])
def test_moon_lander_collocation_matches_shooting_and_closed_form(refine, moon_lander_shooting,
                                                                 suite_refined, suite_switching):
    ms, r_ms, c_ms = moon_lander_shooting  # 60 nodes (tests/ocp/conftest.py)
    if refine:  # 10 intervals refined to 1e-8: the suite's entry, its solve and refinement
        assert suite_settings("moon_lander") == (10, 3, 1e-8, None)
        sol = suite_refined("moon_lander")
    else:
        sol = quiet(Collocation(P.moon_lander(), intervals=20).solve, {})
    st = detect_structure(sol)
    assert kinds(st) == kinds(detect_structure(ms)) == [["min", "max"]]
    r, c1 = suite_switching("moon_lander") if refine else (refine_switching(sol, st), None)
    assert r.switch_times == pytest.approx([moon_lander_switch()], abs=1e-10)
    assert r.objective == pytest.approx(P.moon_lander_exact(), rel=1e-10)
    assert r.switch_times == pytest.approx(r_ms.switch_times, abs=1e-12)
    c0, c1 = certify(sol), c1 if c1 is not None else certify(sol, r)
    # 20 unrefined intervals leave the mass bound violated between the points by ~4e-5:
    # that transcription is no verified candidate, the refined solution is
    assert c0.verdict == (CERTIFIED if sol.verified else UNVERIFIED), c0.reasons
    assert c1.verdict == CERTIFIED, c1.reasons
    # the multiplier costate of collocation is as close to the adjoint as shooting's
    assert c1.costate_estimates_gap < 3 * c_ms.costate_estimates_gap


# -------------------------------------------------------- harmonic oscillator
@pytest.mark.parametrize("refine", [False, True])
def test_oscillator_min_time_collocation_closed_form(refine, suite_refined, suite_switching):
    if refine:  # 10 intervals refined to 1e-8: the suite's entry, its solve and refinement
        assert suite_settings("oscillator_min_time") == (10, 3, 1e-8, None)
        sol = suite_refined("oscillator_min_time")
    else:
        sol = Collocation(oscillator_min_time(), intervals=15).solve()
    st = detect_structure(sol)
    assert kinds(st) == [["min", "max"]]
    r, c1 = suite_switching("oscillator_min_time") if refine else (refine_switching(sol, st), None)
    assert r.exact  # linear: matrix exponentials
    assert r.switch_times == pytest.approx([T_SWITCH], abs=1e-12)
    assert r.T == pytest.approx(T_FINAL, abs=1e-12)
    assert np.max(np.abs(oscillator_min_time_check())) < 1e-11  # scipy: the origin
    assert certify(sol).verdict == CERTIFIED
    assert (c1 if c1 is not None else certify(sol, r)).verdict == CERTIFIED


# ------------------------------------------------------------------- Rayleigh
@pytest.fixture(scope="module")
def rayleigh_reference():
    ref = rayleigh_min_time_pmp()
    assert ref["residual"] < 1e-11
    return ref


@pytest.mark.slow  # 10 s: the RK8 refinement NLP and scipy's boundary-value problem
def test_rayleigh_collocation_reaches_pontryagin_solution(rayleigh_reference):
    tr = Collocation(rayleigh_min_time(), intervals=30)
    sol = tr.solve(guess=rayleigh_min_time_guess())
    st = detect_structure(sol)
    assert kinds(st) == [["max", "min", "max"]]
    r = refine_switching(sol, st)
    ref = rayleigh_reference
    assert r.switch_times == pytest.approx([ref["t1"], ref["t2"]], abs=1e-10)
    assert r.T == pytest.approx(ref["tf"], abs=1e-10)
    # Maurer and Osmolovskii's published figures
    assert r.switch_times == pytest.approx([1.12051, 3.31005], abs=6e-6)
    assert r.T == pytest.approx(3.66817, abs=6e-6)
    c0, c1 = certify(sol), certify(sol, r)
    assert c0.verdict != "not bang-bang", c0.reasons
    assert c1.verdict == CERTIFIED, c1.reasons
    assert c1.switch_sigma_gap < 1e-9
    # multiplier costates on 30 intervals vs the adjoint: of the order of one mesh
    # interval (multiple shooting on 100 nodes: 0.07)
    assert c1.costate_estimates_gap < 0.1


# ------------------------------------------------------------------ robot arm
ROBOT_KINDS = [["min", "max", "min"], ["max", "min"], ["min", "max", "min"]]


def robot_end_state(r) -> np.ndarray:
    """The refined bang controls re-integrated by scipy (DOP853): the end state."""
    L = 5.0

    def rhs(t, y, u):
        rho, _, phi, rd, td, pd = y
        i_the = ((L - rho) ** 3 + rho**3) * math.sin(phi) ** 2 / 3
        i_phi = ((L - rho) ** 3 + rho**3) / 3
        return [rd, td, pd, u[0] / L, u[1] / i_the, u[2] / i_phi]

    y = np.array([4.5, 0.0, math.pi / 4, 0.0, 0.0, 0.0])
    edges = np.r_[0.0, np.cumsum(r.durations)]
    for k, vals in enumerate(r.values):
        if edges[k + 1] > edges[k]:
            y = solve_ivp(rhs, (edges[k], edges[k + 1]), y, args=(vals,), **IVP).y[:, -1]
    return y


@pytest.mark.slow  # 9 s: the refinement NLP of three controls takes 5 s to build
def test_robot_arm_three_controls_by_collocation():
    sol = quiet(Collocation(P.robot_arm(), intervals=40).solve, {})
    st = detect_structure(sol)
    assert kinds(st) == ROBOT_KINDS
    r = refine_switching(sol, st)
    # COPS publishes 9.14138 from a trapezoidal NLP (nh = 200), good to its O(h^2)
    assert r.T == pytest.approx(9.14138, rel=1e-4)
    end = robot_end_state(r)
    np.testing.assert_allclose(end, [4.5, 2 * math.pi / 3, math.pi / 4, 0, 0, 0], atol=1e-9)
    c = certify(sol, r)
    assert c.verdict == CERTIFIED, c.reasons
    assert certify(sol).verdict == CERTIFIED


@pytest.mark.slow
def test_robot_arm_collocation_and_shooting_agree():
    ms = MultipleShooting(P.robot_arm(), nodes=80).solve({})
    co = quiet(Collocation(P.robot_arm(), intervals=12).refine, {}, tol=1e-6)
    st_ms, st_co = detect_structure(ms), detect_structure(co)
    assert kinds(st_ms) == kinds(st_co) == ROBOT_KINDS
    r_ms, r_co = refine_switching(ms, st_ms), refine_switching(co, st_co)
    np.testing.assert_allclose(r_co.switch_times, r_ms.switch_times, atol=1e-10)
    assert r_co.T == pytest.approx(r_ms.T, abs=1e-10)
    c_ms, c_co = certify(ms, r_ms), certify(co, r_co)
    assert c_co.verdict == c_ms.verdict == CERTIFIED
    assert c_co.costate_estimates_gap < 10 * c_ms.costate_estimates_gap


# ------------------------------------------------ state constraints stay honest
def line_guess(T, x_of_s, u):
    t = np.linspace(0.0, T, 41)
    x = np.array([x_of_s(s) for s in t / T])
    return Trajectory(t, x, np.tile(u, (len(t), 1)), ("x", "v"), ("u",))


# a coarse mesh on purpose: the transcription crosses the limit between points (warned), the
# refinement and the certificate are what is tested
@pytest.mark.filterwarnings("ignore::ocp.definition.errors.PathViolationWarning")
@pytest.mark.parametrize("refine", [False, True])
def test_speed_limit_boundary_arc_by_collocation_is_not_certified(refine):
    tr = Collocation(speed_limited(), intervals=30)
    par = {"d": 3.0, "vmax": 1.0}
    g = line_guess(4.0, lambda s: [3 * s, 0.5], [0.0])
    sol = tr.refine(par, tol=1e-7, guess=g) if refine else tr.solve(par, guess=g)
    st = detect_structure(sol)
    assert kinds(st) == [["max", "boundary", "min"]]
    r = refine_switching(sol, st)
    assert r.switch_times == pytest.approx([1.0, 3.0], abs=1e-12)  # vmax, d / vmax
    c = certify(sol, r)
    assert c.verdict == INCONCLUSIVE and "state constraint active" in c.reasons[-1]
    assert certify(sol).verdict == (INCONCLUSIVE if sol.verified else UNVERIFIED)


# a coarse mesh on purpose (see above)
@pytest.mark.filterwarnings("ignore::ocp.definition.errors.PathViolationWarning")
def test_ceiling_boundary_arc_by_collocation_is_not_certified():
    tr = Collocation(ceiling(), intervals=30)
    g = line_guess(4.0, lambda s: [0.3 * np.sin(np.pi * s), 0.0], [0.0])
    sol = tr.solve({"l": 0.5}, guess=g)
    st = detect_structure(sol)
    assert kinds(st) == [["max", "min", "boundary", "min", "max"]]
    r = refine_switching(sol, st)
    a = math.sqrt(0.5)
    assert r.switch_times == pytest.approx([a, 2 * a, 4 - 2 * a, 4 - a], abs=1e-10)
    c = certify(sol, r)
    assert c.verdict == INCONCLUSIVE and "state constraint active" in c.reasons[-1]
    assert certify(sol).verdict != CERTIFIED


def test_finer_transcription_splits_the_collocation_mesh():
    tr = Collocation(oscillator_min_time(), intervals=8)
    sol = tr.solve()
    fine = finer_transcription(sol)
    assert fine is not None and fine.success
    assert len(fine.mesh) == 2 * 8 + 1
    np.testing.assert_allclose(fine.mesh[::2] / fine.T, sol.mesh / sol.T, atol=1e-12)
