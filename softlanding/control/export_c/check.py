"""The exported C controller against the Python (numba) one, on random states and grounds.

A case is a landing: the paper's robot on a random ground ``(K, c_d)`` at a random impact
velocity, with a random sample period, sensor noise and margin. Its first plan is solved
from the impact state (:func:`~softlanding.control.bangbang.solve_plan`), then the samples
follow (:func:`~softlanding.control.bangbang.control_step`), each from the state the last
plan predicted, perturbed (the plant's ground differs from the prior: the true ground's
``K`` is off by up to 50 %; and the measurements are noisy), with the foot's acceleration
that the true ground gives, until the plan's foot stop. Both controllers run every call
from the same inputs (made from the Python side's outputs); compared are the statuses,
``P`` and ``M`` after every call and the plan's force at three times after each, the
force of the Python side from :func:`~softlanding.optimal.landing.arrest_schedule` (not
from the C's formula).
"""

from __future__ import annotations

import itertools
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.export_c.binding import CController, compile_shared
from softlanding.errors import ExportError
from softlanding.model.controllers import ForceSchedule
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import arrest_schedule
from softlanding.optimal.limits import force_limit

#: Samples of one landing at most (more landings, more grounds, for the same number).
MAX_SAMPLES = 20
#: Largest relative difference of any output the C may have from the Python controller.
TOLERANCE = 1e-12


@dataclass(frozen=True)
class Landing:
    """One landing's inputs.

    Attributes
    ----------
    P : array
        The robot's numbers (the ground's ``K``, ``c_d``: the controller's prior).
    guess : (float, float)
        The first plan's durations before Newton.
    x0 : array of 4
        The state at impact.
    truth : (float, float)
        The ground's ``(K, c_d)`` the measured accelerations come from.
    noise : float
        Relative standard deviation of the measured state.
    seed : int
        Of the measurements' noise.
    """

    P: np.ndarray
    guess: tuple[float, float]
    x0: np.ndarray
    truth: tuple[float, float]
    noise: float
    seed: int


def random_landings(robot: Robot = PAPER_ROBOT, seed: int = 0) -> Iterator[Landing]:
    """Random landings of ``robot``, one after another.

    Parameters
    ----------
    robot : Robot
        With a force limit.
    seed : int
        Of :func:`numpy.random.default_rng`.
    """
    rng = np.random.default_rng(seed)
    r = robot
    u_max = force_limit(robot)
    for i in itertools.count():
        k = float(np.exp(rng.uniform(np.log(0.3), np.log(3.0))))
        c_d = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.0, 1.0))
        noise = float(rng.choice([0.0, 1e-6, 1e-4]))
        P = bb.robot_numbers(r.r_m, r.s, u_max, k, c_d, max(noise, 1e-6),
                             float(rng.choice([0.0, 2.0])), float(rng.uniform(0.005, 0.03)))
        truth = (k * float(rng.uniform(0.5, 1.5)), c_d * float(rng.uniform(0.5, 1.5)))
        x0 = Impact(float(rng.uniform(-10.0, -0.5))).initial_state(r)
        yield Landing(P, (float(rng.uniform(0.05, 0.2)), float(rng.uniform(0.05, 0.2))), x0,
                      truth, noise, seed * 100_003 + i)


def plan_forces(P: np.ndarray, M: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The force of the plan in ``M`` at ``times`` after the step, from the Python schedule
    (push, pull, then :func:`~softlanding.optimal.landing.arrest_schedule`).

    Parameters
    ----------
    P, M : arrays
        The controller's numbers and memory.
    times : array
        Times after the step.
    """
    t1 = float(M[bb.M_TAU1]) if M[bb.M_PHASE] == bb.PUSH else 0.0
    t2 = t1 + float(M[bb.M_TAU2])
    u_max = float(P[bb.P_UMAX])
    tail = arrest_schedule(np.array([M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT], 0.0]),
                           float(P[bb.P_RM]))
    assert isinstance(tail, ForceSchedule)  # (a constant arrest force, then the weight)
    after = np.array(tail.values)[np.searchsorted(tail.times, times - t2, side="right")]
    return np.where(times < t1, u_max, np.where(times < t2, -u_max, after))


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
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
    landings, steps : int
        Landings run, samples (control steps) compared (each landing's first plan besides).
    max_relative : dict
        ``"status"`` (1 if any status differs, else 0), ``"P"``, ``"M"``, ``"force"``: the
        largest relative difference of each over every call.
    statuses : dict
        Status name -> how many calls of the Python controller returned it.
    """

    landings: int = 0
    steps: int = 0
    max_relative: dict[str, float] = field(
        default_factory=lambda: {"status": 0.0, "P": 0.0, "M": 0.0, "force": 0.0})
    statuses: dict[str, int] = field(default_factory=dict)

    def worst(self) -> float:
        """The largest relative difference of any output."""
        return max(self.max_relative.values())

    def describe(self) -> str:
        """One line: what was compared and how far apart."""
        d = self.max_relative
        return (f"{self.steps} samples of {self.landings} landings, largest relative "
                f"difference {self.worst():.3g} (force {d['force']:.3g}, P {d['P']:.3g}, M "
                f"{d['M']:.3g}; statuses {'the same' if d['status'] == 0 else 'differ'})")


def compare(c: CController, n_steps: int = 1000, seed: int = 0) -> Comparison:
    """Run random landings (:func:`random_landings`) of the robot the export is for (its
    ``SL_ROBOT_NUMBERS``' ``r_m``, ``s``, ``u_max``) through both controllers,
    ``n_steps`` samples in all, and compare their outputs.

    Parameters
    ----------
    c : CController
        The compiled export.
    n_steps : int
        Samples (control steps) compared; each landing's first plan comes on top.
    seed : int
        Of the landings.
    """
    out = Comparison()
    ws = bb.workspace()
    got: dict[str, list[np.ndarray]] = {k: [] for k in ("P", "M", "force")}
    want: dict[str, list[np.ndarray]] = {k: [] for k in ("P", "M", "force")}
    P0 = c.robot_numbers
    landings = random_landings(Robot(r_m=float(P0[bb.P_RM]), s=float(P0[bb.P_S]),
                                     u_max=float(P0[bb.P_UMAX])), seed)
    while out.steps < n_steps:
        case = next(landings)
        out.landings += 1
        rng = np.random.default_rng(case.seed)
        Pp, Pc = case.P.copy(), case.P.copy()
        prior, noise = (float(Pp[bb.P_K]), float(Pp[bb.P_CD])), float(Pp[bb.P_NOISE])
        Mp = bb.new_memory(*case.guess, prior, (1.0, 1.0), noise)
        Mc = c.new_memory(*case.guess, prior, (1.0, 1.0), noise)
        x = np.ascontiguousarray(case.x0, float)
        h = float(Pp[bb.P_PERIOD])
        for sample in range(MAX_SAMPLES + 1):
            if sample == 0:
                sp, sc = int(bb.solve_plan(Pp, Mp, x, *ws)), c.solve_plan(Pc, Mc, x)
            else:
                # the force the sample ended under (the plan's stop is more than h away)
                push = Mp[bb.M_PHASE] == bb.PUSH and Mp[bb.M_TAU1] > h
                u = float(Pp[bb.P_UMAX]) if push else -float(Pp[bb.P_UMAX])
                x = _measured(Mp, x, h, case.noise, rng)
                a_f = float(Pp[bb.P_AF0] + Pp[bb.P_BF] * u + Pp[bb.P_GF] * (
                    case.truth[0] * -x[2] + case.truth[1] * x[3] ** 2)) \
                    * (1 + case.noise * rng.standard_normal())
                sp = int(bb.control_step(Pp, Mp, x, a_f, u, h, True, *ws))
                sc = c.control_step(Pc, Mc, x, a_f, u, h, True)
                out.steps += 1
            name = bb.STATUS_NAMES[sp]
            out.statuses[name] = out.statuses.get(name, 0) + 1
            out.max_relative["status"] = max(out.max_relative["status"], float(sp != sc))
            length = (Mp[bb.M_TAU1] if Mp[bb.M_PHASE] == bb.PUSH else 0.0) + Mp[bb.M_TAU2]
            times = np.array([0.5 * h, 0.5, 1.2]) * np.array([1.0, length, length])
            got["P"].append(Pc.copy())
            want["P"].append(Pp.copy())
            got["M"].append(Mc.copy())
            want["M"].append(Mp.copy())
            got["force"].append(np.array([c.force(Pc, Mc, t) for t in times]))
            want["force"].append(plan_forces(Pp, Mp, times))
            if out.steps >= n_steps or length <= h or sp not in (bb.OK, bb.CONVERGING, bb.HOLDS):
                break  # the foot's stop within the next sample, or a state not covered
    for k in got:
        out.max_relative[k] = relative_difference(np.concatenate(got[k]),
                                                  np.concatenate(want[k]))
    return out


def check_export(folder: Path, n_steps: int = 1000, seed: int = 0) -> Comparison:
    """Compile the export in ``folder`` with the system's C compiler (into a temporary
    folder) and :func:`compare` it with the Python controller.

    Parameters
    ----------
    folder : Path
        The exported files.
    n_steps, seed : int
        As :func:`compare`.

    Raises
    ------
    ExportError
        No C compiler, the code does not compile cleanly, or an output differs by more than
        :data:`TOLERANCE` (relative) or a status differs.
    """
    with tempfile.TemporaryDirectory(prefix="softlanding-export-") as tmp:
        lib = compile_shared(Path(folder), Path(tmp) / "libsl.so")
        result = compare(CController(lib), n_steps, seed)
    if result.worst() > TOLERANCE:
        raise ExportError(f"the compiled C differs from the Python controller: "
                          f"{result.describe()}")
    return result


def _measured(M: np.ndarray, x: np.ndarray, h: float, noise: float,
              rng: np.random.Generator) -> np.ndarray:
    """The next sample's measured state: the plan's prediction (else ``x`` moved on), off
    by the model's error and the sensors' noise, the foot still sinking."""
    pred = M[bb.M_PRED:bb.M_PRED + 4] if M[bb.M_PRED_OK] == 1.0 else \
        x + h * np.array([x[1], 0.0, x[3], 0.0])
    out = pred * (1.0 + noise * rng.standard_normal(4))
    out[3] = min(out[3], -1e-6)
    return np.ascontiguousarray(out)


__all__ = ["Comparison", "Landing", "MAX_SAMPLES", "TOLERANCE", "check_export", "compare",
           "plan_forces", "random_landings", "relative_difference"]
