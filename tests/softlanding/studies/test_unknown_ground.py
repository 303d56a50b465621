"""The unknown-ground study on one case: every controller reported, the goals checked."""

import pytest

from softlanding.studies.unknown_ground import study_summary, true_ground, unknown_ground_case


@pytest.mark.slow  # a case of the study: six controllers on one ground (1.8 s CPU, issue 46)
def test_one_case_of_the_study():
    row = unknown_ground_case(-3.0, true_ground(2.0, 0.0))
    assert row["clairvoyant_verified"]
    assert row["mpc"]["ratio"] == pytest.approx(1.0, abs=1e-8) and row["mpc"]["feasible"]
    assert not row["open_loop"]["feasible"]  # the nominal plan breaks a limit on stiff ground
    assert row["impedance_nominal"]["ratio"] > 1.0
    s = study_summary([row])
    assert s["mpc_within_2_percent"] == 1 and s["cases"] == 1


def test_true_ground_is_linear_without_drag():
    assert true_ground(1.5, 0.0).to_dict() == {"model": "linear", "stiffness": 1.5}
    assert true_ground(1.0, 0.2).to_dict() == {"model": "drag", "c_d": 0.2}


# ------------------------------------------------------------------ plans given to the study
GROUNDS = [true_ground(k, c) for k in (0.5, 2.0) for c in (0.0, 1.0)]
REVERSED = tuple(reversed(GROUNDS))


def _plan(kind, grounds=REVERSED, v0=-3.0, robot=None, first=0, schedule="robust",
          branch_time=None):
    """A robust plan as the study reads it (its grounds, and one landing each, told apart by
    depth): nothing is planned."""
    from types import SimpleNamespace

    from softlanding import PAPER_ROBOT, Impact
    from softlanding.control.robust import DEFAULT_BRANCH_TIME, RobustLanding

    return RobustLanding(robot=robot or PAPER_ROBOT, impact=Impact(v0), grounds=tuple(grounds),
                         kind=kind, schedule=schedule, nominal=[],
                         landings=[SimpleNamespace(depth=first + i) for i in range(len(grounds))],
                         branch_time=branch_time if branch_time is not None or kind != "tree"
                         else DEFAULT_BRANCH_TIME)


@pytest.fixture
def study(monkeypatch):
    """unknown_ground_study with every solve replaced: what each case receives, and the
    solves run (each call's own)."""
    from types import SimpleNamespace

    import softlanding.studies.unknown_ground as ug

    solved = []

    def solve(name, result):
        return lambda *a, **k: solved.append(name) or result(*a)

    monkeypatch.setattr(ug, "solve_landing", solve("nominal", lambda *a: "nominal"))
    monkeypatch.setattr(ug, "optimize_impedance",
                        solve("impedance", lambda *a: SimpleNamespace(k_p=1, k_d=0)))
    monkeypatch.setattr(ug, "robust_landing", solve(
        "robust", lambda v, g, *a: _plan("open-loop", g, v, first=100)))
    monkeypatch.setattr(ug, "two_stage_landing", solve(
        "tree", lambda r: _plan("tree", r.grounds, r.impact.v0, first=200)))
    monkeypatch.setattr(ug, "unknown_ground_case", lambda v, g, robot, **kw: {
        "ground": g, "robust": kw["robust"].depth, "tree": kw["tree"].depth})

    def run(plans):
        solved.clear()
        rows = ug.unknown_ground_study([-3.0], (0.5, 2.0), (0.0, 1.0), plans=plans)
        return rows, [s for s in solved if s in ("robust", "tree")]

    run.solved = solved
    return run


def test_the_plans_given_are_read_by_ground_not_planned_again(study):
    # the plans hold the study's grounds in another order: each case gets its own ground's
    rows, planned = study([_plan("open-loop"), _plan("tree", first=10)])
    assert planned == []
    order = list(REVERSED)
    assert [r["ground"] for r in rows] == GROUNDS
    assert [r["robust"] for r in rows] == [order.index(g) for g in GROUNDS]
    assert [r["tree"] for r in rows] == [10 + order.index(g) for g in GROUNDS]


def test_a_velocity_without_a_tree_gets_one_from_its_plan(study):
    rows, planned = study(_plan("open-loop"))  # one plan alone: a sequence of one
    assert planned == ["tree"]
    assert [r["tree"] for r in rows] == [200 + 3 - i for i in range(4)]  # from the given plan
    rows, planned = study([])
    assert planned == ["robust", "tree"]


@pytest.mark.parametrize("plans, words", [
    ([_plan("open-loop", v0=-1.0)], "v0 = -1, not one of the study's"),
    ([_plan("open-loop", GROUNDS[:3])], "other grounds"),
    ([_plan("open-loop", GROUNDS[:3] + [true_ground(1.0, 0.0)])], "other grounds"),
    ([_plan("open-loop", GROUNDS + [GROUNDS[0]])], "other grounds"),  # one ground twice
    ([_plan("closed-loop")], "kind 'closed-loop'"),
    ([_plan("open-loop"), _plan("open-loop")], "two open-loop plans"),
    ([_plan("tree")], "needs the open-loop plan it was made from"),
    ([_plan("open-loop"), _plan("tree", schedule="another")], "needs the open-loop plan"),
    ([_plan("open-loop"), _plan("tree", branch_time=0.1)], "branches at 0.1"),
    (["plan"], "must be a RobustLanding"),
    (42, "must be a sequence of RobustLanding"),
])
def test_a_plan_that_is_not_the_studys_is_refused_before_any_solve(study, plans, words):
    from softlanding.errors import ParameterError

    with pytest.raises(ParameterError, match=words):
        study(plans)
    assert study.solved == []


def test_a_plan_of_another_robot_is_refused(study):
    from softlanding import PAPER_ROBOT
    from softlanding.errors import ParameterError

    with pytest.raises(ParameterError, match="another robot"):
        study([_plan("open-loop", robot=PAPER_ROBOT.replace(s=5.0))])
