"""``MultiPhaseProblem.link`` never joins nothing silently (it used to solve two unrelated
phases with ``verified=True`` when their state names differed)."""

import pytest

from ocp import MultiPhaseProblem, ProblemDefinitionError


def two_phases(second_state: str) -> tuple[MultiPhaseProblem, object, object]:
    mp = MultiPhaseProblem("two")
    a, b = mp.phase("a"), mp.phase("b")
    a.state("x")
    a.set_dynamics({"x": 1.0})
    b.state(second_state)
    b.set_dynamics({second_state: 1.0})
    return mp, a, b


def test_link_refuses_phases_sharing_no_state():
    mp, a, b = two_phases("y")
    with pytest.raises(ProblemDefinitionError, match="share no state name"):
        mp.link(a, b)


def test_link_with_named_or_no_states_is_explicit():
    mp, a, b = two_phases("y")
    mp.link(a, b, states=())  # time only, said explicitly
    assert [c.name for c in mp.links] == ["time: a -> b"]
    mp2, a2, b2 = two_phases("x")
    mp2.link(a2, b2)
    assert [c.name for c in mp2.links] == ["x: a -> b", "time: a -> b"]
