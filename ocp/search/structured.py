"""Structured starts of :func:`ocp.multistart`: bang sequences of the controls, simulated.

Local optima of a control problem mostly differ in the control's structure --
how many arcs at the bounds and in which order (a pendulum pumped in three or
four swings, a car that turns left or right first) -- and in the time scale.
A structured start is built as one builds a guess by hand:

* every control is piecewise constant with 0, 1 or 2 switches at random
  times, alternating between the low and the high end of its box (its
  bounds; an unbounded side: the default guess's value -+ ``spread`` times its
  scale, as for the sampled starts). That is a bang sequence where the
  problem is affine in the control (dynamics, running cost and path
  constraints), where bang-bang and singular arcs are what extremals are made
  of; where it is not (a heading angle in ``cos``/``sin``, a quadratic cost),
  the levels are random points of the low and the high half of the box
  instead. The six sequences (0, 1 or 2 switches, starting low or high) are
  dealt in turn to the first control, at random to the others; a start identical to
  one made before (a sequence without switches has no random time to vary it, so its
  second turn would repeat the first solve) is replaced by the next sequence's;
* the states are simulated forward from the default guess's initial state
  under that control (RK4, :data:`STEPS` steps over the phase's time box), so
  that they follow the dynamics;
* a free final time is the time at which the simulated states come closest to
  the terminal values the problem fixes (equalities in one state's end value;
  each difference relative to the state's box), searched within the phase's
  time box; without such values it is a random point of that box. The states
  are then corrected linearly in time to those terminal values, so that the
  start meets the end conditions and Ipopt closes the dynamics' small defect;
* of :data:`CANDIDATES` such starts (the same sequence, other switch times and
  durations) the one kept is the one whose simulation ends closest to the
  terminal values and whose corrected states violate the path constraints and
  state bounds least (each relative to ``max(1, |bound|)``, as the check
  between nodes measures it); the states are then clipped into their bounds.
  A simulation is cheap next to a solve; a start that leaves the bounds or
  runs through an obstacle costs Ipopt hundreds of iterations.

A phase time-linked to a previous one starts at that phase's end time and
its end states (same names).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..definition.guess import fixed_ends
from ..definition.problem import OptimalControlProblem
from ..transcriptions.integrators import rk4_interval
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from .feasibility import PathCheck
from .starts import SAMPLES, Coordinate, PhasePart, assemble, duration_box, prefix

__all__ = ["PATTERNS", "STEPS", "StructuredStarts"]

STEPS = 400
"""RK4 steps of a structured start's simulation over its phase's time box."""
CANDIDATES = 6
"""Candidates simulated per structured start; the one that ends closest to the targets and
violates the path constraints least is kept."""
PATTERNS = tuple((switches, first) for switches in (0, 1, 2) for first in (0, 1))
"""(number of switches, first level: 0 the box's low end, 1 its high end)."""


@dataclass
class _PhaseSetup:
    """What the structured starts need of one phase."""

    t0: float
    duration: Coordinate | None  # the box of the free duration, None if fixed
    duration_name: str
    fixed_duration: float
    x0: np.ndarray
    xlo: np.ndarray
    xhi: np.ndarray
    width: np.ndarray  # each state's box width
    ulo: np.ndarray
    uhi: np.ndarray
    targets: dict[int, float]  # fixed terminal values by state index
    simulate: ca.Function
    pv: np.ndarray  # the parameters and decision variables, [p; v] of the static vector
    bang: list[bool]  # per control: the problem is affine in it (levels at the box's ends)
    check: PathCheck  # the path constraints and bounded states on SAMPLES points


class StructuredStarts:
    """Builds the structured starts of a transcription (see the module docstring).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    coords : list of Coordinate
        The sampled starts' coordinates (their boxes are reused).
    base : Solution
        The default guess (:func:`ocp.search.starts.default_solution`).
    """

    def __init__(self, tr: Transcription, params: dict[str, float], coords: list[Coordinate],
                 base: Solution) -> None:
        self.tr, self.base = tr, base
        self.pv = np.asarray(tr.param_vector(params), dtype=float).ravel()
        w0 = tr.default_guess(params)
        self.v = np.asarray(w0[tr.iV], dtype=float).ravel()
        self.var_point = dict(zip(tr.multiphase.var_names, map(float, self.v), strict=True))
        self.links = {b: a for a, b in tr.multiphase.time_links}
        by_name = {c.name: c for c in coords}
        self.phases = [self._setup(i, by_name) for i in range(len(base.phases))]
        self.made: set[tuple[tuple[str, float], ...]] = set()  # the points of the starts made

    def _setup(self, i: int, by_name: dict[str, Coordinate]) -> _PhaseSetup:
        ps, cp = self.base.phases[i], self.tr.compiled[i]
        pre = prefix(self.tr, i)
        names = ps.problem.state_names
        _, _, xlo, xhi, _, _, _, _ = (np.array(v, dtype=float).ravel()
                                      for v in cp.bounds(self.pv))
        xbox = [by_name[pre + n] for n in names]
        ubox = [by_name[pre + n] for n in ps.problem.control_names]
        duration, dname = duration_box(self.tr, i, by_name, ps.t0)
        x_end, _ = ps.at(np.array([ps.T]))
        targets = {k: float(x_end[0, k]) for k in fixed_ends(ps.problem)[1]}
        return _PhaseSetup(
            ps.t0, duration, dname, ps.T - ps.t0,
            np.asarray(ps.x, dtype=float)[0], xlo, xhi,
            np.array([max(c.hi - c.lo, 1e-12) for c in xbox]),
            np.array([c.lo for c in ubox]), np.array([c.hi for c in ubox]), targets,
            _simulator(self.tr, i), np.concatenate([self.pv, self.v]), affine_controls(ps.problem),
            PathCheck.of(self.tr, i, self.pv, SAMPLES))

    def make(self, number: int, rng: np.random.Generator) -> tuple[dict[str, float], np.ndarray]:
        """The ``number``-th structured start: its description and decision vector.

        Parameters
        ----------
        number : int
            Which structured start (0, 1, ...): it picks the first control's sequence.
        rng : numpy.random.Generator
            Draws the switch times, the other controls' sequences and the sampled times.

        Returns
        -------
        tuple
            ``(point, w)``: the start's times, first control levels and switch times by
            name (``"u"``, ``"u.t1"``, ``"u.t2"``), and its decision vector. A start
            identical to one made before (a sequence without switches whose closest
            approach repeats) is replaced by the next sequence's.
        """
        for shift in range(len(PATTERNS)):  # a start made before would be solved again
            point, parts = self._best(number + shift, rng)
            key = tuple(sorted(point.items()))
            if key not in self.made:
                break
        self.made.add(key)
        return point, assemble(self.tr, self.base, parts, point)

    def _best(self, number: int, rng: np.random.Generator
              ) -> tuple[dict[str, float], list[PhasePart]]:
        """Of :data:`CANDIDATES` candidates of sequence ``number``, the one of least miss."""
        best: tuple[float, dict[str, float], list[PhasePart]] | None = None
        for _ in range(CANDIDATES):
            miss, point, parts = self._candidate(number, rng)
            if best is None or miss < best[0]:
                best = (miss, point, parts)
        assert best is not None
        _, point, parts = best
        return point | self.var_point, parts

    def _candidate(self, number: int, rng: np.random.Generator
                   ) -> tuple[float, dict[str, float], list[PhasePart]]:
        """One candidate: its terminal miss (summed over phases), description and phases."""
        point: dict[str, float] = {}
        parts: list[PhasePart] = []
        ends: list[tuple[float, np.ndarray]] = []
        total = 0.0
        for i, ph in enumerate(self.phases):
            pre = prefix(self.tr, i)
            t0, x0 = ph.t0, ph.x0.copy()
            if i in self.links:
                a = self.links[i]
                t0 = ends[a][0]
                prev = self.base.phases[a].problem.state_names
                for j, n in enumerate(self.base.phases[i].problem.state_names):
                    if n in prev:
                        x0[j] = ends[a][1][prev.index(n)]
            part, plan, miss = _phase_start(ph, t0, x0, number, rng, pre,
                                            self.base.phases[i].problem.control_names)
            point |= plan
            parts.append(part)
            ends.append((float(part.t[-1]), part.x[-1]))
            total += miss
        return total, point, parts


def affine_controls(ph: OptimalControlProblem) -> list[bool]:
    """Per control: whether the dynamics, running cost and path constraints are affine in it.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    """
    h, _, _ = ph.path_stack()
    rows = ca.vertcat(ph.rhs, ph.lagrange, h)
    return [not ca.depends_on(ca.jacobian(rows, ph.u[j]), ph.u) for j in range(ph.nu)]


def _simulator(tr: Transcription, i: int) -> ca.Function:
    """``STEPS`` RK4 steps of phase ``i`` (cached with the transcription's compiled phases)."""
    key = ("multistart_simulator", i, STEPS)
    cache = tr.grid_free.functions
    if key not in cache:
        cache[key] = rk4_interval(tr.compiled[i].ode, 1).mapaccum("simulate", STEPS)
    return cache[key]


def _levels(ph: _PhaseSetup, number: int, rng: np.random.Generator, duration: float,
            names: list[str], pre: str) -> tuple[list[tuple[np.ndarray, np.ndarray]],
                                                 dict[str, float]]:
    """Every control's switch times (from the phase start) and levels, and their description."""
    out, plan = [], {}
    for j, name in enumerate(names):
        k = number if j == 0 else int(rng.integers(len(PATTERNS)))
        switches, first = PATTERNS[k % len(PATTERNS)]
        times = np.sort(rng.uniform(0.05, 0.95, switches)) * duration
        lo, hi = ph.ulo[j], ph.uhi[j]
        ends = [(first + m) % 2 for m in range(switches + 1)]
        if ph.bang[j]:
            levels = np.where(ends, hi, lo).astype(float)
        else:  # a random point of the low or the high half of the box
            levels = lo + (np.array(ends) + rng.random(len(ends))) * (hi - lo) / 2
        out.append((times, levels))
        plan[pre + name] = float(levels[0])
        for m, ts in enumerate(times):
            plan[f"{pre}{name}.t{m + 1}"] = float(ts)
    return out, plan


def _controls_at(controls: list[tuple[np.ndarray, np.ndarray]], t: np.ndarray) -> np.ndarray:
    """The piecewise-constant controls at the times ``t`` from the phase start, (len(t), nu)."""
    cols = [levels[np.searchsorted(times, t, side="right")] for times, levels in controls]
    return np.column_stack(cols) if cols else np.zeros((t.size, 0))


def _phase_start(ph: _PhaseSetup, t0: float, x0: np.ndarray, number: int,
                 rng: np.random.Generator, pre: str, names: list[str]
                 ) -> tuple[PhasePart, dict[str, float], float]:
    """One phase of a structured start: simulate, pick the duration, correct the ends; and
    its score: the terminal miss before the correction (relative to the states' boxes)
    plus the path constraints' violation after it."""
    if ph.duration is None:
        sampled, lo, hi = ph.fixed_duration, ph.fixed_duration, ph.fixed_duration
    else:
        sampled = ph.duration.value(float(rng.random()))
        lo, hi = ph.duration.lo, ph.duration.hi
    controls, plan = _levels(ph, number, rng, sampled, names, pre)
    horizon = max(hi, sampled)
    grid = horizon * np.arange(STEPS + 1) / STEPS
    h = horizon / STEPS
    u_mid = _controls_at(controls, grid[:-1] + h / 2)
    static = np.concatenate([ph.pv, [t0, t0 + sampled]])
    xs = ph.simulate(x0, u_mid.T, (t0 + grid[:-1])[None, :], np.full((1, STEPS), h),
                     np.tile(static[:, None], (1, STEPS)))[0]
    x = _held_finite(np.vstack([x0, np.asarray(xs, dtype=float).T]))
    duration, miss = sampled, 0.0
    if ph.targets:
        idx = list(ph.targets)
        dist = np.linalg.norm((x[:, idx] - np.array([ph.targets[k] for k in idx]))
                              / ph.width[idx], axis=1)
        dist[(grid < lo - 1e-12 * hi) | (grid > hi + 1e-12 * hi)] = np.inf
        k = int(np.argmin(dist))
        duration, miss = float(grid[k]), float(dist[k])
    s = np.linspace(0.0, 1.0, SAMPLES)
    t = duration * s
    xg = np.column_stack([np.interp(t, grid, x[:, j]) for j in range(x.shape[1])])
    for k, value in ph.targets.items():
        xg[:, k] += s * (value - xg[-1, k])
    ug = _controls_at(controls, t)
    miss += ph.check.violation(t0 + t, xg, ug, np.concatenate([ph.pv, [t0, t0 + duration]]))
    xg = np.clip(xg, ph.xlo, ph.xhi)  # after scoring: a start that leaves them scores worse
    if ph.duration is not None:
        plan[ph.duration_name] = duration + (t0 if ph.duration_name.endswith("T") else 0.0)
    return PhasePart(t0 + t, xg, ug), plan, miss


def _held_finite(x: np.ndarray) -> np.ndarray:
    """The simulation up to its first non-finite row, that row's predecessor held after it."""
    bad = ~np.all(np.isfinite(x), axis=1)
    if np.any(bad):
        first = int(np.argmax(bad))
        x[first:] = x[max(first - 1, 0)]
    return x
