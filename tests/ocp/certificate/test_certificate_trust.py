"""A certificate that cannot lie, and honest refinement statuses (issue 21).

Reference values are independent of ``ocp``: Fuller's closed-form synthesis
(``ocp_suite.fuller``, its constant re-derived here by minimisation), a
one-parameter minimisation over exact polynomial arcs for the short-horizon
Fuller problem, and the double integrator's reachable set.
"""

from __future__ import annotations

import copy
import math
from functools import cache

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy.optimize import minimize_scalar

from ocp import InfeasibleError, MultipleShooting, OptimalControlProblem, SolveError
from ocp.certificate.certify import (
    CERTIFIED,
    CHATTERING,
    INCONCLUSIVE,
    NOT_APPLICABLE,
    OTHER_CANDIDATE,
    UNVERIFIED,
    certify,
    detect_chattering,
)
from ocp.structure.refinement import kkt_converged
from ocp.structure.switching import clear_cache, detect_structure, refine_switching
from tests.oracles.ocp_suite.fuller import FULLER_C, cost_to_origin, fuller, fuller_value, ratio
from tests.oracles.problems import min_time_double_integrator

T0_FULLER = cost_to_origin(1.0)[1]  # time to reach the origin from (1, 0): 2.7152


@cache
def _solve(x0: float, T: float, free_end: bool, nodes: int):
    """Fuller's problem by multiple shooting, solved once per module (several tests read
    the same solutions: they are only read; the one test that edits one edits a copy)."""
    return MultipleShooting(fuller(x0, T, free_end), nodes=nodes).solve({})


# ------------------------------------------------------------------ the reference
def test_fuller_reference_is_independent():
    """The closed form: Fuller's constant is the minimiser of the synthesis' cost (so the
    reference does not rest on the quoted constant), and well-resolved transcriptions
    approach 2 V (mintOC scale and rescaled by homogeneity). Checks the reference, not a
    feature (the module is new)."""
    best = minimize_scalar(lambda C: cost_to_origin(1.0, C)[0], bounds=(0.3, 0.49),
                           method="bounded", options={"xatol": 1e-10})
    assert best.x == pytest.approx(FULLER_C, abs=1e-6)
    assert ratio() == pytest.approx(0.2421, abs=1e-4)
    assert fuller_value() == pytest.approx(1.5280351e-05, rel=1e-7)
    # homogeneity: x1 -> k^2 x1, t -> k t multiplies the cost by k^5
    assert fuller_value(1.0, 10.0) == pytest.approx(1e5 * fuller_value(), rel=1e-12)
    sol = _solve(1.0, 6.0, False, 120)
    assert sol.objective == pytest.approx(fuller_value(1.0, 6.0), rel=3e-4)
    assert sol.objective > fuller_value(1.0, 6.0)  # a transcription is feasible: above


# ------------------------------------------------------------------ false certificates
def test_fuller_is_not_certified_it_chatters():
    """Fuller's problem with time to rest at the origin (x0 = (1, 0), T = 6, i.e. mintOC's
    problem rescaled by homogeneity with horizon 0.6): the transcription's structure has an
    interior arc, which refine_switching flies as a singular arc of order 2 (the best
    bang-singular candidate: Fuller's optimum has no such junction), yet today's certify
    says "bang-bang certified". Now: chattering suspected near T_0 = 2.7152 (or its mirror
    T - T_0), with the switch ratio near Fuller's 0.2421, and the refined candidate's
    singular arc fails its conditions."""
    sol = _solve(1.0, 6.0, False, 40)
    st = detect_structure(sol)
    assert not st.refinable
    r = refine_switching(sol)
    assert "singular" in r.kinds and r.objective < sol.objective
    refined = certify(sol, r)
    assert refined.verdict == CHATTERING and not refined.certified
    assert any(a.kind == "singular" and a.order == 2 and a.status == "fails"
               for a in refined.arcs)
    cert = certify(sol)
    assert cert.verdict == CHATTERING and not cert.certified
    assert cert.reasons[0].startswith("chattering suspected near t = ")
    ch = cert.chattering
    assert ch is not None and ch.confirmed
    t_star = ch.t_star if ch.direction == "forward" else 6.0 - ch.t_star
    assert t_star == pytest.approx(T0_FULLER, abs=0.03)
    assert ch.ratio == pytest.approx(ratio(), abs=0.06)
    assert max(ch.counts.values()) > ch.counts[40]  # more switches on the finer grid
    assert cert.to_dict()["chattering"]["t_star"] == ch.t_star


def test_structure_doubt_alone_forbids_the_certificate():
    """Without the chattering detector the same solution is still not certified: structure
    detection finds an interior arc, so the verdict is "inconclusive" with that reason
    (today: "bang-bang certified")."""
    sol = _solve(1.0, 6.0, False, 40)
    cert = certify(sol, chattering=False)
    assert cert.verdict == INCONCLUSIVE
    assert any(r.startswith("structure detection finds an interior arc on [") for r in
               cert.reasons)


def test_fuller_free_end_chatters_into_a_singular_arc():
    """Second member of the class: free final state, chattering into the origin then the
    singular arc u = 0 (cost V(1, 0)). Today: "not bang-bang" (the singular arc) without a
    word of chattering; now the accumulation point T_0 is found, forward."""
    sol = _solve(1.0, 10.0, True, 60)
    assert sol.objective == pytest.approx(fuller_value(1.0, 10.0, free_end=True), rel=2e-3)
    ch = detect_chattering(sol)
    assert ch is not None and ch.direction == "forward"
    assert ch.t_star == pytest.approx(T0_FULLER, abs=0.03)
    assert len(ch.switch_times) >= 4
    assert certify(sol).verdict == CHATTERING


# ------------------------------------------------------------------ no false alarm
def _short_fuller_value() -> tuple[float, np.ndarray]:
    """T = 5 < 2 T_0: the optimum has four switches, symmetric about T/2 (min a, max b,
    min c, max b, min a). x2(T/2) = 0 gives c = 2 (b - a) and then b = T/4; minimise the
    exact polynomial cost over a. Returns (cost, switch times)."""
    T = 5.0
    b = T / 4

    def cost(a: float) -> float:
        x1, x2, J = 1.0, 0.0, 0.0
        for u, d in ((-1.0, a), (1.0, b), (-1.0, b - a)):  # the first half
            arc = Polynomial([x1, x2, u / 2])
            J += float((arc**2).integ()(d))
            x1, x2 = float(arc(d)), x2 + u * d
        return 2 * J

    a = minimize_scalar(cost, bounds=(0.5, b), method="bounded",
                        options={"xatol": 1e-12}).x
    return cost(a), np.cumsum([a, b, 2 * (b - a), b])


def test_no_chattering_on_genuine_bang_bang():
    """Fuller with a horizon too short to reach the origin (T = 5) is bang-bang with four
    switches (independent value above): certified, no chattering; likewise the README's
    minimum-time double integrator."""
    J, switches = _short_fuller_value()
    sol = _solve(1.0, 5.0, False, 60)
    assert detect_chattering(sol) is None
    cert = certify(sol)
    assert cert.verdict == CERTIFIED and cert.chattering is None
    r = refine_switching(sol)
    assert r.objective == pytest.approx(J, rel=1e-10)
    assert np.allclose(r.switch_times, switches, atol=1e-6)
    assert certify(sol, r).verdict == CERTIFIED

    sol = MultipleShooting(_readme_di(), nodes=40).solve({"d": 2.0})
    assert detect_chattering(sol) is None
    cert = certify(sol, refine_switching(sol))
    assert cert.verdict == CERTIFIED and cert.chattering is None
    assert sol.T == pytest.approx(2 * math.sqrt(2.0), rel=1e-2)


# ------------------------------------------------------------------ refusals
def _unreachable() -> OptimalControlProblem:
    """x'' = u, |u| <= 1, from rest to x(1) = 100: at most 1/2 is reachable."""
    p = OptimalControlProblem("unreachable")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", lower=-1, upper=1)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x, 100.0)
    p.terminal_constraint(v, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    return p


def test_failed_solves_are_refused():
    """The iterate of an InfeasibleError (today: "bang-bang certified" although its last node
    sits at x = 99.7 where at most 1/2 is reachable: its continuity is broken), of a
    SolveError (today: "inconclusive") and a solution not verified between its nodes (today:
    "bang-bang certified") get "not applicable", with Ipopt's status."""
    with pytest.raises(InfeasibleError) as info:
        MultipleShooting(_unreachable(), nodes=20).solve({})
    cert = certify(info.value.iterate)
    assert cert.verdict == NOT_APPLICABLE and not cert.applicable and not cert.certified
    assert info.value.status in cert.reasons[0]
    assert math.isnan(cert.H_max_abs)

    ms = MultipleShooting(fuller(1.0, 5.0), nodes=30, ipopt_options={"max_iter": 2})
    with pytest.raises(SolveError) as info2:
        ms.solve({})
    assert certify(info2.value.iterate).verdict == NOT_APPLICABLE

    sol = copy.copy(_solve(1.0, 5.0, False, 30))
    sol.verified = False  # as a PathViolationError's iterate carries it
    assert certify(sol).verdict == UNVERIFIED


def test_failed_refinement_is_refused():
    """A refinement that ran out of iterations raises SolveError; its iterate says
    success False and certify refuses it (today: "not bang-bang", a refutation of a point
    that is no extremal)."""
    sol = _solve(1.0, 5.0, False, 30)
    clear_cache(sol.problem)  # this problem's refinement NLPs built afresh, no one else's
    with pytest.raises(SolveError) as info:
        refine_switching(sol, ipopt_options={"max_iter": 1}, fast=False, repair=False)
    it = info.value.iterate
    assert it.success is False
    cert = certify(sol, it)
    assert cert.verdict == NOT_APPLICABLE and "refinement did not converge" in cert.reasons[0]


# ------------------------------------------------------------------ honest statuses
def test_refinement_at_machine_precision_says_converged():
    """Fuller, T = 5, from 24 nodes: Ipopt does not end the refinement with
    Solve_Succeeded (Solved_To_Acceptable_Level here; Search_Direction_Becomes_Too_Small
    from other grids) while the result matches the independent value to 1e-12. The status
    now says it converged and names Ipopt's message (today: the bare Ipopt message)."""
    sol = _solve(1.0, 5.0, False, 24)
    clear_cache(sol.problem)
    J, _ = _short_fuller_value()
    r = refine_switching(sol, fast=False)
    assert r.success
    assert r.status.startswith("Solve_Succeeded (KKT residual ")
    assert "; Ipopt said " in r.status and "Ipopt said Solve_Succeeded" not in r.status
    assert r.objective == pytest.approx(J, rel=1e-12)


def test_kkt_acceptance_logic():
    """Only a KKT point to rounding passes: a primal violation never does, and outside the
    rounding-level stalls the dual residual must be at machine precision."""
    ok = {"status": "Maximum_Iterations_Exceeded", "primal": 1e-15, "dual": 1e-14,
          "complementarity": 1e-16}
    assert kkt_converged(ok)
    assert not kkt_converged({**ok, "primal": 1e-6})
    assert not kkt_converged({**ok, "dual": 1e-9})
    assert kkt_converged({**ok, "status": "Search_Direction_Becomes_Too_Small", "dual": 1e-9})
    assert not kkt_converged({**ok, "complementarity": 1e-3})
    assert not kkt_converged({**ok, "dual": math.nan})
    assert not kkt_converged({**ok, "status": "Infeasible_Problem_Detected", "primal": 0.3})


def _two_phase():
    """The README's push-then-brake problem: push with |u| <= 1, then brake at -1; minimum
    total time to rest at d (the brake phase has no control)."""
    from ocp import MultiPhaseProblem

    mp = MultiPhaseProblem("push_brake")
    d = mp.parameter("d")
    push, brake = mp.phase("push"), mp.phase("brake")
    x, v = push.state("x"), push.state("v")
    u = push.control("u", lower=-1, upper=1)
    push.set_dynamics({"x": v, "v": u})
    push.initial_constraint(x, 0.0)
    push.initial_constraint(v, 0.0)
    push.free_final_time(0.01, 10)
    xb, vb = brake.state("x"), brake.state("v")
    brake.set_dynamics({"x": vb, "v": -1.0})
    brake.terminal_constraint(xb - d, 0.0)
    brake.terminal_constraint(vb, 0.0)
    brake.free_duration(0.01, 10)
    mp.link(push, brake)
    mp.minimize(brake.T)
    return mp


def test_failed_phase_refinement_is_refused():
    """Multi-phase: the iterate of a failed refine_phases (success False) is refused by
    certify and certify_phases alike (today: "not bang-bang", judged as if converged)."""
    from ocp.certificate.phases import PhasesCertificate, certify_phases
    from ocp.structure.phase_refinement import refine_phases

    sol = MultipleShooting(_two_phase(), nodes=[20, 20]).solve({"d": 2.0})
    good = refine_phases(sol)
    assert good.success and certify(sol, good).verdict == CERTIFIED
    assert good.T == pytest.approx(2 * math.sqrt(2.0), rel=1e-12)
    with pytest.raises(SolveError) as info:
        refine_phases(sol, ipopt_options={"max_iter": 1}, fast=False)
    bad = info.value.iterate
    assert bad.success is False
    for cert in (certify(sol, bad), certify_phases(sol, bad)):
        assert isinstance(cert, PhasesCertificate)
        assert cert.verdict == NOT_APPLICABLE and not cert.applicable


def test_chattering_without_a_re_solve_needs_a_long_run():
    """Without re-solves (verify=False), a grid fine enough to show three shrinking switch
    intervals with consistent ratios suffices (unconfirmed); a coarse grid showing only two
    does not (today: "bang-bang certified" on the fine grid, "inconclusive" on the coarse
    one, which without chattering the structure check also gives)."""
    fine = _solve(1.0, 6.0, False, 480)
    ch = detect_chattering(fine, resolve=False)
    assert ch is not None and not ch.confirmed
    t_star = ch.t_star if ch.direction == "forward" else 6.0 - ch.t_star
    assert t_star == pytest.approx(T0_FULLER, abs=0.01)
    assert ch.ratio == pytest.approx(ratio(), abs=0.02)
    assert certify(fine, verify=False).verdict == CHATTERING
    coarse = _solve(1.0, 6.0, False, 40)
    assert detect_chattering(coarse, resolve=False) is None
    assert certify(coarse, verify=False).verdict == INCONCLUSIVE  # the interior arc


def test_refinement_of_another_candidate_is_refused():
    """A refinement belongs to the solution it refined: another parameter value, another
    problem or another transcription's start gives "not applicable" (before: the minimum-
    time double integrator at d = 2 was "bang-bang certified" with the refinement of d = 5,
    final times 2.83 and 4.47), single- and multi-phase alike."""
    ms = MultipleShooting(_readme_di(), nodes=40)
    sol2, sol5 = ms.solve({"d": 2.0}), ms.solve({"d": 5.0})
    r2, r5 = refine_switching(sol2), refine_switching(sol5)
    assert certify(sol2, r2).verdict == CERTIFIED
    cert = certify(sol2, r5)
    # (its verdict said "the solve did not converge": the solve did, the pairing is wrong)
    assert cert.verdict == OTHER_CANDIDATE and "other values of d" in cert.reasons[0]
    rebuilt = MultipleShooting(_readme_di(), nodes=40).solve({"d": 2.0})
    assert certify(rebuilt, r2).verdict == CERTIFIED  # the same problem, built twice
    other = MultipleShooting(_readme_di(umax=2.0), nodes=40).solve({"d": 2.0})
    assert "another problem" in certify(other, r2).reasons[0]
    ms30 = MultipleShooting(fuller(1.0, 5.0), nodes=30)
    coarse = ms30.solve({})
    finer = MultipleShooting(ms30.problem, nodes=60).solve({})
    assert "started from a transcription" in certify(finer, refine_switching(coarse)).reasons[0]

    from ocp.structure.phase_refinement import refine_phases

    tr = MultipleShooting(_two_phase(), nodes=[20, 20])
    sa, sb = tr.solve({"d": 2.0}), tr.solve({"d": 3.0})
    assert certify(sa, refine_phases(sb)).verdict == OTHER_CANDIDATE


def test_failed_multi_phase_solve_is_refused_not_an_error():
    """A failed multi-phase solve's iterate, certified without a refinement, gets "not
    applicable" (before: a ValueError asking for a refinement of a failed solve)."""
    tr = MultipleShooting(_two_phase(), nodes=[20, 20], ipopt_options={"max_iter": 1})
    with pytest.raises(SolveError) as info:
        tr.solve({"d": 2.0})
    assert certify(info.value.iterate).verdict == NOT_APPLICABLE


def _readme_di(umax: float = 1.0) -> OptimalControlProblem:
    """The README's minimum-time double integrator (its default guess of T)."""
    return min_time_double_integrator(umax=umax, T_guess=None, name="double_integrator")


def test_a_structure_of_ones_own_must_be_the_refined_one():
    """``structure=`` cannot talk the certificate out of a doubt: it must be the structure
    the refinement solved (before: any structure without interior arcs was accepted, with or
    without a refinement)."""
    sol = MultipleShooting(_readme_di(), nodes=40).solve({"d": 2.0})
    st = detect_structure(sol)
    r = refine_switching(sol, st)
    assert certify(sol, r, structure=st).verdict == CERTIFIED
    with pytest.raises(ValueError, match="structure the refinement solved"):
        certify(sol, structure=st)
    other = detect_structure(_solve(1.0, 5.0, False, 60))  # five bang arcs, not two
    with pytest.raises(ValueError, match="structure the refinement solved"):
        certify(sol, r, structure=other)
