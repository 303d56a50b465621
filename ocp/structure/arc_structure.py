"""The arc structure's types: :class:`Arc` (one control's maximal interval at a bound, on a
constraint or inside), :class:`SwitchingStructure` (one control's arcs),
:class:`Interval` and :class:`ArcStructure` (the switch events of every control merged:
the refinement's unknowns), and :class:`TranscribedSolution`, what they read of a solution.
Found by :mod:`ocp.structure.arcs`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, cast

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.solution import Solution
from .flows import Mode

__all__ = ["BANG", "Arc", "ArcStructure", "Interval", "SolutionLike", "SwitchingStructure",
           "TranscribedSolution", "transcribed"]

BANG = ("max", "min")


class TranscribedSolution(Protocol):
    """What this package reads of an :class:`ocp.Solution` (which sets these attributes
    dynamically, so type checkers cannot see them on the class)."""

    problem: OptimalControlProblem
    transcription: Any
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    T: float
    t0: float
    N: int
    params: dict[str, float]
    variables: dict[str, float]
    multipliers: dict[str, np.ndarray]
    objective: float

    def control(self, name: str) -> np.ndarray:
        """The column of control ``name``.

        Parameters
        ----------
        name : str
            Control name.
        """
        ...

    def evaluate(self, expr: ca.SX) -> np.ndarray:
        """An expression of (x, u, p) at every node.

        Parameters
        ----------
        expr : casadi.SX
            An expression of the problem's states, controls and parameters.
        """
        ...


SolutionLike = Solution | TranscribedSolution
"""A transcribed solution, as passed in (``Solution``) or as read (the protocol)."""


def transcribed(sol: SolutionLike) -> TranscribedSolution:
    """``sol`` typed by :class:`TranscribedSolution` (no conversion).

    Parameters
    ----------
    sol : Solution or Trajectory-like
        A solution of a transcription.
    """
    return cast(TranscribedSolution, sol)


@dataclass
class Arc:
    """A maximal interval where one control sits at a bound, on a constraint, or inside.

    Attributes
    ----------
    kind : {"max", "min", "boundary", "vertex", "interior", "singular"}
        ``"singular"`` only where a caller has classified an interior arc as singular
        (:func:`ocp.structure.interior_arcs.refinable_arcs`).
    start, end : float
    active : tuple of str
        State and mixed path constraints active at every node of the arc.
    constraint, side : str or None
        On a boundary arc, the constraint held and its limit (``"lower"``/``"upper"``).
    faces : tuple of str
        Control-only path constraints active at every node of the arc (faces of
        the control set the controls sit on; not state constraints).
    """

    kind: str
    start: float
    end: float
    active: tuple[str, ...] = ()
    constraint: str | None = None
    side: str | None = None
    faces: tuple[str, ...] = ()

    @property
    def duration(self) -> float:
        """``end - start``."""
        return self.end - self.start

    def mode_key(self) -> tuple[str, str | None, str | None]:
        """``(kind, constraint, side)``: arcs with equal keys merge."""
        return (self.kind, self.constraint, self.side)

    @property
    def mode(self) -> Mode:
        """The arc as a refinement :class:`~ocp.structure.flows.Mode` (bang or boundary arcs
        only)."""
        if self.kind == "interior":
            raise ValueError("an interior (singular or free) arc has no refinement mode")
        return Mode(self.kind, self.constraint, self.side)


@dataclass
class SwitchingStructure:
    """Arcs of one control, and whether they are all bang arcs.

    Attributes
    ----------
    control : str
        The control's name.
    arcs : list of Arc
        Its arcs in time order.
    lower, upper : float
        Its bounds.
    """

    control: str
    arcs: list[Arc]
    lower: float
    upper: float

    @property
    def kinds(self) -> list[str]:
        """The arcs' kinds in order."""
        return [a.kind for a in self.arcs]

    @property
    def bang_bang(self) -> bool:
        """Every arc at a bound or at a vertex of the control set (no boundary and no
        interior arc)."""
        return all(a.kind in BANG or a.kind == "vertex" for a in self.arcs)

    @property
    def refinable(self) -> bool:
        """Every arc is a bang or a boundary arc: switching-time refinement applies."""
        return all(a.kind != "interior" for a in self.arcs)

    @property
    def switch_times(self) -> list[float]:
        """Times between consecutive arcs."""
        return [a.end for a in self.arcs[:-1]]

    def without_trailing_constrained(self) -> SwitchingStructure:
        """Drop a final non-bang arc on which a path (state) constraint is active.

        On such an arc the control is whatever keeps the state on its
        constraint, not a bang. Dropping it refines the problem whose final
        time is the end of the last bang arc, which is the right question when
        the terminal conditions already account for the constrained tail (as
        the soft landing's body-arrest condition does).
        """
        last = self.arcs[-1]
        if len(self.arcs) > 1 and last.kind not in BANG and last.active:
            return SwitchingStructure(self.control, self.arcs[:-1], self.lower, self.upper)
        return self


@dataclass
class Interval:
    """An interval between consecutive switch events of any control, with each control's mode.

    Attributes
    ----------
    start, end : float
        The interval's times.
    modes : tuple of Mode
        Each control's mode on it.
    """

    start: float
    end: float
    modes: tuple[Mode, ...]

    @property
    def duration(self) -> float:
        """``end - start``."""
        return self.end - self.start


@dataclass
class ArcStructure:
    """The arc structure of every control, merged into intervals.

    Attributes
    ----------
    controls : tuple of str
    per_control : tuple of SwitchingStructure
        One per control.
    intervals : list of Interval
        Between consecutive switch events of any control; the refinement's unknowns
        are their durations.
    """

    controls: tuple[str, ...]
    per_control: tuple[SwitchingStructure, ...]
    intervals: list[Interval] = field(default_factory=list)

    @property
    def modes(self) -> tuple[tuple[Mode, ...], ...]:
        """Per interval, the mode of every control."""
        return tuple(iv.modes for iv in self.intervals)

    @property
    def kinds(self) -> list[tuple[str, ...]]:
        """Per interval, the kind of every control."""
        return [tuple(m.kind for m in iv.modes) for iv in self.intervals]

    @property
    def durations(self) -> list[float]:
        """Interval lengths."""
        return [iv.duration for iv in self.intervals]

    @property
    def switch_times(self) -> list[float]:
        """Switch events of any control, in order."""
        return [iv.end for iv in self.intervals[:-1]]

    @property
    def bang_bang(self) -> bool:
        """Every control bang-bang."""
        return all(s.bang_bang for s in self.per_control)

    @property
    def refinable(self) -> bool:
        """Every arc of every control is a bang or boundary arc."""
        return all(s.refinable for s in self.per_control)

    @property
    def T(self) -> float:
        """End of the last interval."""
        return self.intervals[-1].end if self.intervals else 0.0

    @classmethod
    def from_controls(cls, structures: list[SwitchingStructure] | tuple[SwitchingStructure, ...],
                      merge_tol: float = 1e-12) -> ArcStructure:
        """Merge per-control arcs into intervals between the switch events of all controls.

        Events of different controls closer than ``merge_tol * T`` are one event.
        When some control has an interior (singular or free) arc there are no
        intervals (``refinable`` is False).
        """
        structures = tuple(structures)
        names = tuple(s.control for s in structures)
        if not all(s.refinable for s in structures):
            return cls(names, structures, [])  # interior arcs: no refinement intervals
        T = max(s.arcs[-1].end for s in structures)
        ev = sorted({t for s in structures for t in s.switch_times})
        events: list[float] = []
        for t in ev:
            if not events or t - events[-1] > merge_tol * max(T, 1.0):
                events.append(t)
        edges = [0.0, *events, T]
        intervals: list[Interval] = []
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            mid = 0.5 * (a + b)
            modes = tuple(_arc_at(s, mid).mode for s in structures)
            if intervals and intervals[-1].modes == modes:
                intervals[-1].end = b
            else:
                intervals.append(Interval(a, b, modes))
        return cls(names, structures, intervals)

    @classmethod
    def from_modes(cls, controls: tuple[str, ...], modes: list[tuple[Mode, ...]],
                   durations: list[float]) -> ArcStructure:
        """A structure given directly by interval modes and durations (a guess)."""
        edges = np.r_[0.0, np.cumsum(durations)]
        intervals = [Interval(float(edges[k]), float(edges[k + 1]), tuple(m))
                     for k, m in enumerate(modes)]
        per = []
        for j, name in enumerate(controls):
            arcs: list[Arc] = []
            for iv in intervals:
                m = iv.modes[j]
                if arcs and arcs[-1].mode == m:
                    arcs[-1].end = iv.end
                else:
                    arcs.append(Arc(m.kind, iv.start, iv.end, (), m.constraint, m.side))
            per.append(SwitchingStructure(name, arcs, np.nan, np.nan))
        return cls(tuple(controls), tuple(per), intervals)


def _arc_at(s: SwitchingStructure, t: float) -> Arc:
    for a in s.arcs:
        if t <= a.end:
            return a
    return s.arcs[-1]
