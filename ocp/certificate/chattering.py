"""Chattering: switches that accumulate at a point, read off a transcription.

An optimal control *chatters* when its switch intervals shrink geometrically
toward a time ``t*`` (Fuller's phenomenon; infinitely many switches, often
entering or leaving a singular arc). A transcription cannot resolve that: it
shows a few switch intervals of decreasing length, then a stretch the grid
cannot resolve (an interior arc, or a switching function that oscillates at the
grid's period or stays near zero). A bang-bang certificate of such a solution
would be false, whatever its figures.

:func:`detect_chattering` looks for it in the sign changes of the switching
function ``sigma_j = dL/du_j + lambda^T g_j`` (costates from the
transcription's continuity multipliers): a run of consecutive intervals between
sign changes, each shorter than the one before by a ratio in
``[RATIO_MIN, RATIO_MAX]``, with ``|sigma|`` decaying along the run and after it
(a genuine last switch is followed by a growing ``|sigma|``). Such a run is a
*suspicion*; it is *confirmed* when, re-solved on a grid fine enough to resolve
the next predicted interval, the run has more switches (their number grows
with the grid, as an accumulation point's must). Without a re-solve, a run of
at least :data:`MIN_RUN_UNCONFIRMED` shrinking intervals with consistent ratios
counts on its own.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..structure.arcs import SolutionLike, TranscribedSolution, transcribed
from ..transcriptions.gridview import grid_spacing
from ..transcriptions.solution import along
from .costates import costates_from_multipliers, pmp_functions

RATIO_MIN, RATIO_MAX = 0.02, 0.7
"""Range of the ratio of consecutive switch intervals counted as geometric shrinking."""

RESOLVED = 2.0
"""An interval between sign changes shorter than this many grid spacings is unresolved."""

MIN_RUN_UNCONFIRMED = 3
"""Shrinking intervals a run needs to count without confirmation on a finer grid."""

__all__ = ["ChatteringResult", "MIN_RUN_UNCONFIRMED", "RATIO_MAX", "RATIO_MIN",
           "detect_chattering", "node_samples", "shrinking_runs"]


@dataclass
class ChatteringResult:
    """Switches accumulating at a point.

    Attributes
    ----------
    control : str
        The control whose switching function shows it.
    t_star : float
        Extrapolated accumulation point (geometric sum of the remaining intervals).
    ratio : float
        Geometric mean ratio of consecutive switch intervals in the run.
    switch_times : tuple of float
        The run's switches (sign changes of sigma), on the finest grid examined.
    direction : str
        ``"forward"`` (intervals shrink as t grows, toward t* from the left) or
        ``"backward"`` (they shrink as t decreases: switches leaving t*).
    confirmed : bool
        True: a finer grid resolved more switches in the run. False: no finer grid
        could be solved (not allowed, or its solve failed), and the run counts on its
        own (at least :data:`MIN_RUN_UNCONFIRMED` shrinking intervals, ratios within a
        factor 3 of each other).
    counts : dict
        Grid nodes -> switches of the run found on that grid.
    """

    control: str
    t_star: float
    ratio: float
    switch_times: tuple[float, ...]
    direction: str
    confirmed: bool
    counts: dict[int, int] = field(default_factory=dict)

    @property
    def reason(self) -> str:
        """One line for a certificate's reasons."""
        grids = ", ".join(f"{c} on {n} nodes" for n, c in sorted(self.counts.items()))
        return (f"chattering suspected near t = {self.t_star:.6g}, not certified: the switch "
                f"intervals of {self.control} shrink geometrically (ratio {self.ratio:.3g}) "
                f"toward it, switches in the run: {grids}")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict."""
        return {"control": self.control, "t_star": self.t_star, "ratio": self.ratio,
                "switch_times": list(self.switch_times), "direction": self.direction,
                "confirmed": self.confirmed,
                "counts": {str(k): v for k, v in self.counts.items()}}


@dataclass
class _Run:
    """A run of shrinking intervals between sign changes (forward time)."""

    zeros: np.ndarray
    ratio: float
    t_star: float
    direction: str
    ratios: np.ndarray


Samples = Callable[[Any], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
"""``samples(sol) -> (t, x, u, lambda)``: where the switching functions are evaluated."""


def node_samples(sol: SolutionLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Node times ``t_1..t_N``, states, the control after each node, multiplier costates.

    Parameters
    ----------
    sol : Solution
        A multiple-shooting solution.
    """
    tsol = transcribed(sol)
    t, lam = costates_from_multipliers(tsol)
    u = np.vstack([tsol.u[1:], tsol.u[-1:]])
    return t, tsol.x[1:], u, lam


def _sigma_samples(sol: TranscribedSolution, samples: Samples) -> tuple[np.ndarray, np.ndarray]:
    """Sample times and switching functions (m, nu)."""
    pr = sol.problem
    t, x, u, lam = samples(sol)
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    sigma = along(pmp_functions(pr).sigma, x, u, lam, pv)[0]
    return np.asarray(t, dtype=float), sigma


def _zeros(t: np.ndarray, s: np.ndarray, tiny: float) -> np.ndarray:
    """Sign changes of ``s`` by linear interpolation, skipping ``|s| <= tiny``."""
    nz = np.flatnonzero(np.abs(s) > tiny)
    a, b = nz[:-1], nz[1:]
    ch = np.sign(s[a]) != np.sign(s[b])
    a, b = a[ch], b[ch]
    return t[a] - s[a] * (t[b] - t[a]) / (s[b] - s[a])


def _amplitudes(t: np.ndarray, s: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``max |s|`` over the samples in each ``[edges[i], edges[i+1]]`` (0 if none)."""
    out = np.zeros(max(len(edges) - 1, 0))
    for i in range(len(out)):
        sel = (t >= edges[i]) & (t <= edges[i + 1])
        out[i] = float(np.max(np.abs(s[sel]), initial=0.0))
    return out


def _forward_runs(t: np.ndarray, s: np.ndarray, z: np.ndarray, h: float,
                  T_end: float) -> list[tuple[int, int]]:
    """Index ranges ``(i, e)`` of intervals ``d[i..e]`` that shrink toward a point ahead."""
    d = np.diff(z)
    if len(d) < 2:
        return []
    amp = _amplitudes(t, s, z)
    out = []
    i = 0
    while i < len(d) - 1:
        e = i
        while e + 1 < len(d) and d[e] > RESOLVED * h and d[e + 1] > RESOLVED * h \
                and RATIO_MIN <= d[e + 1] / d[e] <= RATIO_MAX and amp[e + 1] < amp[e]:
            e += 1
        if e > i and _decays_after(t, s, z[e + 1], d[e], amp[e], T_end):
            out.append((i, e))
        i = e + 1 if e > i else i + 1
    return out


def _decays_after(t: np.ndarray, s: np.ndarray, z_last: float, d_last: float, a_last: float,
                  T_end: float) -> bool:
    """``|s|`` stays below the run's last amplitude over one more run interval after it
    (an accumulation point ahead; a genuine last switch is followed by a growing |s|)."""
    sel = (t > z_last) & (t <= min(z_last + d_last, T_end))
    return bool(sel.any()) and float(np.max(np.abs(s[sel]))) < a_last


def _run(z: np.ndarray, i: int, e: int, direction: str, sign: float) -> _Run:
    d = np.diff(z)[i:e + 1]
    ratios = d[1:] / d[:-1]
    r = float(np.exp(np.mean(np.log(ratios))))
    zs = z[i:e + 2]
    t_star = float(zs[-1] + d[-1] * r / (1 - r))
    return _Run(sign * zs, r, sign * t_star, direction, ratios)


def shrinking_runs(t: np.ndarray, s: np.ndarray, h: float, T0: float,
                   T1: float) -> list[_Run]:
    """Runs of geometrically shrinking intervals between the sign changes of ``s``.

    Parameters
    ----------
    t, s : ndarray (m,)
        Sample times and one switching function.
    h : float
        Grid spacing (intervals shorter than ``RESOLVED * h`` are unresolved).
    T0, T1 : float
        The horizon.

    Returns
    -------
    list
        Each with ``zeros`` (the run's sign changes, in increasing time), ``ratio``,
        ``t_star`` and ``direction``; ``t_star`` inside the horizon.
    """
    scale = float(np.max(np.abs(s), initial=0.0))
    if scale == 0.0:
        return []
    z = _zeros(t, s, 1e-12 * scale)
    out = []
    for sign, direction in ((1.0, "forward"), (-1.0, "backward")):
        tt, zz = (t, z) if sign > 0 else (-t[::-1], -z[::-1])
        ss = s if sign > 0 else s[::-1]
        end = T1 if sign > 0 else -T0
        for i, e in _forward_runs(tt, ss, zz, h, end):
            run = _run(zz, i, e, direction, sign)
            if direction == "backward":
                run.zeros = run.zeros[::-1]
            if T0 < run.t_star < T1:
                out.append(run)
    return out


def _runs_of(sol: TranscribedSolution, samples: Samples) -> dict[str, list[_Run]]:
    t, sigma = _sigma_samples(sol, samples)
    h = grid_spacing(sol)
    return {name: shrinking_runs(t, sigma[:, j], h, float(sol.t[0]), float(sol.t[-1]))
            for j, name in enumerate(sol.problem.control_names)}


def _matching(runs: list[_Run], run: _Run, tol: float) -> _Run | None:
    """The run of ``runs`` with the same direction whose t* is closest to ``run``'s
    (within ``tol``)."""
    near = [r for r in runs if r.direction == run.direction and abs(r.t_star - run.t_star) <= tol]
    return min(near, key=lambda r: abs(r.t_star - run.t_star), default=None)


def _factor_to_resolve(run: _Run, h: float, max_factor: int) -> int:
    """Grid refinement (a power of 2) that resolves the next predicted interval."""
    d_next = abs(float(run.zeros[-1] - run.zeros[-2]) if run.direction == "forward"
                 else float(run.zeros[1] - run.zeros[0])) * run.ratio
    want = 2 * RESOLVED * h / max(d_next, 1e-300)
    factor = 2 ** max(1, math.ceil(math.log2(max(want, 2.0))))
    return int(min(factor, max_factor))


def detect_chattering(sol: SolutionLike, *,
                      resolve: Callable[[Any, int], Any] | None = None,
                      max_nodes: int = 1000,
                      samples: Samples | None = None) -> ChatteringResult | None:
    """Switches accumulating at a point, from a transcription's switching functions.

    Parameters
    ----------
    sol : Solution
        A converged transcribed solution (single phase).
    resolve : callable, optional
        ``resolve(sol, factor)`` re-solves on a grid ``factor`` times finer and
        returns the new solution (or None): the confirmation that the run gains
        switches on a finer grid (:func:`ocp.certificate.certify.detect_chattering` passes
        :func:`ocp.certificate.certify.finer_transcription`). Without it, only runs of at least
        :data:`MIN_RUN_UNCONFIRMED` shrinking intervals count.
    max_nodes : int
        Largest grid a confirmation may solve.
    samples : callable, optional
        ``samples(sol) -> (t, x, u, lambda)`` (default :func:`node_samples`, the
        multiple-shooting nodes and continuity multipliers).

    Returns
    -------
    ChatteringResult or None
        The run with the most switches that counts (see ``confirmed``); None when
        there is none.
    """
    tsol = transcribed(sol)
    smp = samples or node_samples
    found: list[ChatteringResult] = []
    for name, runs in _runs_of(tsol, smp).items():
        for run in runs:
            res = _confirm(tsol, name, run, resolve, max_nodes, smp)
            if res is not None:
                found.append(res)
    return max(found, key=lambda r: len(r.switch_times), default=None)


def _confirm(sol: TranscribedSolution, name: str, run: _Run,
             resolve: Callable[[Any, int], Any] | None, max_nodes: int,
             samples: Samples) -> ChatteringResult | None:
    """The run as a result if a finer grid gives it more switches or, when no finer grid
    can be solved, if it is long enough on its own; None otherwise."""
    N, h = int(sol.N), grid_spacing(sol)
    counts = {N: len(run.zeros)}
    fine = None
    if resolve is not None and max_nodes >= 2 * N:
        fine = resolve(sol, _factor_to_resolve(run, h, max_nodes // N))
    if fine is not None:
        fsol = transcribed(fine)
        tol = max(abs(float(run.zeros[-1] - run.zeros[0])), 4 * h)
        match = _matching(_runs_of(fsol, samples).get(name, []), run, tol)
        counts[int(fsol.N)] = 0 if match is None else len(match.zeros)
        if match is None or len(match.zeros) <= len(run.zeros):
            return None  # the finer grid does not add switches: no accumulation point
        return ChatteringResult(name, match.t_star, match.ratio,
                                tuple(map(float, match.zeros)), match.direction, True, counts)
    consistent = float(np.max(run.ratios) / np.min(run.ratios)) <= 3.0
    if len(run.ratios) + 1 >= MIN_RUN_UNCONFIRMED and consistent:
        return ChatteringResult(name, run.t_star, run.ratio, tuple(map(float, run.zeros)),
                                run.direction, False, counts)
    return None
