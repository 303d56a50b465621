"""The exported C controller against the Python (numba) one, on random states and grounds.

Each case is a robot's numbers ``P`` for a random ground ``(K, c_d)``, sensor noise and
margin, and a state near a landing's: the first plan is solved from it
(:func:`~softlanding.control.bangbang.solve_plan`), then two samples follow
(:func:`~softlanding.control.bangbang.control_step`): one from a perturbed state with a
measured acceleration (a re-solve on a new estimate), one from the state the plan
predicted (the plan-holds path where it applies). Both controllers run every call from
the same inputs; compared are the statuses, ``P`` and ``M`` after every call and the
plan's force at a few times, the force of the Python side from
:func:`~softlanding.optimal.landing.arrest_schedule` (not from the C's formula).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.export_c.binding import CController
from softlanding.model.controllers import ForceSchedule
from softlanding.model.robot import PAPER_ROBOT
from softlanding.optimal.landing import arrest_schedule


@dataclass(frozen=True)
class Case:
    """One comparison's inputs.

    Attributes
    ----------
    P : array
        The robot's numbers (the ground's ``K``, ``c_d`` the plan's).
    guess : (float, float)
        The first plan's durations before Newton.
    x0, x1 : array of 4
        The state the first plan starts from, the state measured after the first sample.
    a_f, u, h : float
        The first sample's measured foot acceleration, force and length.
    estimate : bool
        Update the estimate.
    times : array
        When the plans' forces are compared (fractions of the plan's length).
    """

    P: np.ndarray
    guess: tuple[float, float]
    x0: np.ndarray
    x1: np.ndarray
    a_f: float
    u: float
    h: float
    estimate: bool
    times: np.ndarray = field(default_factory=lambda: np.linspace(0.05, 1.45, 7))


def random_cases(n: int, seed: int = 0) -> list[Case]:
    """``n`` random cases on the paper's robot.

    Parameters
    ----------
    n : int
        How many.
    seed : int
        Of :func:`numpy.random.default_rng`.
    """
    rng = np.random.default_rng(seed)
    r = PAPER_ROBOT
    u_max = float(r.u_max or 0.0)
    out = []
    for _ in range(n):
        k = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
        c_d = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 1.0))
        noise = float(10 ** rng.uniform(-6, -3))
        margin = float(rng.choice([0.0, 2.0]))
        period = float(rng.choice([0.005, 0.01, 0.02]))
        P = bb.robot_numbers(r.r_m, r.s, u_max, k, c_d, noise, margin, period)
        v0 = float(rng.uniform(-10.0, -0.5))
        depth = float(rng.uniform(0.0, 0.3))
        x0 = np.array([r.s / 2 - depth + rng.uniform(-1, 1), v0 * rng.uniform(0.8, 1.0),
                       -depth, v0 * rng.uniform(0.3, 1.0)])
        pull = rng.random() < 0.25  # pulling from the start: only the foot's stop left
        guess = (0.0 if pull else float(rng.uniform(0.02, 0.3)), float(rng.uniform(0.02, 0.3)))
        h = period
        x1 = x0 + h * np.array([x0[1], 0.0, x0[3], 0.0]) + rng.normal(0.0, 1e-3, 4)
        x1[3] = min(x1[3], -1e-3)
        a_f = float(P[bb.P_AF0] + P[bb.P_BF] * u_max
                    + P[bb.P_GF] * (1.2 * k * (-x1[2]) + c_d * x1[3] ** 2)
                    + rng.normal(0.0, noise))
        out.append(Case(P, guess, x0, x1, a_f, -u_max if pull else u_max, h,
                        bool(rng.random() < 0.8)))
    return out


def plan_force(P: np.ndarray, M: np.ndarray, t: float) -> float:
    """The force of the plan in ``M`` at ``t`` after the step, from the Python schedule
    (push, pull, then :func:`~softlanding.optimal.landing.arrest_schedule`).

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    t : float
        Time after the step.
    """
    t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
    t2 = t1 + float(M[bb.M_TAU2])
    u_max = float(P[bb.P_UMAX])
    if t < t1:
        return u_max
    if t < t2:
        return -u_max
    tail = arrest_schedule(np.array([M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT], 0.0]),
                           float(P[bb.P_RM]))
    assert isinstance(tail, ForceSchedule)  # (a constant arrest force, then the weight)
    return tail.values[int(np.searchsorted(tail.times, t - t2, side="right"))]


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    """Largest ``|a - b| / max(|a|, |b|)`` (0 where both are 0; inf where one is not finite
    and they differ)."""
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
    rel = np.where(same, 0.0, np.where(np.isfinite(rel), rel, np.inf))
    return float(rel.max(initial=0.0))


@dataclass
class Comparison:
    """How far the C controller's outputs are from the Python controller's.

    Attributes
    ----------
    cases : int
        Cases compared.
    max_relative : dict
        ``"status"`` (1 if any status differs, else 0), ``"P"``, ``"M"``, ``"force"``: the
        largest relative difference of each over every call of every case.
    statuses : dict
        Status name -> how many calls of the Python controller returned it.
    """

    cases: int = 0
    max_relative: dict[str, float] = field(
        default_factory=lambda: {"status": 0.0, "P": 0.0, "M": 0.0, "force": 0.0})
    statuses: dict[str, int] = field(default_factory=dict)

    def add(self, what: str, a: object, b: object) -> None:
        """Fold one output's difference in."""
        d = _relative(np.asarray(a, float), np.asarray(b, float))
        self.max_relative[what] = max(self.max_relative[what], d)

    def worst(self) -> float:
        """The largest relative difference of any output."""
        return max(self.max_relative.values())


def compare(c: CController, cases: list[Case]) -> Comparison:
    """Run every case through both controllers and compare their outputs.

    Parameters
    ----------
    c : CController
        The compiled export.
    cases : list of Case
        :func:`random_cases`.
    """
    out = Comparison()
    ws = bb.workspace()
    for case in cases:
        out.cases += 1
        Pp, Pc = case.P.copy(), case.P.copy()
        prior, std, noise = (Pp[bb.P_K], Pp[bb.P_CD]), (1.0, 1.0), float(Pp[bb.P_NOISE])
        Mp = bb.new_memory(*case.guess, prior, std, noise)
        Mc = c.new_memory(*case.guess, prior, std, noise)
        out.add("M", Mc, Mp)
        calls = [("plan", case.x0, 0.0, 0.0, 0.0, False), ("step", case.x1, case.a_f, case.u,
                                                          case.h, case.estimate)]
        for i in range(3):
            if i == 2:  # the next sample as the plan predicted it (the plan-holds path)
                pred = Mp[bb.M_PRED:bb.M_PRED + 4].copy()
                x2 = pred if Mp[bb.M_PRED_OK] == 1.0 else case.x1 + 1e-4
                calls.append(("step", x2, case.a_f, case.u, case.h, False))
            kind, x, a_f, u, h, est = calls[i]
            x = np.ascontiguousarray(x, float)
            if kind == "plan":
                sp = int(bb.solve_plan(Pp, Mp, x, *ws))
                sc = c.solve_plan(Pc, Mc, x)
            else:
                sp = int(bb.control_step(Pp, Mp, x, a_f, u, h, est, *ws))
                sc = c.control_step(Pc, Mc, x, a_f, u, h, est)
            name = bb.STATUS_NAMES[sp]
            out.statuses[name] = out.statuses.get(name, 0) + 1
            out.max_relative["status"] = max(out.max_relative["status"], float(sp != sc))
            out.add("P", Pc, Pp)
            out.add("M", Mc, Mp)
            length = (Mp[bb.M_TAU1] if Mp[bb.M_PHASE] == bb.PUSH else 0.0) + Mp[bb.M_TAU2]
            for t in case.times * length:
                out.add("force", c.force(Pc, Mc, t), plan_force(Pp, Mp, t))
    return out


__all__ = ["Case", "Comparison", "compare", "plan_force", "random_cases"]
