"""Control-only path constraints are faces of a polyhedral control set (issue 21).

On the tree before this change, with four on/off thrusters and ``u1 + u2 <= 1``,
``u3 + u4 <= 1`` (tests/ocp_suite/thrusters_2d.py):

* ``detect_structure`` labelled the y thrusters as riding ``u1 + u2 <= 1``
  (boundary arcs of a constraint in which they do not appear);
* ``refine_switching`` failed with "relative degree above 3 in ['u4']";
* ``certify`` called the coupling constraints state constraints ("inconclusive").

With three mode controls on the simplex ``w1 + w2 + w3 = 1``
(tests/ocp_suite/modal_double_integrator.py) every control was labelled a
boundary arc of the equality and the refinement crashed inside CasADi.

References are independent of ``ocp``: the closed-form bang-off-bang optimum of
the fuel-optimal double integrator (Athans and Falb 1966, ch. 8), checked by
``scipy.integrate.solve_ivp`` in the suite files.
"""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np
import pytest

from ocp import MultipleShooting, OptimalControlProblem
from ocp.certificate.certify import CERTIFIED, certify
from ocp.structure.constraint_kinds import (
    CONTROL,
    MIXED,
    STATE,
    constraint_kind,
    coupled_groups,
    riding_controls,
)
from ocp.structure.control_set import control_polytope, polytope_vertices, vertex_scores
from ocp.structure.flows import Mode
from ocp.structure.switching import detect_structure, refine_structure, refine_switching
from tests.oracles.ocp_suite.modal_double_integrator import (
    modal_double_integrator,
    modal_exact,
    modal_simulated,
    modal_switch_times,
)
from tests.oracles.ocp_suite.problems import rayleigh_mixed
from tests.oracles.ocp_suite.thrusters_2d import (
    thrusters_2d,
    thrusters_2d_exact,
    thrusters_2d_simulated,
    thrusters_2d_switch_times,
)

NODES = 60


@cache
def solved(name: str):
    build = {"thrusters": thrusters_2d, "modal": modal_double_integrator}[name]
    sol = MultipleShooting(build(), nodes=NODES).solve()
    assert sol.success
    return sol


@cache
def refined(name: str):
    return refine_switching(solved(name))


def test_references_agree():
    """The closed forms and the solve_ivp replays of their switching structures agree."""
    xT, fuel = thrusters_2d_simulated()
    assert np.max(np.abs(xT)) < 1e-10 and fuel == pytest.approx(thrusters_2d_exact(), rel=1e-12)
    xT, fuel = modal_simulated()
    assert np.max(np.abs(xT)) < 1e-10 and fuel == pytest.approx(modal_exact(), rel=1e-12)


def test_constraint_kinds():
    """Control-only, mixed and state constraints are told apart (no such helper before)."""
    p = thrusters_2d()
    assert [constraint_kind(p, c) for c in p.path] == [CONTROL, CONTROL]
    assert riding_controls(p, p.path[0]) == ()
    assert coupled_groups(p) == [("u1", "u2"), ("u3", "u4")]
    r = rayleigh_mixed()  # u + x1/6 <= 0 stays mixed
    assert [constraint_kind(r, c) for c in r.path] == [MIXED]
    assert riding_controls(r, r.path[0]) == ("u",)
    q = OptimalControlProblem("state_constrained")
    x, v = q.state("x"), q.state("v")
    a, b = q.control("a", -1, 1), q.control("b", -1, 1)
    q.set_dynamics({"x": v, "v": a})
    q.path_constraint(x, upper=1.0, name="x <= 1")
    q.path_constraint(b + v, upper=1.0, name="b + v <= 1")
    # x <= 1 on x alone is x's bound: structure detection sees it as a state constraint
    assert [constraint_kind(q, c) for c in q.structure_path] == [MIXED, STATE]
    # x'' = a: only a can hold x <= 1 (relative degree 2); b is not in it
    assert riding_controls(q, "x <= 1") == ("a",)


def test_control_not_in_a_state_constraint_does_not_ride_it():
    """Bryson-Denham (x'' = a, x <= 1/9, boundary arc on [1/3, 2/3]) beside an independent
    y' = b, |b| <= 1, maximising int y with y(0) = y(1) = 0 (b = +1, then -1 at t = 1/2,
    inside the boundary arc). Only a holds x <= 1/9; before, b was labelled as riding it
    on [1/3, 2/3]."""
    p = OptimalControlProblem("bryson_denham_and_b")
    x, v, y = p.state("x"), p.state("v"), p.state("y")
    a, b = p.control("a", -10, 10), p.control("b", -1, 1)
    p.set_dynamics({"x": v, "v": a, "y": b})
    p.path_constraint(x, upper=1 / 9, name="x <= 1/9")
    for s, start, end in ((x, 0, 0), (v, 1, -1), (y, 0, 0)):
        p.initial_constraint(s, start)
        p.terminal_constraint(s, end)
    p.fixed_final_time(1.0)
    p.minimize_integral(a**2 / 2 - y)
    sol = MultipleShooting(p, nodes=NODES).solve()
    st = detect_structure(sol)
    assert [x.kind for x in st.per_control[0].arcs] == ["interior", "boundary", "interior"]
    kinds_b = [(x.kind, x.constraint) for x in st.per_control[1].arcs]
    assert kinds_b == [("max", None), ("min", None)]
    assert st.per_control[1].switch_times == pytest.approx([0.5], abs=1.5 / NODES)


def test_structure_has_bang_arcs_only():
    """No control rides a control-only constraint: every arc is a bang, at the closed-form
    switches to the grid's resolution (before: u3/u4 'boundary' on u1 + u2 <= 1)."""
    sol = solved("thrusters")
    st = detect_structure(sol)
    assert st.bang_bang and st.refinable
    assert all(a.kind in ("max", "min") and a.constraint is None
               for s in st.per_control for a in s.arcs)
    h = sol.T / NODES
    assert np.allclose(st.switch_times, thrusters_2d_switch_times(), atol=1.5 * h)
    # the faces the controls sit on are reported apart from state constraints
    u1_on = detect_structure(sol).per_control[0].arcs[-1]
    assert u1_on.kind == "max" and u1_on.faces == ("u1 + u2 <= 1",) and u1_on.active == ()


def test_refinement_reaches_the_closed_form():
    """Switching times and fuel to 1e-10 of the closed form (before: 'relative degree above
    3 in ['u4']')."""
    r = refined("thrusters")
    assert r.exact
    assert np.allclose(r.switch_times, thrusters_2d_switch_times(), rtol=0, atol=1e-10)
    assert r.objective == pytest.approx(thrusters_2d_exact(), rel=1e-10)
    # the controls sit at vertices of each axis' triangle
    for vals in r.values:
        assert vals[0] + vals[1] <= 1 and vals[2] + vals[3] <= 1


def test_certified_over_the_polytope():
    """The Hamiltonian is minimised over the polytope: certified from the refinement and
    from the transcription (before: 'inconclusive: state constraint active')."""
    c = certify(solved("thrusters"), refined("thrusters"))
    assert c.verdict == CERTIFIED, c.reasons
    assert c.sigma_sign_agreement == 1.0 and c.state_constraint_active_intervals == []
    c = certify(solved("thrusters"))
    assert c.verdict == CERTIFIED, c.reasons


def test_moved_switch_is_not_certified():
    """A candidate with one switch moved by 0.05 (still bang-off-bang, on the polytope's
    vertices) fails the minimum condition."""
    r = refined("thrusters")
    dur = r.durations.copy()
    dur[0] += 0.05
    dur[1] -= 0.05
    c = certify(solved("thrusters"), dataclasses.replace(r, durations=dur))
    assert c.verdict != CERTIFIED
    assert any("switch" in why or "sits at" in why for why in c.reasons), c.reasons


def test_equality_coupled_modes():
    """Three modes on the simplex w1 + w2 + w3 = 1: one mode per arc (brake, coast,
    accelerate), refined to the closed form and certified; a moved switch is not
    (before: every control a 'boundary' arc of the equality, refinement crashed)."""
    sol = solved("modal")
    st = detect_structure(sol)
    assert st.kinds == [("min", "min", "max"), ("min", "max", "min"), ("max", "min", "min")]
    r = refined("modal")
    assert np.allclose(r.switch_times, modal_switch_times(), rtol=0, atol=1e-10)
    assert r.objective == pytest.approx(modal_exact(), rel=1e-10)
    c = certify(sol, r)
    assert c.verdict == CERTIFIED, c.reasons
    assert certify(sol).verdict == CERTIFIED
    dur = r.durations.copy()
    dur[1] += 0.05
    dur[2] -= 0.05
    assert certify(sol, dataclasses.replace(r, durations=dur)).verdict != CERTIFIED


def test_suboptimal_fixed_structure_is_not_certified():
    """Brake, accelerate, coast (no coast in the middle) is feasible: brake and accelerate
    sqrt(2) each, coast T - 2 sqrt(2); its fuel 2 sqrt(2) is 2.4 times the optimum. Refined
    within that fixed structure it is an extremal of nothing: the Hamiltonian is not
    minimised over the simplex, and the certificate says so."""
    p = modal_double_integrator()
    on, off = Mode("max"), Mode("min")
    r = refine_structure(p, ((off, off, on), (on, off, off), (off, on, off)),
                         np.array([1.4, 1.4, 1.2]), np.array([2.0, 0.0]), {})
    assert r.durations[:2] == pytest.approx([np.sqrt(2)] * 2, rel=1e-12)
    assert r.objective == pytest.approx(2 * np.sqrt(2), rel=1e-12)
    c = certify(solved("modal"), r)
    assert c.verdict == "not bang-bang"
    assert c.sigma_sign_agreement < 0.5


def test_vertex_inside_the_box():
    """Thrusters that could each push 2 but share a supply of 1 (u in [0, 2], u1 + u2 <= 1):
    a thruster on sits at a vertex of the triangle inside its own bounds. Detected as a
    vertex arc (held by its pair's constraint), refined with its value fixed by that
    constraint to the same closed form, certified; a moved switch is not (before: the
    'on' arcs were interior or boundary arcs and the refinement failed)."""
    sol = MultipleShooting(thrusters_2d(umax=2.0), nodes=NODES).solve()
    st = detect_structure(sol)
    assert st.refinable and st.bang_bang
    on = [a for s in st.per_control for a in s.arcs if a.kind not in ("max", "min")]
    assert len(on) == 4 and {a.kind for a in on} == {"vertex"}
    assert {a.constraint for a in on} == {"u1 + u2 <= 1", "u3 + u4 <= 1"}
    r = refine_switching(sol, st)
    assert np.allclose(r.switch_times, thrusters_2d_switch_times(), rtol=0, atol=1e-10)
    assert r.objective == pytest.approx(thrusters_2d_exact(), rel=1e-10)
    assert r.values[0] == pytest.approx((0.0, 1.0, 0.0, 1.0), abs=1e-14)
    assert certify(sol, r).verdict == CERTIFIED
    dur = r.durations.copy()
    dur[0] += 0.05
    dur[1] -= 0.05
    assert certify(sol, dataclasses.replace(r, durations=dur)).verdict != CERTIFIED


@pytest.mark.parametrize("box", [True, False], ids=["box", "no box"])
def test_single_control_cap(box):
    """Minimum time 0 -> 1 of x'' = u, u in [-1, 1/2] (with a box [-1, 1] and the cap
    u <= 1/2 a control-only constraint, or with no box and -1 <= u <= 1/2 the constraint):
    u = 1/2 for t1 then -1 for t1/2, 0.375 t1^2 = 1, T = 1.5 sqrt(8/3) (closed form).
    The cap on u alone is u's bound (ocp.definition.normal_form): the arcs are bang arcs
    "max" (at 1/2) and "min", however the bounds are written (before the normal form:
    vertex arcs of the interval [-1, 1/2]; before issue 21, 'boundary' then 'interior',
    not refinable)."""
    p = OptimalControlProblem("capped_double_integrator")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -1, 1) if box else p.control("u")
    p.set_dynamics({"x": v, "v": u})
    p.path_constraint(u, upper=0.5, lower=-1.0 if not box else -np.inf, name="u <= 1/2")
    for s, start, end in ((x, 0, 1), (v, 0, 0)):
        p.initial_constraint(s, start)
        p.terminal_constraint(s, end)
    p.free_final_time(0.1, 10, guess=2)
    p.minimize_terminal(p.T)
    sol = MultipleShooting(p, nodes=40).solve()
    kinds = [a.kind for a in detect_structure(sol).per_control[0].arcs]
    assert kinds == ["max", "min"]
    r = refine_switching(sol)
    assert r.T == pytest.approx(1.5 * np.sqrt(8 / 3), rel=1e-12)
    assert r.values == pytest.approx([0.5, -1.0], abs=1e-15)
    assert certify(sol, r).verdict == CERTIFIED


def test_mode_outside_the_control_set_is_refused():
    """Both x thrusters on is no vertex of the control set: a clear error, not a solve."""
    p = thrusters_2d()
    on, off = Mode("max"), Mode("min")
    with pytest.raises(ValueError, match="not a vertex of the control set"):
        refine_structure(p, ((on, on, off, off),), np.array([3.0]),
                         np.array([1.0, 0.0, 0.5, 0.0]), {})


def test_polytope_vertices_and_linear_programme():
    """Vertex enumeration and the per-sample LP against hand-derived answers."""
    # triangle u1, u2 >= 0, u1 + u2 <= 1
    G = np.array([[1.0, 0], [0, 1], [-1, 0], [0, -1], [1, 1]])
    h = np.array([1.0, 1, 0, 0, 1])
    V = polytope_vertices(G, h)
    assert sorted(map(tuple, np.round(V, 12))) == [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)]
    p = modal_double_integrator()
    poly = control_polytope(p, ("w1", "w2", "w3"), np.zeros(0))
    assert poly is not None
    assert sorted(map(tuple, poly.vertices)) == [(0, 0, 1), (0, 1, 0), (1, 0, 0)]
    # sigma shifted by a constant (the equality's multiplier) leaves the minimiser alone;
    # a tie between two vertices is degenerate (gap 0)
    sc = vertex_scores(poly, np.array([[3.0, 1.0, 2.0], [13.0, 11.0, 12.0], [1.0, 1.0, 2.0]]))
    assert [tuple(poly.vertices[b]) for b in sc.best[:2]] == [(0, 1, 0), (0, 1, 0)]
    assert sc.gap[:2] == pytest.approx([1.0, 1.0]) and sc.gap[2] == 0.0
