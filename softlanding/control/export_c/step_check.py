"""The exported C filtered step (``sl_filtered_weight``, ``sl_filtered_step``) against the
Python one (:func:`~softlanding.control.recovery.sample_weight`,
:func:`~softlanding.control.recovery.filtered_step`), on the recorded samples of noisy
filtered landings (:func:`~.filter_check.filtered_calls`).

Each sample runs in both from the same inputs (``P``, ``M``, the filter's memory, the
filtered state, the recovery's count); compared are the weight, the status, ``P``, ``M``
and the count after it, and the plan's force at three times after it (the Python side's from
the Python schedule, :func:`~.reference.plan_forces`). The weight is also compared on the
grid of :func:`weight_probes`, whose edges no landing reaches (a foot above the surface or
at rest, a negative force or estimate, a covariance so large that the weight is the least,
or not a number).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control import foot_filter as ff
from softlanding.control.estimation import MIN_WEIGHT
from softlanding.control.export_c.binding import CController
from softlanding.control.export_c.filter_check import StepCall
from softlanding.control.export_c.reference import plan_forces, relative_difference
from softlanding.control.recovery import filtered_step, sample_weight

#: The outcomes of a sample's recovery (:func:`recovery_outcome`).
OUTCOMES = ("recovered", "recovery deferred", "recovery failed")


@dataclass
class StepComparison:
    """How far the C filtered step's outputs are from the Python one's.

    Attributes
    ----------
    steps : int
        Samples compared.
    weighted : int
        Samples the estimate weighed less than 1.
    outcomes : dict
        How many samples' push needed the bounded full solve (:data:`OUTCOMES`): it
        converged (``"recovered"``), ran out of the sample's work and goes on at the next
        (``"recovery deferred"``), or did neither (``"recovery failed"``: not covered, or
        :data:`~softlanding.control.recovery.RECOVERY_SAMPLES` deferred in a row).
    statuses : dict
        Status name -> how many samples of the Python step returned it.
    weights : dict
        The :func:`weight_probes` by the Python weight: ``"1"``, ``"weighted"``, ``"least"``
        (:data:`~softlanding.control.estimation.MIN_WEIGHT`).
    max_relative : dict
        ``"weight"``, ``"status"`` (1 if any differs), ``"P"``, ``"M"``, ``"recovering"``
        (the recovery's count), ``"force"``: the largest relative difference of each.
    """

    steps: int = 0
    weighted: int = 0
    outcomes: dict[str, int] = field(default_factory=lambda: dict.fromkeys(OUTCOMES, 0))
    statuses: dict[str, int] = field(default_factory=dict)
    weights: dict[str, int] = field(default_factory=lambda: dict.fromkeys(
        ("1", "weighted", "least"), 0))
    max_relative: dict[str, float] = field(default_factory=lambda: dict.fromkeys(
        ("weight", "status", "P", "M", "recovering", "force"), 0.0))

    def worst(self) -> float:
        """The largest relative difference of any output."""
        return max(self.max_relative.values(), default=0.0)

    def describe(self) -> str:
        """One line: what was compared and how far apart."""
        o = self.outcomes
        return (f"{self.steps} filtered steps ({self.weighted} weighted; the bounded full "
                f"solve {o['recovered']} recovered, {o['recovery deferred']} deferred, "
                f"{o['recovery failed']} failed) and {sum(self.weights.values())} weights "
                f"of a grid ({self.weights['least']} the least), largest relative difference "
                f"{self.worst():.3g}")


def recovery_outcome(status: int, M: np.ndarray, before: int, after: int,
                     M_before: np.ndarray | None = None) -> str | None:
    """What the recovery did in a sample (:data:`OUTCOMES`), or None where it did not run.

    Parameters
    ----------
    status : int
        The sample's status (:func:`~softlanding.control.recovery.filtered_step`'s).
    M : array
        The memory after it (its ``M_STATUS`` the real-time step's own).
    before, after : int
        The recovery's count before and after it.
    M_before : array, optional
        The memory before it: a recovery that failed is a Newton failure of a push whose
        iteration had been unconverged for ``MAX_UNCONVERGED`` samples, which the fallback
        then met (``M_FALLBACKS`` up, ``M_WHY`` the failure).
    """
    if status == bb.OK and M[bb.M_STATUS] == bb.NEWTON_FAILED:
        return "recovered"
    if status == bb.DEFERRED and after == before + 1:
        return "recovery deferred"
    if M_before is not None and M[bb.M_FALLBACKS] > M_before[bb.M_FALLBACKS] \
            and M[bb.M_WHY] == bb.NEWTON_FAILED and M_before[bb.M_PHASE] == bb.PUSH \
            and M_before[bb.M_UNCONVERGED] >= bb.MAX_UNCONVERGED:
        return "recovery failed"
    return None


def weight_probes(P: np.ndarray
                  ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, float, float]]:
    """A grid of the weight's inputs: ``(M, F, x, a_f, u)`` for the numbers ``P``, over the
    foot's height (above the surface too) and velocity (at rest too), the ground force
    (negative too), the estimate (negative too) and the filter's covariance (none, small,
    so large that the weight is the least, not a number).

    Parameters
    ----------
    P : array
        :func:`~softlanding.control.bangbang.robot_numbers`.
    """
    out = []
    u = float(P[bb.P_UMAX])
    for xf, vf, force, k, c_d, cov in itertools.product(
            (0.1, 0.0, -0.5, -3.0), (0.0, -1e-3, -1.0, -10.0), (-1.0, 0.0, 0.5, 50.0),
            (-0.1, 0.0, 0.5, 3.0), (-0.2, 0.0, 1.0),
            ((0.0, 0.0, 0.0), (1e-3, 0.0, 1e-3), (0.5, 0.1, 0.8), (1e9, -1e8, 1e9),
             (np.nan, 0.0, 0.0))):
        M = bb.new_memory(0.1, 0.1, (k, c_d), (1.0, 1.0), 1.0)
        F = ff.new_filter(np.array([10.0, vf, xf, vf]))
        F[ff.F_P00], F[ff.F_P01], F[ff.F_P11] = cov
        a_f = float(P[bb.P_AF0] + P[bb.P_BF] * u + P[bb.P_GF] * force)
        out.append((M, F, np.array([10.0, vf, xf, vf]), a_f, u))
    return out


def compare_steps(c: CController, calls: list[StepCall]) -> StepComparison:
    """Run ``calls`` through the C filtered step and the Python one, and compare.

    Parameters
    ----------
    c : CController
        The compiled export.
    calls : list of StepCall
        :func:`~.filter_check.filtered_calls`' steps.
    """
    out = StepComparison(steps=len(calls))
    ws = bb.workspace()
    keys = ("weight", "status", "P", "M", "recovering", "force")
    got: dict[str, list[np.ndarray]] = {k: [] for k in keys}
    want: dict[str, list[np.ndarray]] = {k: [] for k in keys}
    for k in calls:
        Pp, Pc, Mp, Mc = k.P.copy(), k.P.copy(), k.M.copy(), k.M.copy()
        wp = sample_weight(Pp, Mp, k.F, k.x, k.a_f, k.u)
        wc = c.filtered_weight(Pc, Mc, k.F.copy(), k.x.copy(), k.a_f, k.u)
        # the sample's weight as mpc_landing gives it (1 without a fit), the same to both
        w = wp if k.estimate else 1.0
        sp, rp = filtered_step(Pp, Mp, k.x.copy(), k.a_f, k.u, k.h, k.estimate, w,
                               k.recovering, *ws)
        sc, rc = c.filtered_step(Pc, Mc, k.x.copy(), k.a_f, k.u, k.h, k.estimate, w,
                                 k.recovering)
        out.weighted += w < 1.0
        name = bb.STATUS_NAMES[sp]
        out.statuses[name] = out.statuses.get(name, 0) + 1
        outcome = recovery_outcome(sp, Mp, k.recovering, rp, k.M)
        if outcome is not None:
            out.outcomes[outcome] += 1
        length = (Mp[bb.M_TAU1] if Mp[bb.M_PHASE] == bb.PUSH else 0.0) + Mp[bb.M_TAU2]
        times = np.array([0.5 * Pp[bb.P_PERIOD], 0.5 * length, 1.2 * length])
        for key, a, b in (("weight", wc, wp), ("status", sc, sp), ("P", Pc, Pp),
                          ("M", Mc, Mp), ("recovering", rc, rp),
                          ("force", [c.force(Pc, Mc, t) for t in times],
                           plan_forces(Pp, Mp, times))):
            got[key].append(np.atleast_1d(np.asarray(a, float)))
            want[key].append(np.atleast_1d(np.asarray(b, float)))
    P = np.ascontiguousarray(c.robot_numbers)
    for M, F, x, a_f, u in weight_probes(P):
        wp = sample_weight(P, M, F, x, a_f, u)
        out.weights["1" if wp == 1.0 else "least" if wp == MIN_WEIGHT else "weighted"] += 1
        got["weight"].append(np.array([c.filtered_weight(P, M, F, x, a_f, u)]))
        want["weight"].append(np.array([wp]))
    for key in keys:
        if got[key]:
            out.max_relative[key] = relative_difference(np.concatenate(got[key]),
                                                        np.concatenate(want[key]))
    out.max_relative["status"] = float(out.max_relative["status"] > 0)
    return out


__all__ = ["OUTCOMES", "StepComparison", "compare_steps", "recovery_outcome", "weight_probes"]
