"""A certificate per arc type (issue 44 items 1 and 3): interior, singular, state boundary.

Independent references: the scalar LQ problem's closed form (``J = tanh(1)/2``, the
Riccati solution ``S(t) = tanh(T - t)``); the singular problem's (``u = -1`` until
``t = 1``, then the singular arc ``u = 0``, ``J = 1/3``, ``sigma = lambda``, ``sigma'' =
-2u``: order 1, Kelley's coefficient 2); Bryson--Denham's (``l = 1/9``: junctions at
``3l`` and ``1 - 3l``, ``J = 4/(9l) = 4``, the costate ``lambda_x = 2/(9 l^2) = 18``
jumping to 0 at the entry and to -18 at the exit: ``eta = 18`` at both).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ocp import (
    Collocation,
    MultipleShooting,
    OptimalControlProblem,
    SolveError,
    certify,
    refine_switching,
)
from ocp.certificate.arc_record import ArcCheck
from ocp.certificate.arc_verdict import NOT_EXTREMAL, junction_margin, settle
from ocp.certificate.checks import CERTIFIED
from ocp.certificate.refined_state_arcs import check_refined_boundary
from ocp.structure.arcs import Arc, ArcStructure, SwitchingStructure, detect_structure
from ocp.structure.singular import singular_algebra


def lq() -> OptimalControlProblem:
    p = OptimalControlProblem("lq")
    x, u = p.state("x"), p.control("u")
    p.set_dynamics([u])
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(1.0)
    p.minimize_integral((x**2 + u**2) / 2)
    return p


def singular(T: float = 2.0) -> OptimalControlProblem:
    p = OptimalControlProblem("bang_singular")
    x, u = p.state("x"), p.control("u", lower=-1, upper=1)
    p.set_dynamics([u])
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(T)
    p.minimize_integral(x**2)
    return p


def bryson_denham(form: str, order: int = 2, l_: float = 1 / 9) -> OptimalControlProblem:
    """x <= l as a declared state bound, bound_state or a path constraint; order 2
    (x'' = u) or 3 (x''' = u)."""
    p = OptimalControlProblem(f"bryson_denham_{form}_{order}")
    x = p.state("x", upper=l_) if form == "state" else p.state("x")
    names = ["v", "a"][:order - 1]
    chain = [p.state(n) for n in names]
    u = p.control("u")
    if form == "bound_state":
        p.bound_state("x", upper=l_)
    elif form == "path":
        p.path_constraint(x, upper=l_)
    rhs = {"x": chain[0]}
    for n, nxt in zip(names, [*chain[1:], u], strict=True):
        rhs[n] = nxt
    p.set_dynamics(rhs)
    ends = {"x": (0.0, 0.0), "v": (1.0, -1.0), "a": (0.0, 0.0)}
    for n, s in zip(["x", *names], [x, *chain], strict=True):
        p.initial_constraint(s, ends[n][0])
        p.terminal_constraint(s, ends[n][1])
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2 / 2)
    return p


@pytest.fixture(scope="module")
def lq_solutions():
    return {"collocation": Collocation(lq(), 10).refine({}, tol=1e-8),
            "shooting": MultipleShooting(lq(), nodes=40).solve({})}


@pytest.mark.parametrize("how", ["collocation", "shooting"])
def test_lq_certified_interior_arc(lq_solutions, how):
    sol = lq_solutions[how]
    c = certify(sol)
    assert c.verdict == "certified (interior)" and c.certified, c.reasons
    (arc,) = c.arcs
    assert arc.kind == "interior" and arc.status == "holds"
    assert arc.residuals["stationarity |H_u|"] < (1e-8 if how == "collocation" else 1e-3)
    assert arc.residuals["min H_uu"] == pytest.approx(1.0)  # Legendre-Clebsch
    assert arc.residuals["costate equation"] < 1e-3
    # the Jacobi test ran and found no conjugate point; its Riccati matrix at the first
    # sample is tanh(T - t) (free final state: S(T) = 0, S' = S^2 - 1)
    assert arc.residuals["Jacobi min sigma(dX)"] > 0.5
    note = [n for n in arc.notes if n.startswith("no conjugate point")]
    S0 = float(note[0].split("[[")[1].split("]]")[0])
    t1 = float(sol.t[1]) if how == "collocation" else 0.5 * (sol.t[1] + sol.t[2])
    # (to the samples' accuracy: O(h) on the shooting grid)
    assert S0 == pytest.approx(math.tanh(1.0 - t1), abs=2e-3 if how == "collocation" else 1e-2)
    assert c.to_dict()["arcs"][0]["kind"] == "interior"


@pytest.fixture(scope="module")
def bang_singular():
    sol = MultipleShooting(singular(), nodes=40).solve({})
    return sol, refine_switching(sol)


def test_singular_algebra_order_and_kelley():
    alg = singular_algebra(singular(), "u")
    assert alg.order == 1
    assert float(alg.kelley) == 2.0 and float(alg.law) == 0.0


def test_bang_singular_refined_to_machine_precision_and_certified(bang_singular):
    sol, r = bang_singular
    assert abs(sol.objective - 1 / 3) > 1e-10  # the transcription alone is not there
    assert r.kinds == ["min", "singular"]
    assert abs(r.objective - 1 / 3) <= 1e-10
    assert abs(r.switch_times[0] - 1.0) <= 1e-10
    c = certify(sol, r)
    assert c.verdict == "certified (bang, singular order 1)" and c.certified, c.reasons
    (arc,) = [a for a in c.arcs if a.kind == "singular"]
    assert arc.order == 1 and arc.residuals["Kelley (-1)^k b min"] == pytest.approx(2.0)
    assert arc.residuals["singular control |u - u_s|"] <= 1e-12
    assert certify(sol).verdict == "certified (bang, singular order 1)"


def test_bang_singular_off_junction_is_refuted(bang_singular):
    sol, r = bang_singular
    bad = dataclasses.replace(r, durations=r.durations * np.array([1.05, 0.95]))
    c = certify(sol, bad)
    assert c.verdict == NOT_EXTREMAL and not c.certified
    assert any(s.startswith("singular arc of u on [") for s in c.reasons)


def test_half_covered_interior_arc_is_never_certified(bang_singular):
    """Structure detection's doubt is answered only where holding rows cover the interior
    arc, all of it but a junction margin at each end: a bogus interior arc on [0, 2], whose
    second half is the certified singular row, keeps the verdict "inconclusive"."""
    sol, r = bang_singular
    cert = certify(sol, r)
    assert cert.certified
    end = r.T
    bogus = ArcStructure.from_controls([SwitchingStructure("u", [Arc("interior", 0.0, end)],
                                                           -1.0, 1.0)])
    for margin in (0.0, junction_margin(sol)):
        c = dataclasses.replace(cert, verdict=CERTIFIED, reasons=[])
        settle(c, bogus, refuting=True, margin=margin)
        assert c.verdict == "inconclusive" and not c.certified
        assert "structure detection finds an interior arc on [0, 2]" in c.reasons[-1]
    # the arc as detected (its junction a grid interval from the refined one) is covered
    (arc,) = [a for a in detect_structure(sol).per_control[0].arcs if a.kind == "interior"]
    assert abs(arc.start - 1.0) < junction_margin(sol)
    c = dataclasses.replace(cert, verdict=CERTIFIED, reasons=[])
    settle(c, detect_structure(sol), refuting=True, margin=junction_margin(sol))
    assert c.verdict == "certified (bang, singular order 1)", c.reasons


class _Solved(dict):
    """Bryson--Denham per form, collocation with mesh refinement, solved on first use;
    ``refined(form)`` adds its refinement (also on first use)."""

    def __missing__(self, form: str):
        self[form] = Collocation(bryson_denham(form), 20).refine({}, tol=1e-8)
        return self[form]

    def refined(self, form: str):
        key = ("refined", form)
        if key not in self:
            self[key] = refine_switching(self[form])
        return self[form], self[key]


@pytest.fixture(scope="module")
def bd_solutions():
    return _Solved()


@pytest.mark.parametrize("form", ["state", "bound_state", "path"])
def test_bryson_denham_certified_with_its_boundary_arc(bd_solutions, form):
    sol = bd_solutions[form]
    assert sol.objective == pytest.approx(4.0, abs=1e-6)
    c = certify(sol)
    assert c.verdict == "certified (interior, state boundary order 2)", c.reasons
    (arc,) = [a for a in c.arcs if a.kind == "state boundary"]
    assert arc.order == 2 and arc.side == "upper" and arc.status == "holds"
    # junctions placed where the costate's two sides agree across grad c (detected: to a
    # mesh interval)
    assert arc.residuals["entry time"] == pytest.approx(1 / 3, abs=1e-2)
    assert arc.residuals["exit time"] == pytest.approx(2 / 3, abs=1e-2)
    assert arc.residuals["entry jump eta"] == pytest.approx(18.0, rel=1e-3)
    assert arc.residuals["exit jump eta"] == pytest.approx(18.0, rel=1e-3)


@pytest.mark.parametrize("form", [pytest.param("state", marks=pytest.mark.slow),
                                  pytest.param("bound_state", marks=pytest.mark.slow), "path"])
def test_bryson_denham_refined_and_its_boundary_arc_certified(bd_solutions, form):
    """The default route refines the regular interior arcs (costate copies) and the boundary
    arc's junctions; the refined certificate checks the boundary arc itself: the costate
    rebuilt across it by indirect adjoining, its jumps eta = 18 at both junctions, the
    density mu = 0 and the total measure 36 (read also from the transcription's path
    multipliers where the constraint is a path constraint)."""
    sol, r = bd_solutions.refined(form)
    assert r.kinds == ["interior", "boundary", "interior"]
    assert r.objective == pytest.approx(4.0, abs=1e-12)
    # J is stationary in the junctions: they are known to about sqrt(eps)
    assert r.switch_times == pytest.approx([1 / 3, 2 / 3], abs=1e-7)
    c = certify(sol, r)
    assert c.verdict == "certified (interior, state boundary order 2)", c.reasons
    assert c.checked_from == 0.0
    (arc,) = [a for a in c.arcs if a.kind == "state boundary"]
    assert arc.status == "holds" and arc.order == 2
    assert (arc.start, arc.end) == pytest.approx(r.switch_times, abs=1e-15)
    assert arc.residuals["entry jump eta"] == pytest.approx(18.0, rel=1e-6)
    assert arc.residuals["exit jump eta"] == pytest.approx(18.0, rel=1e-6)
    assert arc.residuals["total measure pi_0"] == pytest.approx(36.0, rel=1e-6)
    assert arc.residuals["density mu >= 0 (a_0 non-increasing)"] <= 1e-10
    if form == "path":
        assert arc.residuals["transcription's measure"] == pytest.approx(36.0, rel=1e-4)
    else:
        assert "transcription's measure" not in arc.residuals
    first = [a for a in c.arcs if a.kind == "interior" and a.end <= 0.34]
    assert first and first[0].status == "holds"  # checked with its costate copy


def test_bryson_denham_wrong_candidates_refuted(bd_solutions):
    sol, r = bd_solutions.refined("path")
    bad = dataclasses.replace(r, durations=r.durations * np.array([1.02, 0.98, 1.0]))
    c = certify(sol, bad)
    assert c.verdict == NOT_EXTREMAL and not c.certified
    # a costate that jumps the wrong way at the entry: eta < 0 is refuted by the sign check
    row = [a for a in certify(sol, r).arcs if a.kind == "state boundary"][0]
    t, x, u, k = r.samples(400)
    sel = k == 1
    arc = ArcCheck("state boundary", row.control, row.start, row.end, side="upper")
    pr = r.problem.costate_copies.origin
    before = np.array([18.0 - 40.0, 0.0])  # true: (18, 0)
    check_refined_boundary(arc, pr, 0, t[sel], x[sel][:, :2], u[sel], r.pv, before,
                           x[k == 2][0, 4:6], 1e-6, 0.0)
    assert arc.status == "fails" and arc.residuals["entry jump eta"] == pytest.approx(-22.0)


def test_lq_refined_by_default_route_and_certified(lq_solutions):
    sol = lq_solutions["shooting"]
    r = refine_switching(sol)
    assert r.kinds == ["interior"]
    assert r.objective == pytest.approx(math.tanh(1.0) / 2, abs=1e-14)
    assert r.x0[1] == pytest.approx(math.tanh(1.0), abs=1e-12)  # lambda(0) = S(0) x(0)
    c = certify(sol, r)
    assert c.verdict == "certified (interior)", c.reasons


def first_order_tail() -> OptimalControlProblem:
    """``min int u^2/2 + x``, ``x' = u``, ``x(0) = 1``, ``x >= 0``, ``T = 2``: ``u = t - sqrt 2``
    until ``x`` reaches 0 at ``t = sqrt 2``, then a boundary arc of order 1 to the end with
    ``lambda = 0``, density ``mu = 1`` and no jump (a regular H: the control is continuous),
    ``J = 2 sqrt(2) / 3``."""
    p = OptimalControlProblem("first_order_tail")
    x, u = p.state("x", lower=0.0), p.control("u")
    p.set_dynamics([u])
    p.initial_constraint(x, 1.0)
    p.fixed_final_time(2.0)
    p.minimize_integral(u**2 / 2 + x)
    return p


def test_entry_jump_inside_the_junctions_resolution_is_no_sign_violation():
    """The softlanding tail's case (issue 44, certificate item 4): a boundary arc with a
    density and no entry jump. The jump estimated from the costate lines beside a junction
    known to a grid interval is -mu h-ish (here -0.039 on 40 intervals, -0.027 on 80: it
    shrinks with the grid); it was a sign failure, and H_u on the arc (u = lambda = 0) was
    judged relative to terms that vanish there. Now it is certified, with the reason."""
    sol = MultipleShooting(first_order_tail(), nodes=40).solve({})
    assert sol.objective == pytest.approx(2 * math.sqrt(2) / 3, abs=3e-4)
    c = certify(sol)
    assert c.verdict == "certified (interior, state boundary order 1)", c.reasons
    (arc,) = [a for a in c.arcs if a.kind == "state boundary"]
    assert arc.status == "holds" and arc.order == 1
    assert arc.residuals["entry time"] == pytest.approx(math.sqrt(2), abs=0.05)
    eta, density = arc.residuals["entry jump eta"], arc.residuals["multiplier mu dt max"]
    assert density == pytest.approx(1.0 * 2 / 40, rel=1e-2)  # mu = 1 over one interval
    assert -density <= eta < 0
    assert any(n.startswith("entry jump eta") and "within the numerical error" in n
               for n in arc.notes)


@pytest.mark.parametrize("build", [singular, lambda: bryson_denham("path")])
def test_stopped_early_never_certified(build):
    with pytest.raises(SolveError) as info:
        MultipleShooting(build(), nodes=30, ipopt_options={"max_iter": 3}).solve({})
    c = certify(info.value.iterate)
    assert not c.certified and c.verdict.startswith("not applicable")


def test_lq_is_a_qp_solved_in_one_iteration():
    """The LQ problem is a QP: Ipopt converges in one iteration, so max_iter 3 does not stop
    it early, and its certificate is that of a converged optimum."""
    sol = MultipleShooting(lq(), nodes=30, ipopt_options={"max_iter": 3}).solve({})
    assert sol.success and sol.iterations == 1
    assert certify(sol).verdict == "certified (interior)"


@pytest.mark.slow
def test_third_order_constraint_touch_is_not_certified_as_a_boundary_arc():
    """x''' = u, x <= l: a constraint of order 3, whose optimal contacts are touch points
    (boundary arcs of odd order >= 3 are generically not optimal). The transcription shows
    short "boundary arcs" a mesh interval long: the certificate reads the order (3) and
    does not certify them."""
    sol = Collocation(bryson_denham("state", order=3, l_=0.05), 20).refine({}, tol=1e-6)
    c = certify(sol)
    assert not c.certified and c.verdict == "inconclusive"
    rows = [a for a in c.arcs if a.kind == "state boundary"]
    assert rows and all(a.order == 3 and a.status != "holds" for a in rows)
