"""``ocp.multistart``: problems with several local optima (issue 21).

The case: the time-optimal pendulum swing-up with ``|u| <= 0.4``
(tests/ocp_suite/pendulum_swingup.py). From the default guess a 50-interval
collocation converges to the five-arc extremal (T = 17.288), 75 % above the
global optimum T* = 9.853736876 (four arcs), a value computed independently
by a scipy switching-time optimisation over the bang-bang structures
(``exact()``, recomputed by the slow test). ``multistart`` with 8 seeded
Sobol' starts finds T* and reports the local optima it met.

Fails on today's tree: there is no ``ocp.multistart``.
"""

import math
from functools import cache

import numpy as np
import pytest

from ocp import Collocation, MultipleShooting, OptimalControlProblem, SolveError, multistart
from ocp.definition.errors import ProblemDefinitionError
from tests.oracles.ocp_suite.pendulum_swingup import (
    REFERENCE,
    build,
    coarse_transcription,
    exact,
    structure_optimum,
    transcription,
)


@cache
def run():
    return multistart(transcription(), n=8, seed=0)


@cache
def coarse(seed, workers=None, method="sobol", n=3):
    return multistart(coarse_transcription, n=n, seed=seed, workers=workers, method=method)


def test_default_guess_lands_on_a_local_optimum_and_multistart_finds_the_best():
    res = run()
    local = res.starts[0]  # the default guess, solved as the user would
    assert local.origin == "default" and local.point == {} and local.verified
    assert local.objective > 1.5 * REFERENCE  # the failure: a local optimum
    assert res.success and len(res.starts) == 8
    assert res.best.verified and res.best.success
    assert res.best.objective == pytest.approx(REFERENCE, rel=1e-4)  # 50 intervals
    assert res.fun == res.best.objective
    # the distinct optima: best first, the default's among them, every verified start counted
    objs = [o.objective for o in res.optima]
    assert len(objs) >= 2 and objs == sorted(objs)
    assert any(o == pytest.approx(local.objective, rel=1e-6) for o in objs[1:])
    assert sum(o.count for o in res.optima) + len(res.failures) == 8
    assert res.starts[0].optimum is not None and res.starts[0].optimum > 0
    assert "distinct optima" in res.message


def test_the_best_refines_to_the_independent_value():
    best = run().best
    sol = Collocation(build(), intervals=50).refine(tol=1e-7, guess=best)
    assert sol.mesh_converged
    assert sol.objective == pytest.approx(REFERENCE, rel=1e-6)


def test_starts_cover_the_box_and_are_deterministic():
    res = run()
    pts = [s.point for s in res.starts[1:]]
    assert set(pts[0]) == {"theta", "omega", "u", "T"}
    u = np.array([p["u"] for p in pts])
    T = np.array([p["T"] for p in pts])
    assert np.all(np.abs(u) <= 0.4) and np.all((T >= 0.1) & (T <= 50.0))
    assert T.min() < 1.0 < 10.0 < T.max()  # log-uniform over [0.1, 50]
    # the same seed gives the same starts (and the same outcome); another seed others
    assert [s.point for s in coarse(0).starts] == [s.point for s in res.starts[:3]]
    lhs = coarse(1, method="lhs", n=2)
    assert [s.origin for s in lhs.starts] == ["default", "lhs"]
    assert lhs.starts[1].point != res.starts[1].point
    assert all(abs(s.point["u"]) <= 0.4 for s in lhs.starts[1:])


def test_processes_give_the_same_results():
    serial, parallel = coarse(0), coarse(0, workers=2)
    assert [s.status for s in parallel.starts] == [s.status for s in serial.starts]
    for a, b in zip(serial.starts, parallel.starts, strict=True):
        assert a.point == b.point
        assert (math.isnan(a.objective) and math.isnan(b.objective)) or \
            b.objective == pytest.approx(a.objective, rel=1e-9)
    assert parallel.best.verified and parallel.best.transcription.N == 20


def test_the_users_guess_is_start_zero():
    best = coarse(0).best
    res = multistart(coarse_transcription, n=1, guess=best)
    assert [s.origin for s in res.starts] == ["guess"]
    assert res.best.objective == pytest.approx(best.objective, rel=1e-9)


def test_failures_are_reported_with_ipopt_statuses():
    p = OptimalControlProblem("unreachable")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -1, 1)
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x, 10.0)  # needs T >= 2 sqrt(10)
    p.terminal_constraint(v, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_integral(u**2)
    res = multistart(MultipleShooting(p, nodes=10), n=3, seed=0)
    assert not res.success and len(res.failures) == 3
    assert all(f.status in ("Infeasible_Problem_Detected", "Restoration_Failed")
               for f in res.failures)
    with pytest.raises(SolveError, match="no verified optimum"):
        _ = res.best


def test_multi_phase_problem_with_linked_times():
    from tests.oracles.ocp_suite.problems import bryson_denham_phases

    res = multistart(Collocation(bryson_denham_phases(), intervals=[4, 2, 4]), n=3, seed=0)
    assert res.best.objective == pytest.approx(4.0, rel=1e-9)  # 4 / (9 l), l = 1/9
    pt = res.starts[1].point
    assert {"rise.T", "boundary.duration", "fall.u"} <= set(pt)
    assert "boundary.t0" not in pt and "fall.t0" not in pt  # they start where the last ends


def test_bad_arguments():
    with pytest.raises(ProblemDefinitionError, match="builder"):
        multistart(coarse_transcription(), n=2, workers=2)
    with pytest.raises(ProblemDefinitionError, match="method"):
        multistart(coarse_transcription, method="grid")


def test_start_box():
    from ocp.search.multistart import start_coordinates

    coords = start_coordinates(coarse_transcription(), {})
    assert [c.name for c in coords] == ["theta", "omega", "u", "T"]
    assert coords[0].lo == 0.0 and coords[0].hi == pytest.approx(math.pi)  # pi/2 -+ pi/2
    assert (coords[2].lo, coords[2].hi) == (-0.4, 0.4) and coords[3].log


@pytest.mark.slow
def test_dask_client_gives_the_same_results():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1,
                            dashboard_address=None) as client:
        res = multistart(coarse_transcription, n=3, seed=0, client=client)
    assert [s.objective for s in res.starts] == pytest.approx(
        [s.objective for s in coarse(0).starts], rel=1e-9)


@pytest.mark.slow
def test_reference_value_is_the_best_structure():
    """The independent computation behind REFERENCE (scipy, about 3 minutes)."""
    assert structure_optimum(4, 1.0) == pytest.approx(REFERENCE, rel=1e-9)
    assert exact() == pytest.approx(REFERENCE, rel=1e-9)


def test_no_front_door_name_is_a_submodule():
    """``from ocp import NAME`` must give the function, whatever was imported before: a
    submodule of the same name would replace it once imported (``ocp.multistart`` did)."""
    import importlib.util

    import ocp

    clashes = [n for n in ocp.__all__ if importlib.util.find_spec(f"ocp.{n}") is not None]
    assert clashes == []
    importlib.import_module("ocp.search.multistart")
    assert callable(ocp.multistart) and not isinstance(ocp.multistart, type(ocp))
