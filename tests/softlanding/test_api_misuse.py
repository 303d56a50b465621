"""Misusing the Python API gives the package's own errors naming the argument (issue 23,
item 9), never an AttributeError or a CasADi shape error from deep inside."""

import numpy as np
import pytest

from softlanding import (
    PAPER_ROBOT,
    optimize_impedance,
    simulate,
    solve_hop,
    solve_landing,
    solve_leg_extension,
    solve_two_phase,
)
from softlanding.control.mpc import mpc_landing
from softlanding.control.robust import robust_landing
from softlanding.errors import ParameterError
from softlanding.model import FeedbackSchedule, ForceSchedule, Impedance, LinearGround, Rigid
from softlanding.model.ground import MAX_GROUNDS, AddedMassGround, CustomGround, DragGround
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.hop_arcs import SETTINGS, ArcGuess, refine_arcs
from softlanding.simulation.simulator import simulate_batch

CASES = [
    ("ground", lambda: simulate(PAPER_ROBOT, -1, Rigid(), "drag")),
    ("controller", lambda: simulate(PAPER_ROBOT, -1, "rigid")),
    ("robot", lambda: simulate(None, -1, Rigid())),
    ("robot", lambda: simulate_batch("robot", -1, 0.1, 0.1)),
    ("robot", lambda: solve_landing(-3, robot=None)),
    ("ground", lambda: solve_landing(-3, ground="drag")),
    ("robot", lambda: solve_two_phase(-3, robot=None)),
    ("ground", lambda: solve_two_phase(-3, ground=1.0)),
    ("robot", lambda: solve_leg_extension(-3, robot=None)),
    ("eta", lambda: solve_hop(-3, eta="0.5")),
    ("robot", lambda: solve_hop(-3, robot=None)),
    ("doublings", lambda: solve_hop(-3, doublings=5)),
    ("setting", lambda: refine_arcs(ArcGuess([], [], 0.0), PAPER_ROBOT, Impact(-3), 0.0,
                                    setting=len(SETTINGS))),
    ("robot", lambda: optimize_impedance(-3, robot="x")),
    ("warm_start", lambda: solve_landing(-3, warm_start="previous")),
    ("warm_start", lambda: solve_two_phase(-3, warm_start=object())),
    ("warm_start", lambda: solve_leg_extension(-3, warm_start=object())),
    # issue 34, item 8: a TypeError, numpy's ValueError or a plain ValueError before
    ("grounds", lambda: robust_landing(-3, None)),
    ("grounds", lambda: robust_landing(-3, [LinearGround(), "sand"])),
    ("grounds", lambda: robust_landing(-3, [LinearGround(1 + i / 1000)
                                            for i in range(MAX_GROUNDS + 1)])),
    ("controller", lambda: simulate(PAPER_ROBOT, -1, Impedance)),
    ("v0", lambda: simulate(PAPER_ROBOT, np.array([-1.0, -2.0]), Rigid())),
    ("steps", lambda: solve_two_phase(-3, steps=3)),
    # issue 47, defect 10: an array was taken as a ground's number, failing later in numpy
    ("c_d", lambda: DragGround(np.array([1, 2]))),
    ("stiffness", lambda: DragGround(0.1, [1.0, 2.0])),
    ("stiffness", lambda: LinearGround(np.array([1.0]))),
    ("kappa", lambda: AddedMassGround(1.0, 0.1, np.ones(2))),
    ("force", lambda: CustomGround("arrays", lambda d, v: np.array([d, d]))),
    # an adversarial review: lists, strings and bools were taken as a model's numbers (a list
    # failed later as numpy's or Python's error, "5" was read as 5 and True as 1)
    ("r_m", lambda: Robot(r_m=[5], s=20)),
    ("r_m", lambda: Robot(r_m=[], s=20)),
    ("r_m", lambda: Robot(r_m="5", s=20)),
    ("u_max", lambda: Robot(r_m=5, s=20, u_max=True)),
    ("r_m", lambda: Robot(r_m=10**400, s=20)),
    ("k_p", lambda: Impedance(k_p=[0.2, 0.3], k_d=0.18)),
    ("k_d", lambda: Impedance(k_p=0.2, k_d=np.bool_(True))),
    ("v0", lambda: Impact("-3")),
    ("stiffness", lambda: LinearGround("1")),
    ("times", lambda: ForceSchedule("ab", "cd")),
    ("gains", lambda: FeedbackSchedule((1.0,), [[0, 0, 0, 0], [1, 1, 1, 1, 1]])),
    ("v0", lambda: mpc_landing(-1e-9)),
    ("margin", lambda: mpc_landing(-3, estimate=False, margin=2.0)),
]


@pytest.mark.parametrize("name,call", CASES, ids=[f"{n}-{i}" for i, (n, _) in enumerate(CASES)])
def test_wrong_argument_is_a_parameter_error_naming_it(name, call):
    with pytest.raises(ParameterError) as e:
        call()
    assert e.value.parameter == name


def test_a_warm_start_of_another_variant_is_refused():
    two = solve_two_phase(-1.0)
    with pytest.raises(ParameterError, match="warm_start"):
        solve_landing(-1.0, warm_start=two)


def test_a_ground_is_checked_by_its_members_whether_they_are_its_class_or_its_own():
    # expect() remembers the package's own frozen grounds (the Protocol's isinstance looks
    # each member up, 24 us a call on Python 3.11); a user's class is checked every time: an
    # instance whose members are its own, one that lacks a member, one that has set a method
    # to None (the Protocol refuses it) after another of its class passed
    from softlanding.errors import expect
    from softlanding.model.ground import Ground

    class Own:
        def __init__(self, complete):
            self.yield_force, self.added_mass = (lambda d, v: d), (lambda d: 0.0)
            self.is_affine, self.to_dict = False, dict
            if complete:
                self.name = "own"

    class Lacking:
        name, is_affine = "lacking", False

        def yield_force(self, d, v):
            return d

    class Full(Lacking):
        def added_mass(self, d):
            return 0.0

        def to_dict(self):
            return {}

    for _ in range(2):
        ok = Own(True)
        assert expect("ground", ok, Ground) is ok
        with pytest.raises(ParameterError, match="ground"):
            expect("ground", Own(False), Ground)
        with pytest.raises(ParameterError, match="ground"):
            expect("ground", Lacking(), Ground)
        full, blocked = Full(), Full()
        blocked.added_mass = None
        assert expect("ground", full, Ground) is full
        if not isinstance(blocked, Ground):  # Python 3.11 (3.12's per-class check accepts it)
            with pytest.raises(ParameterError, match="ground"):
                expect("ground", blocked, Ground)
    g = DragGround(1.0, 0.5)
    assert expect("ground", g, Ground) is g and expect("ground", g, Ground) is g
    with pytest.raises(ParameterError, match="robot"):
        simulate(g, -1, Rigid())
