"""Non-affine grounds in the simulator: the integrated yielding path against the exact path,
against an independent solve_ivp, its convergence, the energy ledger, user laws."""

import math

import numpy as np
import pytest

from softlanding import Impact, Impedance, Robot, simulate, simulate_batch
from softlanding.model.controllers import ForceSchedule, Rigid
from softlanding.model.ground import LINEAR_GROUND, AddedMassGround, CustomGround, DragGround
from softlanding.model.terrain import paper_rig_units, poppy_seed_added_mass, power_law_ground
from softlanding.simulation.groundcode import kernel_law, law_expressions, needs_integration
from tests.oracles.ivp_terrain import landing_ivp

ROBOT = Robot(5, 20)
POPPY = poppy_seed_added_mass(paper_rig_units())
RNG = np.random.default_rng(20240611)
CASES = [(RNG.uniform(0, 1), RNG.uniform(0, 1), RNG.uniform(-10, 0)) for _ in range(40)]


def test_zero_drag_integrated_path_reproduces_the_exact_path():
    """c_d = 0 through the DOP853 path: depth to 1e-9, same steps, same stroke and force."""
    worst = 0.0
    limited = Robot(5, 20, u_max=2.0)
    for kp, kd, v0 in CASES:
        for robot in (ROBOT, limited):
            a = simulate(robot, Impact(v0), Impedance(kp, kd))
            b = simulate(robot, Impact(v0), Impedance(kp, kd), method="integrate")
            assert a.status == b.status
            if not a.rest_proven:
                continue
            assert a.steps == b.steps and a.feasible == b.feasible
            worst = max(worst, abs(a.depth - b.depth), abs(a.u_peak - b.u_peak),
                        abs(a.stroke_min - b.stroke_min), abs(a.energy.actuator
                                                              - b.energy.actuator))
    assert worst < 1e-9


def test_zero_drag_ground_objects_take_the_exact_path():
    assert not needs_integration(DragGround(0.0))
    assert not needs_integration(AddedMassGround(0.0, 1.0, 1.0))
    assert needs_integration(DragGround(0.1)) and needs_integration(POPPY)
    a = simulate(ROBOT, Impact(-3), Impedance(0.3, 0.4), DragGround(0.0))
    b = simulate(ROBOT, Impact(-3), Impedance(0.3, 0.4))
    assert a.depth == b.depth and not a.energy.integrated


@pytest.mark.parametrize("ground", [DragGround(0.05), DragGround(1.0), POPPY,
                                    AddedMassGround(0.01, 2.0, 1.0, c_d=0.2)],
                         ids=["drag-0.05", "drag-1", "poppy-added-mass", "cone-and-drag"])
def test_agrees_with_independent_solve_ivp(ground):
    """DOP853 at rtol 1e-12 in scipy, written from the equations: depths within 1e-7."""
    kw = (dict(c_d=ground.c_d) if isinstance(ground, DragGround) else
          dict(c_d=ground.c_d, pi_a=ground.pi_a, radius=ground.radius, kappa=ground.kappa))
    for kp, kd, v0 in CASES[:6]:
        kp, kd = 0.05 + kp, 0.05 + kd
        a = simulate(ROBOT, Impact(v0), Impedance(kp, kd), ground)
        r = landing_ivp(v0, kp, kd, **kw)
        assert abs(a.depth - r["depth"]) < 1e-7
        assert a.steps == r["steps"]
        assert abs(a.t_first_stop - r["t_first_stop"]) < 1e-7
    a = simulate(ROBOT, Impact(-6), Rigid(), ground)
    assert abs(a.depth - landing_ivp(-6, 0, 0, rigid=True, **kw)["depth"]) < 1e-7


def test_depth_converges_as_the_tolerance_tightens():
    """Error against a 1e-14 run falls with the tolerance (roughly in proportion)."""
    g = DragGround(0.2)
    ref = simulate(ROBOT, Impact(-7), Impedance(0.4, 0.3), g, rtol=1e-14).depth
    errs = [abs(simulate(ROBOT, Impact(-7), Impedance(0.4, 0.3), g, rtol=t).depth - ref)
            for t in (1e-6, 1e-8, 1e-10)]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1e-9
    assert errs[0] < 1e-4


@pytest.mark.slow  # compiles fixed_steps, which no other fast test runs (0.9 s, issue 46)
def test_dop853_is_eighth_order_on_the_yielding_field():
    """Fixed steps: halving the step divides the error by about 2^8."""
    from softlanding.simulation.kernel import _f64
    from softlanding.simulation.kernel.yielding import fixed_steps, workspace_nl

    G, fp = kernel_law(DragGround(0.5), 5.0)
    A = np.zeros(25)
    A[1] = 1.0  # x_b' = v_b
    A[9] = -1.0  # v_b' = -1 (no force)
    sysd = (tuple(A), (0.0, 0.0, 0.0, 0.0, 0.0), _f64(G), fp, np.zeros(5))

    def run(n):
        y = np.array([10.0, -3.0, 0.0, -3.0, 1.0, 0, 0, 0, 0])
        fixed_steps(sysd, y, 1.0, n, workspace_nl(1e-12))
        return y[:4].copy()

    ref = run(512)
    e = [np.abs(run(n) - ref).max() for n in (8, 16, 32)]
    orders = [math.log2(e[i] / e[i + 1]) for i in range(2)]
    assert all(7.0 < p < 10.0 for p in orders), orders


@pytest.mark.parametrize("ground", [DragGround(0.2), POPPY, power_law_ground(1.5)],
                         ids=["drag", "added-mass", "power"])
def test_energy_ledger_closes(ground):
    """E0 - ET = ground + drag + grains + actuator to 1e-9 relative (quadratures along the
    solution)."""
    for kp, kd, v0 in CASES[:10]:
        r = simulate(ROBOT, Impact(v0), Impedance(kp, kd), ground)
        if not r.rest_proven:
            continue
        e = r.energy
        assert abs(e.residual) <= 1e-9 * max(1.0, abs(e.E0 - e.ET))
        assert e.drag >= -1e-12 and e.grains >= -1e-12


def test_plastic_work_matches_closed_form_and_drag_is_positive():
    r = simulate(ROBOT, Impact(-5), Impedance(0.3, 0.5), DragGround(0.3))
    assert abs(r.energy.ground - r.depth**2 / 2) < 1e-10
    assert r.energy.drag > 0.1


def test_relanding_on_the_cone_is_inelastic_and_accounted():
    """A hopping landing (no damping) lands again on the grains: the grain ledger takes the
    collision loss and the ledger still closes."""
    g = AddedMassGround(0.02, 3.0, 1.0)
    r = simulate(ROBOT, Impact(-3), Impedance(0.9, 0.0), g, t_max=200)
    assert r.steps >= 2
    e = r.energy
    if r.rest_proven:
        assert abs(e.residual) <= 1e-9 * max(1.0, abs(e.E0 - e.ET))
    traj = r.trajectory()
    assert np.isfinite(traj.x).all()


def test_power_law_rigid_leg_matches_energy_balance():
    """One body on f = d^n: v0^2/2 + d = d^(n+1)/(n+1) at the stop."""
    from scipy.optimize import brentq

    for n, v0 in ((1.5, -4.0), (0.7, -2.0), (2.0, -8.0)):
        r = simulate(ROBOT, Impact(v0), Rigid(), power_law_ground(n))
        d = brentq(lambda x, n=n, v0=v0: x ** (n + 1) / (n + 1) - x - v0 * v0 / 2, 1e-9, 100.0,
                   xtol=1e-15)
        assert abs(r.depth - d) < 1e-9


def test_builtin_laws_in_the_kernel_equal_their_casadi_definition():
    """The kernel's closed forms mirror ground.py's expressions (the one definition)."""
    from numba import njit

    from softlanding.simulation.kernel.groundlaw import law

    @njit
    def ev(G, fp, d, v):
        return law(G, fp, np.zeros(5), d, v)

    for g in (DragGround(0.3), POPPY, AddedMassGround(0.02, 3.0, 1.2, c_d=0.1)):
        G, fp = kernel_law(g, 5.0)
        f = law_expressions(g)
        for d, v in ((0.0, -2.0), (1.3, -0.7), (12.0, -5.0), (2.5, 0.0)):
            got = ev(G, fp, d, v)
            want = [float(x) for x in f(d, v)]
            assert np.allclose(got, want, rtol=1e-13, atol=1e-15)


def test_custom_ground_with_added_mass_gets_the_momentum_flux():
    """A user's mass law: the grains' momentum flux m_a'(d) v^2 is added to the force."""
    g = CustomGround("cone-user", lambda d, v: d, mass=lambda d: 0.01 * d)
    assert abs(float(g.yield_force(2.0, -3.0)) - (2.0 + 0.01 * 9.0)) < 1e-15
    r = simulate(ROBOT, Impact(-4), Impedance(0.3, 0.3), g)
    assert r.rest_proven and abs(r.energy.residual) < 1e-9 * (r.energy.E0 - r.energy.ET)
    assert r.energy.grains > 0


@pytest.mark.slow  # long: the README's command keeps its CPU budget
def test_batch_equals_single_landings_under_drag():
    g = DragGround(0.2)
    kp, kd = np.array([0.1, 0.4, 0.8]), np.array([0.2, 0.6])
    b = simulate_batch(ROBOT, -4.8, kp[:, None], kd[None, :], g, energy=True)
    for i in range(3):
        for j in range(2):
            r = simulate(ROBOT, Impact(-4.8), Impedance(kp[i], kd[j]), g)
            assert b.depth[i, j] == r.depth
            assert b.drag[i, j] == r.energy.drag


def test_open_loop_schedule_and_trajectory_on_drag():
    g = DragGround(0.2)
    sched = ForceSchedule.from_arcs([0.2, 0.3], [8.2, -8.2, 5 / 6])
    r = simulate(Robot(5, 20, 8.2), Impact(-3), sched, g)
    tr = r.trajectory(n=200)
    i = np.searchsorted(tr.t, r.t_first_stop)
    assert abs(-tr.x[i, 2] - r.depth) < 1e-9 or r.steps > 1


def test_linear_ground_unchanged():
    r = simulate(ROBOT, Impact(-1), Impedance(0.2, 0.18), LINEAR_GROUND)
    assert r.steps == 2 and abs(r.depth - 1.634469526521306) < 1e-12


def test_the_terrain_constants_quoted_agree_with_the_code():
    """The module docstring quotes each medium's alpha_z and the paper foot's stiffness; they
    must be the numbers the code computes (it once quoted zeta = 0.488 beside a fit summing
    to 0.464, i.e. 6477 N/m beside the 6159 N/m reported)."""
    import math
    import re

    from softlanding.model import terrain

    doc = terrain.__doc__.replace("\n", " ")
    lp, cp = (sum(terrain.MEDIA[m].rft) for m in ("poppy-lp", "poppy-cp"))
    quoted = re.search(r"alpha_z = ([0-9.]+)`` \(LP\) and ``([0-9.]+)``", doc)
    assert quoted and float(quoted[1]) == round(lp, 3) and float(quoted[2]) == round(cp, 3)
    area = math.pi * (terrain.PAPER_FOOT_DIAMETER / 2) ** 2
    k_cp = terrain.rft_stiffness(terrain.medium("poppy-cp"))
    assert k_cp == pytest.approx(cp * 1e6 * area, rel=1e-12)
    assert f"{k_cp:.0f} N/m" in doc and f"{0.488e6 * area:.0f} N/m" in doc
