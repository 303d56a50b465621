"""The exported C controller against the Python (numba) one, on random states and grounds.

Both run every recorded call of random landings (:mod:`.samples`) from the same inputs;
compared are the statuses, ``P`` and ``M`` after every call and the plan's force at three
times after each, the force of the Python side from
:func:`~softlanding.optimal.landing.arrest_schedule` (not from the C's formula). The foot
filter and the plan's force integrals (:mod:`.filter_check`), and the filtered step's
weights and recovery (:mod:`.step_check`), are compared on noisy filtered landings; both
on the samples of ``mpc_landing``'s creep landings (:mod:`.creep_samples`), where the creep
law covers most samples.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.export_c.binding import CController, compile_shared
from softlanding.control.export_c.creep_samples import creep_calls, creep_law_samples
from softlanding.control.export_c.filter_check import (
    FilterComparison,
    compare_filter,
    filtered_calls,
)
from softlanding.control.export_c.reference import plan_forces, relative_difference
from softlanding.control.export_c.samples import Call, recorded_calls
from softlanding.control.export_c.step_check import StepComparison, compare_steps
from softlanding.errors import ExportError
from softlanding.model.robot import Robot

#: Largest relative difference of any output the C may have from the Python controller.
TOLERANCE = 1e-12


@dataclass
class Comparison:
    """How far the C controller's outputs are from the Python controller's.

    Attributes
    ----------
    landings, steps : int
        Landings run, samples (control steps) compared (each landing's first plan besides).
    pull_steps : int
        Samples that ended pulling (the switch passed).
    max_relative : dict
        ``"status"`` (1 if any status differs, else 0), ``"P"``, ``"M"``, ``"force"``: the
        largest relative difference of each over every call.
    statuses : dict
        Status name -> how many calls of the Python controller returned it.
    filter : FilterComparison or None
        The foot filter's and the force integrals' comparison (:mod:`.filter_check`).
    filtered : StepComparison or None
        The filtered step's, on the same landings (:mod:`.step_check`).
    creep : Comparison or None
        The samples of the exactly sensed creep landings of ``mpc_landing``
        (:mod:`.creep_samples`), compared as these.
    creep_filtered : StepComparison or None
        The filtered steps of the noisy filtered creep landings.
    """

    landings: int = 0
    steps: int = 0
    pull_steps: int = 0
    max_relative: dict[str, float] = field(
        default_factory=lambda: {"status": 0.0, "P": 0.0, "M": 0.0, "force": 0.0})
    statuses: dict[str, int] = field(default_factory=dict)
    filter: FilterComparison | None = None
    filtered: StepComparison | None = None
    creep: Comparison | None = None
    creep_filtered: StepComparison | None = None

    def worst(self) -> float:
        """The largest relative difference of any output (the filter's, the filtered
        step's and the creep landings' too)."""
        return max(*self.max_relative.values(),
                   *(r.worst() for r in (self.filter, self.filtered, self.creep,
                                         self.creep_filtered) if r is not None))

    def creep_law_samples(self) -> int:
        """The samples compared that the Python controller's creep law covered (status
        ``creep law``), in all."""
        return sum(creep_law_samples(r.statuses) for r in (self, self.filtered, self.creep,
                                                           self.creep_filtered)
                   if r is not None)

    def describe(self) -> str:
        """One line: what was compared and how far apart."""
        d = self.max_relative
        cr, cf = self.creep, self.creep_filtered
        return (f"{self.steps} samples ({self.pull_steps} pulling) of {self.landings} "
                f"landings, largest relative "
                f"difference {self.worst():.3g} (force {d['force']:.3g}, P {d['P']:.3g}, M "
                f"{d['M']:.3g}; statuses {'the same' if d['status'] == 0 else 'differ'})"
                + (f"; the foot filter: {self.filter.describe()}" if self.filter else "")
                + (f"; {self.filtered.describe()}" if self.filtered else "")
                + (f"; creep landings: {cr.steps} exact samples and "
                   f"{0 if cf is None else cf.steps} filtered, largest relative difference "
                   f"{max(cr.worst(), 0.0 if cf is None else cf.worst()):.3g}"
                   if cr is not None else "")
                + f"; {self.creep_law_samples()} samples by the creep law in all")


def robot_of_numbers(P: np.ndarray) -> Robot:
    """The robot whose ``r_m``, ``s``, ``u_max`` the numbers ``P`` hold.

    Parameters
    ----------
    P : array
        :func:`~softlanding.control.bangbang.robot_numbers`.
    """
    return Robot(r_m=float(P[bb.P_RM]), s=float(P[bb.P_S]), u_max=float(P[bb.P_UMAX]))


def compare(c: CController, n_steps: int = 1000, seed: int = 0) -> Comparison:
    """Run the calls of random landings (:func:`~.samples.recorded_calls`) of the robot the
    export is for (its ``SL_ROBOT_NUMBERS``) through both controllers, ``n_steps`` samples
    in all, and compare their outputs.

    Parameters
    ----------
    c : CController
        The compiled export.
    n_steps : int
        Samples (control steps) compared; each landing's first plan comes on top.
    seed : int
        Of the landings.
    """
    calls, landings = recorded_calls(robot_of_numbers(c.robot_numbers), n_steps, seed)
    return compare_calls(c, calls, landings)


def compare_calls(c: CController, calls: list[Call], landings: int) -> Comparison:
    """Run ``calls`` through both controllers and compare their outputs.

    Parameters
    ----------
    c : CController
        The compiled export.
    calls : list of Call
        :func:`~.samples.recorded_calls`' or :func:`~.creep_samples.creep_calls`'.
    landings : int
        How many landings they make.
    """
    out = Comparison(landings=landings, steps=sum(not k.first for k in calls),
                     pull_steps=sum(not k.first and (k.M[bb.M_PHASE] == bb.PULL
                                                     or k.M[bb.M_TAU1] <= k.h) for k in calls))
    ws = bb.workspace()
    got: dict[str, list[np.ndarray]] = {k: [] for k in ("P", "M", "force")}
    want: dict[str, list[np.ndarray]] = {k: [] for k in ("P", "M", "force")}
    for k in calls:
        Pp, Pc, Mp, Mc = k.P.copy(), k.P.copy(), k.M.copy(), k.M.copy()
        if k.first:
            sp, sc = int(bb.solve_plan(Pp, Mp, k.x, *ws, np.inf)), c.solve_plan(Pc, Mc, k.x)
        else:
            sp = int(bb.control_step(Pp, Mp, k.x, k.a_f, k.u, k.h, k.estimate, *ws))
            sc = c.control_step(Pc, Mc, k.x, k.a_f, k.u, k.h, k.estimate)
        name = bb.STATUS_NAMES[sp]
        out.statuses[name] = out.statuses.get(name, 0) + 1
        out.max_relative["status"] = max(out.max_relative["status"], float(sp != sc))
        length = (Mp[bb.M_TAU1] if Mp[bb.M_PHASE] == bb.PUSH else 0.0) + Mp[bb.M_TAU2]
        times = np.array([0.5 * Pp[bb.P_PERIOD], 0.5 * length, 1.2 * length])
        got["P"].append(Pc)
        want["P"].append(Pp)
        got["M"].append(Mc)
        want["M"].append(Mp)
        got["force"].append(np.array([c.force(Pc, Mc, t) for t in times]))
        want["force"].append(plan_forces(Pp, Mp, times))
    for key in got:
        out.max_relative[key] = relative_difference(np.concatenate(got[key]),
                                                    np.concatenate(want[key]))
    return out


def check_export(folder: Path, n_steps: int = 1000, seed: int = 0,
                 filter_steps: int = 600) -> Comparison:
    """Compile the export in ``folder`` with the system's C compiler (into a temporary
    folder), :func:`compare` it with the Python controller, its foot filter with the
    Python filter (:func:`~.filter_check.compare_filter`) and its filtered step with the
    Python one (:func:`~.step_check.compare_steps`) on the same noisy landings, and both on
    the samples of ``mpc_landing``'s creep landings (:mod:`.creep_samples`: the creep law).

    Parameters
    ----------
    folder : Path
        The exported files.
    n_steps, seed : int
        As :func:`compare`.
    filter_steps : int
        Filter steps (and filtered steps) compared.

    Raises
    ------
    ExportError
        No C compiler, the code does not compile cleanly, or an output differs by more than
        :data:`TOLERANCE` (relative) or a status differs.
    """
    with tempfile.TemporaryDirectory(prefix="softlanding-export-") as tmp:
        lib = compile_shared(Path(folder), Path(tmp) / "libsl.so")
        c = CController(lib)
        result = compare(c, n_steps, seed)
        calls = filtered_calls(robot_of_numbers(c.robot_numbers), filter_steps, seed)
        result.filter = compare_filter(c, filter_steps, seed, calls)
        result.filtered = compare_steps(c, calls.steps)
        creeps = creep_calls(robot_of_numbers(c.robot_numbers))
        result.creep = compare_calls(c, creeps.exact, creeps.landings)
        result.creep_filtered = compare_steps(c, creeps.filtered)
    if result.worst() > TOLERANCE:
        raise ExportError(f"the compiled C differs from the Python controller: "
                          f"{result.describe()}")
    return result


__all__ = ["TOLERANCE", "Comparison", "check_export", "compare", "compare_calls", "plan_forces",
           "relative_difference", "robot_of_numbers"]
