import pytest


@pytest.fixture(scope="session")
def grid_hop():
    """The free hop at ``v0 = -2``, ``eta = 0`` from the first of ``HOP_STARTS`` only, one
    grid, no exact-arc refinement (4.6 s CPU): shared by the tests of the cycle and of the
    CLI's rendering of it, all in the second test command (issue 46), as are the search, the
    doubled grids and the refinement."""
    import softlanding.optimal.hopping as hopping
    from softlanding import PAPER_ROBOT

    with pytest.MonkeyPatch.context() as m:
        m.setattr(hopping, "HOP_STARTS", hopping.HOP_STARTS[:1])
        return hopping.solve_hop(-2.0, PAPER_ROBOT, eta=0.0, refine=False)


@pytest.fixture(scope="session")
def arrest_infeasible():
    """The error of the paper's landing at ``v0 = -10`` with ``u_max = 2`` (no arrest within
    the force limit): four relaxed solves name the condition (about 7 s CPU on a loaded
    machine), so the API's test and the two-phase CLI's read it from one solve."""
    from softlanding import PAPER_ROBOT
    from softlanding.errors import InfeasibleLandingError
    from softlanding.optimal.landing import solve_landing

    with pytest.raises(InfeasibleLandingError) as info:
        solve_landing(-10.0, PAPER_ROBOT.replace(u_max=2.0), replay=False)
    return info.value


@pytest.fixture(scope="session")
def paper_impedance_optimum():
    """``optimize_impedance(v0)`` on the paper's robot and ground, each ``v0`` once per
    session (about 2.5 s CPU each): read by the refined optimum's checks and by the
    recorded single-ground result of the worst-case study. Results are only read."""
    from softlanding.studies.impedance import optimize_impedance

    cache = {}

    def optimum(v0):
        if v0 not in cache:
            cache[v0] = optimize_impedance(v0)
        return cache[v0]

    return optimum


@pytest.fixture(scope="session")
def study_robust():
    """``robust_landing(v0, grounds, nominal=solve_landing(v0))`` over the unknown-ground
    study's 15 grounds, from the nominal plan (the study's start), each ``v0`` once per
    session (a minute or two of CPU each at v0 = -6 and -10): read by the guide's robust
    column (tests/softlanding/control/test_robust.py) and by the convergence test's run from
    the nominal plan alone. The NLP cache is cleared first, as the study's run starts (the
    re-plans' paths depend on the NLPs earlier solves left cached). Results are only read."""
    import itertools

    from ocp.structure.switching import clear_cache
    from softlanding import solve_landing
    from softlanding.control import robust_landing
    from softlanding.studies.unknown_ground import STUDY_DRAG, STUDY_STIFFNESS, true_ground

    cache = {}

    def run(v0):
        if v0 not in cache:
            clear_cache()
            grounds = [true_ground(k, c)
                       for k, c in itertools.product(STUDY_STIFFNESS, STUDY_DRAG)]
            cache[v0] = (grounds, robust_landing(v0, grounds, nominal=solve_landing(v0)))
        return cache[v0]

    return run
