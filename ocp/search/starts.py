"""Sampled starts of :func:`ocp.multistart`: the box of what the problem knows, and its points.

A sampled start is a point of a scrambled Sobol' sequence or a Latin
hypercube (:mod:`scipy.stats.qmc`, seeded) in the box of these coordinates:

* every free initial time not linked to the previous phase's end (``t0``),
  in its bounds;
* every free final time: ``T`` when the phase starts at a fixed time, its
  ``duration`` otherwise. Its box is what the problem knows of the phase's
  time scale, not the bounds alone (``free_final_time()``'s default, [1e-3,
  1e3], spans six decades): the duration that start 0 converged to (else the
  guessed duration), and the time the dynamics need for the change the guess
  asks of the states (:func:`ocp.definition.sizes.transfer_time`); the box
  runs from the smallest of these over :data:`TIME_SPAN` to the largest times
  :data:`TIME_SPAN`, cut by the bounds (a bound narrower than that is a real
  range and is kept); log-uniform when it spans more than a decade;
* every state: its value at mid-phase. The start is the default guess plus
  ``sin(pi s) (z - x_default(1/2))`` (``s`` the normalised time), which keeps
  the guess's end values and passes through the sampled ``z`` at mid-phase;
* every control: a constant;
* every decision variable.

A state's or control's box is its bounds; an infinite side is replaced by the
default guess's value ``-+ spread * max(1, |value|)``; ``box={"name": (lo,
hi)}`` sets any coordinate's box by name (``"T"``, ``"duration"``, ``"t0"``;
``"phase.name"`` in a multi-phase problem).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import qmc

from ..definition.errors import ProblemDefinitionError
from ..definition.multiphase import PhaseTimes
from ..definition.scaling import loose_bounds
from ..definition.sizes import transfer_time
from ..definition.trajectory import Trajectory
from ..transcriptions.diagnosis import periodic_states
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from ..transcriptions.transcription import decision_bounds

__all__ = ["TIME_SPAN", "Coordinate", "PhasePart", "assemble", "duration_box",
           "start_coordinates"]

TIME_SPAN = 4.0
"""A free time's box spans its known scales divided and multiplied by this (module doc)."""
SAMPLES = 201
"""Points per phase of the trajectory a start is built from."""


@dataclass
class Coordinate:
    """One coordinate of a start and its box.

    Attributes
    ----------
    name : str
        Its name (``"T"``, a state's, a control's, ``"phase.name"`` in a multi-phase
        problem).
    lo, hi : float
        The box ``[lo, hi]``.
    log : bool
        Sampled log-uniformly.
    """

    name: str
    lo: float
    hi: float
    log: bool = False

    def value(self, r: float) -> float:
        """The coordinate at the fraction ``r`` in [0, 1] of its box.

        Parameters
        ----------
        r : float
            Fraction of the box (of its logarithm when ``log``).
        """
        if self.log:
            return float(math.exp(math.log(self.lo) + r * (math.log(self.hi) - math.log(self.lo))))
        return float(self.lo + r * (self.hi - self.lo))


@dataclass
class PhasePart:
    """One phase of a start on a grid of times.

    Attributes
    ----------
    t : ndarray
        The times (n,).
    x : ndarray
        The states (n, nx).
    u : ndarray
        The controls (n, nu).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


def prefix(tr: Transcription, phase: int) -> str:
    """The prefix of a phase's coordinate names (``"name."`` when there are several).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    phase : int
        The phase's index.
    """
    return f"{tr.multiphase.phases[phase].name}." if len(tr.phases) > 1 else ""


def start_coordinates(tr: Transcription, params: dict[str, float], spread: float = 1.0,
                      box: dict[str, tuple[float, float]] | None = None,
                      solved: dict[str, float] | None = None,
                      turns: bool = False) -> list[Coordinate]:
    """The coordinates a start samples, with their boxes (see the module docstring).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    spread : float
        Half-width of an unbounded box relative to ``max(1, |default|)``.
    box : dict, optional
        Boxes by name, overriding the bounds.
    solved : dict, optional
        Durations a converged start found, by the name of the time coordinate
        (they replace the guessed durations as a scale of the free times).
    turns : bool
        Widen the unbounded sides of a periodic state's box (one that enters the
        dynamics only through periodic functions,
        :func:`~ocp.transcriptions.diagnosis.periodic_states`) to at least half a turn
        from its centre: the waypoints' box, where a heading may point anywhere. The
        structured starts keep the narrower box, whose widths weigh their terminal
        miss (a full turn there halved the pendulum's hits, measured).
    """
    box = box or {}
    solved = solved or {}
    pv = tr.param_vector(params)
    base = default_solution(tr, params)
    w0 = tr.default_guess(params)
    var_values = [float(w0[k]) for k in range(tr.iV.start, tr.iV.stop)]
    out: list[Coordinate] = []
    linked = {b for _, b in tr.multiphase.time_links}
    for i, (ps, cp, tm) in enumerate(zip(base.phases, tr.compiled, tr.times, strict=True)):
        pre = prefix(tr, i)
        _, _, xlo, xhi, ulo, uhi, _, _ = (np.array(v, dtype=float).ravel()
                                          for v in cp.bounds(pv))
        xm, _ = ps.at(np.array([0.5 * (ps.t0 + ps.T)]))
        turned = periodic_states(ps.problem) if turns else set()
        for j, name in enumerate(ps.problem.state_names):
            out.append(_coordinate(pre + name, xlo[j], xhi[j], xm[0, j], spread, box,
                                   math.pi if name in turned else 0.0))
        for j, name in enumerate(ps.problem.control_names):
            lo, hi = ulo[j], uhi[j]
            mid = 0.5 * (lo + hi) if np.isfinite(lo) and np.isfinite(hi) else 0.0
            out.append(_coordinate(pre + name, lo, hi, mid, spread, box))
        scales = [ps.T - ps.t0]  # the guessed duration, or what start 0 converged to
        for key in (pre + "T", pre + "duration"):
            if key in solved:
                scales = [solved[key]]
        if tm.T_free:
            scales += _transfer_times(ps, var_values)
        out.extend(_time_coordinates(pre, tm, i in linked, spread, box, scales))
    if tr.multiphase.var_names:
        lbw, ubw = decision_bounds(tr, params)
        for k, name in zip(range(tr.iV.start, tr.iV.stop), tr.multiphase.var_names,
                           strict=True):
            out.append(_coordinate(name, lbw[k], ubw[k], w0[k], spread, box))
    return out


def _transfer_times(ps: Solution, var_values: list[float]) -> list[float]:
    """The dynamics' time for the change the default guess asks (empty if none)."""
    x, u = np.asarray(ps.x, dtype=float), np.asarray(ps.u, dtype=float)  # at the nodes
    if x.shape[0] < 2 or not np.all(np.isfinite(x)) or not np.all(np.isfinite(u)):
        return []
    try:
        tau = transfer_time(ps.problem, x[0], x[-1], u[0] if u.size else np.zeros(0),
                            (ps.t0, ps.T), var_values, loose_bounds)
    except (RuntimeError, ArithmeticError):  # a rate CasADi cannot evaluate there
        return []
    return [tau] if tau is not None and math.isfinite(tau) and tau > 0 else []


def _coordinate(name: str, lo: float, hi: float, centre: float, spread: float,
                box: dict[str, tuple[float, float]], least: float = 0.0) -> Coordinate:
    """A coordinate's box: ``box``'s, else the bounds, an infinite side replaced by
    ``centre -+ max(spread * max(1, |centre|), least)``."""
    if name in box:
        a, b = (float(v) for v in box[name])
        return Coordinate(name, a, b)
    if not math.isfinite(centre):
        centre = 0.0
    half = max(spread * max(1.0, abs(centre)), least)
    a = lo if math.isfinite(lo) else min(centre, hi) - half
    b = hi if math.isfinite(hi) else max(centre, a) + half
    return Coordinate(name, float(a), float(b))


def _time_coordinates(pre: str, tm: PhaseTimes, linked: bool, spread: float,
                      box: dict[str, tuple[float, float]],
                      scales: list[float]) -> list[Coordinate]:
    """A phase's sampled times: ``t0`` (free and not linked to the previous phase's end),
    then ``T`` (free, fixed start) or ``duration`` (free, free start), in the box of the
    phase's known durations ``scales`` cut by the bounds (see the module docstring)."""
    out: list[Coordinate] = []
    if tm.t0_free and not linked:
        lo, hi = tm.t0_bounds
        out.append(_coordinate(pre + "t0", lo, hi, tm.t0_guess, spread, box))
    if not tm.T_free:
        return out
    if tm.t0_free:
        name, offset = pre + "duration", 0.0
        lo, hi = tm.span if tm.span is not None else (0.0, math.inf)
        lo = max(lo, 0.0)
    else:
        name, offset = pre + "T", tm.t0_bounds[0]
        lo, hi = tm.T_bounds
    if name in box:
        return out + [_coordinate(name, lo, hi, 0.0, spread, box)]
    known = [v for v in scales if math.isfinite(v) and v > 0]
    if not known:  # nothing known: the bounds, as for any other coordinate
        c = _coordinate(name, lo, hi, tm.T_guess - tm.t0_guess, spread, box)
    else:
        a = max(lo, offset + min(known) / TIME_SPAN)
        b = min(hi, offset + max(known) * TIME_SPAN)
        if not a < b:  # the scales lie outside the bounds: the bounds are what is known
            a, b = lo, hi if math.isfinite(hi) else lo + max(known) * TIME_SPAN
        c = Coordinate(name, float(a), float(b))
    if c.lo > 0 and c.hi > 10 * c.lo:
        c.log = True
    return out + [c]


def sampled_points(coords: list[Coordinate], count: int, method: str,
                   seed: int | np.random.Generator | None) -> list[dict[str, float]]:
    """``count`` points of a scrambled Sobol' sequence or a Latin hypercube in the box.

    Parameters
    ----------
    coords : list of Coordinate
        The coordinates and their boxes.
    count : int
        Number of points.
    method : {"sobol", "lhs"}
        The sampler.
    seed : int, numpy Generator or None
        Its seed.
    """
    if count <= 0:
        return []
    d = len(coords)
    sampler = qmc.Sobol(d, scramble=True, rng=seed) if method == "sobol" \
        else qmc.LatinHypercube(d, rng=seed)
    with warnings.catch_warnings():  # Sobol' balance wants powers of 2; any n is fine
        warnings.simplefilter("ignore", UserWarning)
        unit = sampler.random(count)
    return [{c.name: c.value(float(v)) for c, v in zip(coords, r, strict=True)} for r in unit]


def as_vector(tr: Transcription, params: dict[str, float], guess: Any) -> np.ndarray:
    """A user's guess (solution, trajectory or decision vector) as a decision vector.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    guess : Solution, Trajectory or array
        The guess.
    """
    if isinstance(guess, (Solution, Trajectory)):
        if isinstance(guess, Solution) and guess.transcription is tr:
            return np.asarray(guess.w, dtype=float).copy()
        return tr.guess_from(guess)
    w = np.asarray(guess, dtype=float).ravel()
    if w.shape != (tr.n_w,):
        raise ProblemDefinitionError(f"guess has {w.size} entries, the NLP {tr.n_w}")
    return w


def default_solution(tr: Transcription, params: dict[str, float]) -> Solution:
    """The default guess unpacked as a (not solved) solution, to sample it.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    """
    return unpacked(tr, params, tr.default_guess(params))


def unpacked(tr: Transcription, params: dict[str, float], w: np.ndarray) -> Solution:
    """A decision vector (a start) unpacked as a (not solved) solution, to read it.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    w : ndarray
        The decision vector.
    """
    res = {"x": w, "f": math.nan, "lam_g": np.zeros(tr.n_g), "lam_x": np.zeros(tr.n_w)}
    stats = {"success": False, "return_status": "Not_Solved", "iter_count": 0}
    return Solution.from_nlp(tr, tr.param_vector(params), res, stats, 0.0)


def phase_times(tr: Transcription, base: Solution, pt: dict[str, float]
                ) -> list[tuple[float, float]]:
    """Every phase's ``(t0, T)`` for a point: sampled, linked to the previous end, or guessed.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    base : Solution
        The default guess (:func:`default_solution`).
    pt : dict
        The point's coordinates by name (times absent are the default guess's).
    """
    links = {b: a for a, b in tr.multiphase.time_links}
    out: list[tuple[float, float]] = []
    for i, ps in enumerate(base.phases):
        pre = prefix(tr, i)
        t0 = out[links[i]][1] if i in links else pt.get(pre + "t0", ps.t0)
        T = t0 + pt[pre + "duration"] if pre + "duration" in pt else pt.get(pre + "T", ps.T)
        out.append((float(t0), float(T)))
    return out


def assemble(tr: Transcription, base: Solution, parts: list[PhasePart],
             pt: dict[str, float]) -> np.ndarray:
    """The decision vector of a start from its phases' trajectories (and ``pt``'s variables).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    base : Solution
        The default guess (its phases give the names).
    parts : list of PhasePart
        One trajectory per phase.
    pt : dict
        The start's coordinates: the decision variables are read from it.
    """
    multi = len(base.phases) > 1
    snames = sorted({n for ps in base.phases for n in ps.problem.state_names})
    cnames = sorted({n for ps in base.phases for n in ps.problem.control_names})
    x_all, u_all, ph_all = [], [], []
    for i, (ps, part) in enumerate(zip(base.phases, parts, strict=True)):
        k = part.t.size
        xcol = np.full((k, len(snames)), np.nan)
        ucol = np.full((k, len(cnames)), np.nan)
        for j, name in enumerate(ps.problem.state_names):
            xcol[:, snames.index(name)] = part.x[:, j]
        for j, name in enumerate(ps.problem.control_names):
            ucol[:, cnames.index(name)] = part.u[:, j]
        x_all.append(xcol)
        u_all.append(ucol)
        ph_all.append(np.full(k, i))
    traj = Trajectory(np.concatenate([p.t for p in parts]), np.vstack(x_all), np.vstack(u_all),
                      tuple(snames), tuple(cnames),
                      phase=np.concatenate(ph_all) if multi else None)
    w = tr.guess_from(traj)
    for k, name in zip(range(tr.iV.start, tr.iV.stop), tr.multiphase.var_names, strict=True):
        if name in pt:
            w[k] = pt[name]
    return w


def duration_box(tr: Transcription, i: int, by_name: dict[str, Coordinate],
                 t0: float) -> tuple[Coordinate | None, str]:
    """Phase ``i``'s free duration as a coordinate (an absolute ``T``'s box less ``t0``)
    and the name of the time coordinate it comes from; ``(None, "")`` if the time is fixed.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    i : int
        The phase.
    by_name : dict
        The coordinates by name.
    t0 : float
        The phase's (fixed) initial time, subtracted from an absolute ``T``.
    """
    pre = prefix(tr, i)
    for key in ("T", "duration"):
        if pre + key in by_name:
            c = by_name[pre + key]
            off = t0 if key == "T" else 0.0
            return Coordinate(c.name, max(c.lo - off, 1e-12), c.hi - off, c.log), c.name
    return None, ""
