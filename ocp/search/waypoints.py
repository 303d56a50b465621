"""Waypoint starts of :func:`ocp.multistart`: a path bent through a point of the state
box, with the controls and the free time that fit the dynamics along it.

Local optima that differ in where the trajectory goes -- round an obstacle on one side
or the other, through a high or a low arc -- are reached from paths that already go
there. A waypoint start is built from a point of a scrambled Sobol' sequence (or a
Latin hypercube) in the box of the coordinates (:mod:`ocp.search.starts`):

* **the path**: the default guess's states plus ``sin(pi s) (z - x_default(1/2))``
  (``s`` the normalised time), which keeps the guess's end values and passes through
  the sampled ``z`` at mid-phase;
* **the controls and the duration that fit it**: at every point of the path, the
  control, among a grid of levels of its box (:data:`LEVELS` per control, fewer when
  there are several), whose rates ``f(t, x, u)`` come closest to the path's own; a free
  duration ``T``, among :data:`TIMES` values of its box, is the one for which the path
  drifts least from the dynamics -- the mean over the path of
  ``min_u |dx/ds - T f(x, u)|`` relative to the states' boxes -- so that Ipopt starts
  from small defects (a heading that points along the path, a final time the speed
  can cover) instead of a random constant control and a random time;
* **of** :data:`CANDIDATES` **waypoints** (consecutive points of the sequence) the one
  whose fitted path violates the path constraints and state bounds least
  (:class:`ocp.search.feasibility.PathCheck`); the first one where nothing is
  violated (a problem without path constraints always takes the first, so the starts
  keep the sequence's spread). The states are then clipped into their bounds.

A phase time-linked to a previous one starts at that phase's fitted end time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from .feasibility import PathCheck, mapped_rates
from .starts import (
    SAMPLES,
    Coordinate,
    PhasePart,
    assemble,
    duration_box,
    prefix,
    sampled_points,
)

__all__ = ["CANDIDATES", "LEVELS", "TIMES", "WaypointStarts"]

CANDIDATES = 4
"""Waypoints tried per start (consecutive points of the sequence); the least violating kept."""
LEVELS = 11
"""Levels per control in the grid the controls are fitted on (fewer with several controls:
at most about 125 grid points in all, at least 2 levels each)."""
TIMES = 25
"""Candidate durations of a free phase, spread over its box."""
MAX_GRID = 125


@dataclass
class _Phase:
    """What the waypoint starts need of one phase."""

    t0: float
    duration: Coordinate | None  # the free duration's box, None if fixed
    duration_name: str
    fixed_duration: float
    x_default: np.ndarray  # the default guess's states on the SAMPLES grid
    x_mid: np.ndarray  # and at mid-phase
    xlo: np.ndarray
    xhi: np.ndarray
    width: np.ndarray  # each state's box width
    grid: np.ndarray  # the control candidates, (M, nu)
    check: PathCheck
    names: tuple[list[str], list[str]]  # state and control names


class WaypointStarts:
    """Builds the waypoint starts of a transcription (see the module docstring).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    coords : list of Coordinate
        The coordinates and their boxes.
    base : Solution
        The default guess (:func:`ocp.search.starts.default_solution`).
    method : {"sobol", "lhs"}
        The sequence of waypoints.
    rng : numpy.random.Generator
        Its seed.
    count : int
        The most starts that will be asked for.
    """

    def __init__(self, tr: Transcription, params: dict[str, float], coords: list[Coordinate],
                 base: Solution, method: str, rng: np.random.Generator, count: int) -> None:
        self.tr, self.base = tr, base
        self.pv = np.asarray(tr.param_vector(params), dtype=float).ravel()
        self.points = sampled_points(coords, count * CANDIDATES, method, rng)
        self.links = {b: a for a, b in tr.multiphase.time_links}
        by_name = {c.name: c for c in coords}
        self.phases = [self._setup(i, by_name) for i in range(len(base.phases))]

    def _setup(self, i: int, by_name: dict[str, Coordinate]) -> _Phase:
        ps, pre = self.base.phases[i], prefix(self.tr, i)
        snames, cnames = list(ps.problem.state_names), list(ps.problem.control_names)
        xlo, xhi = (np.array(v, dtype=float).ravel()
                    for v in self.tr.compiled[i].bounds(self.pv)[2:4])
        s = np.linspace(0.0, 1.0, SAMPLES)
        x_default, _ = ps.at(ps.t0 + (ps.T - ps.t0) * s)
        x_mid, _ = ps.at(np.array([0.5 * (ps.t0 + ps.T)]))
        duration, dname = duration_box(self.tr, i, by_name, ps.t0)
        width = np.array([max(by_name[pre + n].hi - by_name[pre + n].lo, 1e-12)
                          for n in snames])
        grid = control_grid([by_name[pre + n] for n in cnames])
        return _Phase(ps.t0, duration, dname, ps.T - ps.t0, np.asarray(x_default, dtype=float),
                      np.asarray(x_mid[0], dtype=float), xlo, xhi, width, grid,
                      PathCheck.of(self.tr, i, self.pv, SAMPLES), (snames, cnames))

    def make(self, number: int) -> tuple[dict[str, float], np.ndarray]:
        """The ``number``-th waypoint start: its description and decision vector.

        Parameters
        ----------
        number : int
            Which start (0, 1, ...): it takes the points ``CANDIDATES * number`` on.

        Returns
        -------
        tuple
            ``(point, w)``: the waypoint's states, the fitted controls at mid-phase, the
            times and decision variables by name; and the decision vector.
        """
        best: tuple[float, dict[str, float], list[PhasePart]] | None = None
        for pt in self.points[CANDIDATES * number:CANDIDATES * (number + 1)]:
            violation, point, parts = self._candidate(dict(pt))
            if best is None or violation < best[0]:
                best = (violation, point, parts)
            if violation == 0.0:
                break
        assert best is not None
        _, point, parts = best
        return point, assemble(self.tr, self.base, parts, point)

    def _candidate(self, pt: dict[str, float]) -> tuple[float, dict[str, float],
                                                        list[PhasePart]]:
        """One waypoint's phases, its description and its violation (summed over phases)."""
        v = np.array([pt.get(n, 0.0) for n in self.tr.multiphase.var_names], dtype=float)
        parts: list[PhasePart] = []
        total = 0.0
        for i, ph in enumerate(self.phases):
            pre = prefix(self.tr, i)
            t0 = float(parts[self.links[i]].t[-1]) if i in self.links \
                else pt.get(pre + "t0", ph.t0)
            part, violation = self._phase(i, ph, pre, t0, pt, v)
            parts.append(part)
            total += violation
        return total, pt, parts

    def _phase(self, i: int, ph: _Phase, pre: str, t0: float, pt: dict[str, float],
               v: np.ndarray) -> tuple[PhasePart, float]:
        """Phase ``i`` of a start: the bent path, the fitted controls and duration (written
        into ``pt``) and the path's violation."""
        snames, cnames = ph.names
        s = np.linspace(0.0, 1.0, SAMPLES)
        z = np.array([pt[pre + n] for n in snames])
        x = ph.x_default + np.sin(np.pi * s)[:, None] * (z - ph.x_mid)[None, :]
        static = np.concatenate([self.pv, v, [t0, t0 + ph.fixed_duration]])
        times = np.array([ph.fixed_duration]) if ph.duration is None \
            else duration_grid(ph.duration)
        rates = self._rates(i, ph, t0 + ph.fixed_duration * s, x, static)
        duration, pick = fitted(np.gradient(x, s, axis=0), rates, times, ph.width)
        u = ph.grid[pick]
        t = t0 + duration * s
        static[-1] = t0 + duration
        violation = ph.check.violation(t, x, u, static)
        if ph.duration is not None:
            pt[ph.duration_name] = duration + (t0 if ph.duration_name.endswith("T") else 0.0)
        for j, n in enumerate(cnames):
            pt[pre + n] = float(u[SAMPLES // 2, j])
        return PhasePart(t, np.clip(x, ph.xlo, ph.xhi), u), violation

    def _rates(self, i: int, ph: _Phase, t: np.ndarray, x: np.ndarray,
               static: np.ndarray) -> np.ndarray:
        """The dynamics' rates at every point of the path under every control of the grid,
        ``(M, SAMPLES, nx)`` (non-finite rates replaced by a large value)."""
        m, k = ph.grid.shape[0], t.size
        fn = mapped_rates(self.tr, i, m * k)
        tt = np.tile(t, m)[None, :]
        xx = np.tile(x.T, (1, m))
        uu = np.repeat(ph.grid.T, k, axis=1)
        with np.errstate(all="ignore"):
            f = np.asarray(fn(tt, xx, uu, np.tile(static[:, None], (1, m * k))), dtype=float)
        f[~np.isfinite(f)] = 1e12
        return f.T.reshape(m, k, -1)


def control_grid(boxes: list[Coordinate]) -> np.ndarray:
    """The candidate controls: a grid of levels of every control's box, ``(M, nu)``.

    Parameters
    ----------
    boxes : list of Coordinate
        The controls' boxes.
    """
    nu = len(boxes)
    if nu == 0:
        return np.zeros((1, 0))
    levels = max(2, min(LEVELS, int(math.floor(MAX_GRID ** (1.0 / nu) + 1e-9))))
    axes = [np.linspace(c.lo, c.hi, levels) for c in boxes]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([g.ravel() for g in mesh])


def duration_grid(box: Coordinate) -> np.ndarray:
    """:data:`TIMES` durations spread over a box (log-spaced when it is sampled so).

    Parameters
    ----------
    box : Coordinate
        The duration's box.
    """
    return np.array([box.value(r) for r in np.linspace(0.0, 1.0, TIMES)])


def fitted(dxds: np.ndarray, rates: np.ndarray, times: np.ndarray,
           width: np.ndarray) -> tuple[float, np.ndarray]:
    """The duration and the controls (grid indices per point) that fit a path best.

    For a duration ``T`` the drift at point ``k`` under control ``m`` is
    ``|dx/ds_k - T f_mk|^2`` relative to the states' widths; every point takes the
    control of least drift, and the duration is the one of least mean drift among
    those the dynamics can cover: at least the mean over the path of
    ``|dx/ds| / max_m |f_m|``, the time to run along it at the fastest rate the
    controls give (where the rates cannot point along the path, a shorter time would
    only shrink the drift by asking for no motion; if no candidate is that long, the
    longest).

    Parameters
    ----------
    dxds : ndarray
        The path's derivative in normalised time, ``(K, nx)``.
    rates : ndarray
        The rates under every control, ``(M, K, nx)``.
    times : ndarray
        Candidate durations.
    width : ndarray
        The states' widths.
    """
    d = dxds / width
    f = rates / width
    a = np.sum(f * f, axis=2)  # (M, K)
    b = np.sum(f * d[None, :, :], axis=2)
    c = np.sum(d * d, axis=1)[None, :]
    with np.errstate(divide="ignore"):
        least = float(np.mean(np.sqrt(c[0]) / np.sqrt(np.max(a, axis=0))))
    times = times[times >= least] if np.any(times >= least) else times[-1:]
    best, pick, duration = math.inf, np.zeros(dxds.shape[0], dtype=int), float(times[0])
    for T in times:
        drift = T * T * a - 2.0 * T * b + c
        m = np.argmin(drift, axis=0)
        mean = float(np.mean(drift[m, np.arange(drift.shape[1])]))
        if mean < best:
            best, pick, duration = mean, m, float(T)
    return duration, pick
