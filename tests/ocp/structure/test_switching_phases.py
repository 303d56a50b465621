"""Switching-time refinement and the PMP certificate across the phases of a multi-phase
problem (ocp.structure.phase_refinement, ocp.certificate.phases): exact answers, junction
conditions, and the
single-phase API left as it was."""

import math

import numpy as np
import pytest

from ocp import MultiPhaseProblem, MultipleShooting, OptimalControlProblem, certify
from ocp.certificate.phases import PhasesCertificate, certify_phases
from ocp.structure.phase_refinement import (
    detect_phase_structures,
    local_phase,
    refine_phase_structure,
    refine_phases,
)
from ocp.structure.switching import refine_switching


def _push_brake():
    """Accelerate with 0 <= u <= 1, then brake at -1 with no control, rest to rest over d in
    minimum time: T = 2 sqrt(d), the push lasting sqrt(d)."""
    mp = MultiPhaseProblem("push_brake")
    d = mp.parameter("d")
    push, brake = mp.phase("push"), mp.phase("brake")
    x, v = push.state("x"), push.state("v")
    push.control("u", 0, 1)
    push.set_dynamics({"x": v, "v": push.u[0]})
    push.initial_constraint(x, 0.0)
    push.initial_constraint(v, 0.0)
    push.free_final_time(0.01, 10, guess=1.0)
    xb, vb = brake.state("x"), brake.state("v")
    brake.set_dynamics({"x": vb, "v": -1.0})
    brake.terminal_constraint(xb - d, 0.0)
    brake.terminal_constraint(vb, 0.0)
    brake.free_duration(0.01, 10, guess=1.0)
    mp.link(push, brake)
    mp.minimize(brake.T)
    return mp


def _two_gains(gain: float):
    """Minimum time rest to rest over d: x'' = u in a first phase of fixed length 0.4,
    x'' = gain u after (|u| <= 1). With gain = 1 it is the double integrator: T = 2 sqrt(d)."""
    mp = MultiPhaseProblem("two_gains")
    d = mp.parameter("d")
    a, b = mp.phase("a"), mp.phase("b")
    for ph, k in ((a, 1.0), (b, gain)):
        ph.state("x")
        v = ph.state("v")
        u = ph.control("u", -1, 1)
        ph.set_dynamics({"x": v, "v": k * u})
    a.initial_constraint(a.x[0], 0.0)
    a.initial_constraint(a.x[1], 0.0)
    a.fixed_final_time(0.4)
    b.terminal_constraint(b.x[0] - d, 0.0)
    b.terminal_constraint(b.x[1], 0.0)
    b.free_duration(0.05, 20, guess=2.0)
    mp.link(a, b)
    mp.minimize(b.T)
    return mp


def test_phases_refined_to_machine_precision():
    tr = MultipleShooting(_push_brake(), nodes=[20, 10])
    for d in (1.0, 2.0):
        r = refine_phases(tr.solve({"d": d}))
        assert r.T == pytest.approx(2 * math.sqrt(d), abs=1e-13)
        assert r.t0[1] == pytest.approx(math.sqrt(d), abs=1e-13)
        assert r.kinds == [["max"], [()]]
        assert r.exact
        # junction: the first phase's end costate equals the second phase's start costate
        np.testing.assert_allclose(r.phases[0].terminal_costate[0], r.junction_costates[1],
                                   atol=1e-12)
        assert r.phases[0].terminal_costate[1] == pytest.approx(-1.0, abs=1e-12)  # min time
    traj = r.trajectory(100)
    assert set(np.unique(traj.phase)) == {0, 1}
    assert traj.t[-1] == pytest.approx(r.T)


def test_different_dynamics_per_phase_match_the_closed_form():
    # gain 1: the double integrator split at t = 0.4; switch at sqrt(d), T = 2 sqrt(d)
    tr = MultipleShooting(_two_gains(1.0), nodes=[8, 30])
    d = 3.0
    r = refine_phases(tr.solve({"d": d}))
    assert r.T == pytest.approx(2 * math.sqrt(d), abs=1e-12)
    assert r.kinds[0] == ["max"] and r.kinds[1] == ["max", "min"]
    assert r.switch_times[1][0] == pytest.approx(math.sqrt(d), abs=1e-12)
    # gain 2 after 0.4: x(0.4) = 0.08, v = 0.4; then accelerate at 2, brake at 2:
    # v_peak^2 = v^2 + 4 (d1) with d1 + v_peak^2 / 4 = d - 0.08
    r2 = refine_phases(MultipleShooting(_two_gains(2.0), nodes=[8, 30]).solve({"d": d}))
    vp = math.sqrt((0.16 + 4 * (d - 0.08)) / 2)
    assert r2.T == pytest.approx(0.4 + (vp - 0.4) / 2 + vp / 2, abs=1e-12)


def test_structure_resolved_for_new_parameters_without_a_transcription():
    tr = MultipleShooting(_push_brake(), nodes=[20, 10])
    r = refine_phases(tr.solve({"d": 1.0}))
    r2 = refine_phase_structure(r.problem, r.modes, r.durations, [p.x0 for p in r.phases],
                                {"d": 4.0})
    assert r2.T == pytest.approx(4.0, abs=1e-12)
    assert r2.nlp is r.nlp or r2.path == "newton"  # the same NLP, re-solved


def test_certificate_of_every_phase_and_the_junctions():
    sol = MultipleShooting(_two_gains(1.0), nodes=[8, 30]).solve({"d": 3.0})
    r = refine_phases(sol)
    c = certify(sol, r)
    assert isinstance(c, PhasesCertificate)
    assert c.verdict == "bang-bang certified", c.reasons
    assert len(c.phases) == 2 and all(p.certified for p in c.phases)
    assert max(c.junction_gaps) < 1e-9
    assert c.H_max_abs < 1e-9
    # without a transcription (a structure re-solve) the certificate still runs
    c2 = certify_phases(None, r)
    assert c2.verdict == "bang-bang certified"


def test_a_wrong_switch_is_refuted_across_phases():
    sol = MultipleShooting(_two_gains(1.0), nodes=[8, 30]).solve({"d": 3.0})
    r = refine_phases(sol)
    bad = r.phases[1]
    bad.durations = bad.durations * np.array([1.05, 0.95])  # switch moved, T kept
    c = certify_phases(sol, r)
    assert c.verdict != "bang-bang certified"


def test_single_phase_api_is_unchanged_and_multi_phase_is_pointed_elsewhere():
    p = OptimalControlProblem()
    x, v = p.state("x"), p.state("v")
    p.control("u", -1, 1)
    p.set_dynamics({"x": v, "v": p.u[0]})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - 1.0, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(0.01, 10)
    p.minimize_terminal(p.T)
    sol = MultipleShooting(p, nodes=40).solve()
    r = refine_switching(sol)
    assert r.T == pytest.approx(2.0, abs=1e-13)
    assert certify(sol, r).certified
    msol = MultipleShooting(_push_brake(), nodes=[20, 10]).solve({"d": 1.0})
    with pytest.raises(ValueError, match="refine_phases"):
        refine_switching(msol)
    with pytest.raises(ValueError, match="refinement"):
        certify(msol)


def test_local_phase_views_start_at_zero():
    sol = MultipleShooting(_push_brake(), nodes=[20, 10]).solve({"d": 1.0})
    loc = local_phase(sol, 1)
    assert loc.t[0] == 0.0 and loc.T == pytest.approx(sol.phases[1].T - sol.phases[1].t0)
    st = detect_phase_structures(sol)
    assert st[0].kinds == [("max",)] and st[1].controls == ()


# ------------------------------------------------------------ decision variables
def _peak_two_gains(form: str, gain: float, d: float = 1.0, T1: float = 0.5, T: float = 2.0):
    """The smallest peak force, min peak with -peak <= u <= peak (the epigraph of min max |u|),
    0 -> d at rest in the fixed time T: x'' = u until T1, x'' = gain u after. The limit
    written as the control's bounds or as two path constraints."""
    mp = MultiPhaseProblem("peak_two_gains")
    peak = mp.variable("peak", 0.0, 10.0, guess=2.0)
    a, b = mp.phase("a"), mp.phase("b")
    for ph, k in ((a, 1.0), (b, gain)):
        ph.state("x")
        v = ph.state("v")
        if form == "bounds":
            u = ph.control("u", lower=-peak, upper=peak)
        else:
            u = ph.control("u")
            ph.path_constraint(u - peak, upper=0.0, name="u <= peak")
            ph.path_constraint(u + peak, lower=0.0, name="u >= -peak")
        ph.set_dynamics({"x": v, "v": k * u})
    a.initial_constraint(a.x[0], 0.0)
    a.initial_constraint(a.x[1], 0.0)
    a.fixed_final_time(T1)
    b.terminal_constraint(b.x[0] - d, 0.0)
    b.terminal_constraint(b.x[1], 0.0)
    b.fixed_final_time(T)
    mp.link(a, b)
    mp.minimize(peak)
    return mp


def _peak_closed_form(gain: float, d: float, T1: float, T: float) -> tuple[float, float]:
    """Peak and switch time: u = +peak until ts (in the second phase), -peak after.
    Rest at T: T1 + gain (ts - T1) = gain (T - ts); the distance per unit peak is
    T1^2 / 2 + (T1 + w)(ts - T1) / 2 + w (T - ts) / 2 with w = gain (T - ts)."""
    ts = (T + T1 - T1 / gain) / 2
    w = gain * (T - ts)
    return d / (T1**2 / 2 + (T1 + w) * (ts - T1) / 2 + w * (T - ts) / 2), ts


@pytest.mark.parametrize("form", ["bounds", "path"])
def test_peak_force_across_phases_refines_with_the_switches_and_certifies(form):
    """A decision variable in the control limits of every phase (issue 32): the switching
    times, the phase durations and the peak refined together (the closed form to 1e-12),
    and each phase's certificate minimises H over [-peak, peak] at the refined peak.
    Before: refused ("refined in single-phase problems only")."""
    gain, d, T1, T = 2.0, 1.0, 0.5, 2.0
    P, ts = _peak_closed_form(gain, d, T1, T)
    sol = MultipleShooting(_peak_two_gains(form, gain, d, T1, T), nodes=[6, 18]).solve()
    assert P == pytest.approx(32 / 51, rel=1e-15)  # by hand: 1 / (1/8 + 45/64 + 49/64)
    assert sol.variables["peak"] == pytest.approx(P, rel=1e-2)  # the grid's answer
    r = refine_phases(sol)
    assert r.kinds == [["max"], ["max", "min"]] and r.exact
    assert r.variables["peak"] == pytest.approx(P, rel=1e-12)
    assert r.objective == pytest.approx(P, rel=1e-12)
    assert r.switch_times[1][0] == pytest.approx(ts, abs=1e-12)
    assert r.t0[1] == pytest.approx(T1, abs=1e-14) and r.T == pytest.approx(T, abs=1e-14)
    assert r.phases[1].values == pytest.approx([P, -P], rel=1e-12)  # the control set at P
    np.testing.assert_allclose(r.xT, [d, 0.0], atol=1e-12)  # the phase's own states
    c = certify(sol, r)
    assert c.verdict == "bang-bang certified", c.reasons
    assert max(c.junction_gaps) < 1e-9 and c.H_max_abs < 1e-9


def test_decision_variable_in_the_dynamics_of_phases():
    """x'' = u + w in both phases (|u| <= 1, the first of fixed length 0.4), w a drift in
    [0.1, 0.3]: minimum time 0 -> 1 at rest is T = 2 / sqrt(1 - w^2), least at w = 0.1,
    switching at sqrt((1 - w) / (1 + w))."""
    mp = MultiPhaseProblem("drift_phases")
    w = mp.variable("w", 0.1, 0.3, guess=0.2)
    a, b = mp.phase("a"), mp.phase("b")
    for ph in (a, b):
        ph.state("x")
        v = ph.state("v")
        u = ph.control("u", -1, 1)
        ph.set_dynamics({"x": v, "v": u + w})
    a.initial_constraint(a.x[0], 0.0)
    a.initial_constraint(a.x[1], 0.0)
    a.fixed_final_time(0.4)
    b.terminal_constraint(b.x[0] - 1.0, 0.0)
    b.terminal_constraint(b.x[1], 0.0)
    b.free_duration(0.05, 20, guess=2.0)
    mp.link(a, b)
    mp.minimize(b.T)
    sol = MultipleShooting(mp, nodes=[6, 24]).solve()
    r = refine_phases(sol)
    assert r.variables["w"] == pytest.approx(0.1, abs=1e-14)
    assert r.T == pytest.approx(2 / math.sqrt(0.99), abs=1e-12)
    assert r.switch_times[1][0] == pytest.approx(math.sqrt(0.9 / 1.1), abs=1e-12)
    assert certify(sol, r).verdict == "bang-bang certified"
