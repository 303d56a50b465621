"""Distinct local optima of :func:`ocp.multistart`, grouped as the starts arrive, and when to stop.

Two verified solutions are the same optimum when their objectives agree to
``objective_rtol * max(1, |J|)`` and their states, compared on a common
normalised time grid relative to ``1 + max |x|``, to ``distance_tol``. A new
solution is compared with the first solution of every optimum found so far,
in the order of the starts, so the grouping does not depend on where the
starts ran.

The stopping rule ``(k, m)`` (:class:`StopRule`): stop once the best
objective found so far has been reached by ``k`` starts and the last ``m``
starts found no objective that was not already known (a failed start finds
none). The landscape then repeats itself: more starts of the same kinds mostly
land on known optima. The rule reads objectives, not trajectories, so that a
family of solutions of equal cost (a control that does not matter on some arc)
counts as one level and does not keep the run going.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..transcriptions.solution import Solution

__all__ = ["LocalOptimum", "Optima", "StopRule", "trajectory_distance"]


@dataclass
class LocalOptimum:
    """One distinct local optimum: its objective, a solution, the starts that reached it.

    Attributes
    ----------
    objective : float
        Its objective (the best of the starts that reached it).
    solution : Solution
        The solution with that objective.
    starts : list of int
        The starts that reached it.
    fraction : float
        The fraction of the starts run that reached it.
    """

    objective: float
    solution: Solution
    starts: list[int] = field(default_factory=list)
    fraction: float = 0.0

    @property
    def count(self) -> int:
        """How many starts reached it."""
        return len(self.starts)


def trajectory_distance(a: Solution, b: Solution, samples: int = 101) -> float:
    """Largest state difference of two solutions on a common normalised time grid.

    Relative to ``1 + max |x|`` of each state over both; phase by phase.

    Parameters
    ----------
    a, b : Solution
        Two solutions of the same problem.
    samples : int
        Grid points per phase.
    """
    s = np.linspace(0.0, 1.0, samples)
    worst = 0.0
    for pa, pb in zip(a.phases, b.phases, strict=True):
        xa, _ = pa.at(pa.t0 + (pa.T - pa.t0) * s)
        xb, _ = pb.at(pb.t0 + (pb.T - pb.t0) * s)
        scale = 1.0 + np.maximum(np.abs(xa).max(axis=0), np.abs(xb).max(axis=0))
        worst = max(worst, float(np.max(np.abs(xa - xb) / scale)))
    return worst


class Optima:
    """The distinct optima of the starts recorded so far (see the module docstring).

    Parameters
    ----------
    objective_rtol, distance_tol : float
        When two solutions are the same optimum.
    """

    def __init__(self, objective_rtol: float, distance_tol: float) -> None:
        self.objective_rtol, self.distance_tol = objective_rtol, distance_tol
        self._founders: list[Solution] = []
        self._groups: list[LocalOptimum] = []
        self.recorded = 0
        self.last_new = -1  # the number of the last start that found a new objective
        self._objectives: list[float] = []  # every verified start's objective

    def add(self, index: int, sol: Solution | None) -> int | None:
        """Record start ``index``; returns the arrival number of its optimum (None if none).

        Parameters
        ----------
        index : int
            The start's number (starts are recorded in order).
        sol : Solution or None
            Its verified solution, or None when it has none.
        """
        self.recorded += 1
        if sol is None:
            return None
        if not any(self.same(sol.objective, o) for o in self._objectives):
            self.last_new = index
        self._objectives.append(sol.objective)
        for k, (founder, grp) in enumerate(zip(self._founders, self._groups, strict=True)):
            if self.same(sol.objective, founder.objective) and \
                    trajectory_distance(sol, founder) <= self.distance_tol:
                grp.starts.append(index)
                if sol.objective < grp.objective:
                    grp.objective, grp.solution = sol.objective, sol
                return k
        self._founders.append(sol)
        self._groups.append(LocalOptimum(sol.objective, sol, [index]))
        return len(self._groups) - 1

    def same(self, a: float, b: float) -> bool:
        """Whether two objectives are the same level (to ``objective_rtol * max(1, |b|)``).

        Parameters
        ----------
        a, b : float
            Two objectives.
        """
        return abs(a - b) <= self.objective_rtol * max(1.0, abs(b))

    def best_count(self) -> int:
        """How many starts reached the best objective so far (0 if none)."""
        if not self._objectives:
            return 0
        best = min(self._objectives)
        return sum(1 for o in self._objectives if self.same(o, best))

    def ranked(self) -> list[LocalOptimum]:
        """The optima best first, each with the fraction of the recorded starts that reached it."""
        out = sorted(self._groups, key=lambda g: (g.objective, g.starts[0]))
        for g in out:
            g.fraction = g.count / max(self.recorded, 1)
        return out


@dataclass(frozen=True)
class StopRule:
    """Stop once the best objective has ``best_count`` starts and ``quiet`` found none new.

    Attributes
    ----------
    best_count : int
        Starts that must have reached the best objective (``k``).
    quiet : int
        Consecutive latest starts without a new objective (``m``).
    """

    best_count: int
    quiet: int

    def reason(self, optima: Optima, index: int) -> str:
        """Why to stop after start ``index`` ("" to go on).

        Parameters
        ----------
        optima : Optima
            The optima recorded up to and including start ``index``.
        index : int
            The last start recorded.
        """
        k = optima.best_count()
        quiet = index - optima.last_new
        if optima.last_new < 0 or k < self.best_count or quiet < self.quiet:
            return ""
        return (f"stopped early after {index + 1} starts: the best objective was reached by {k} "
                f"starts and the last {quiet} found no new one "
                f"(stop=({self.best_count}, {self.quiet}))")
