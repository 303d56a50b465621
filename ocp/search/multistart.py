"""Multistart: the tool for problems with several extremals (local optima).

A nonlinear optimal control problem can have several local optima -- a
pendulum swung up in two, three or four swings, a path around an obstacle on
either side. Ipopt converges to the one whose basin holds the initial guess,
and a PMP certificate can only say that it is an extremal (a local statement),
not that it is the best. :func:`multistart` solves from ``n`` starts spread
over the box of the bounds and returns the best verified solution together
with every distinct local optimum found, its objective and how many starts
reached it::

    res = multistart(Collocation(p, intervals=60), n=16, seed=1)
    res.best.objective, [o.objective for o in res.optima], res.failures

Starts
------
Start 0 is the user's ``guess`` (or the default guess). The others are points
of a scrambled Sobol' sequence or a Latin hypercube (:mod:`scipy.stats.qmc`,
seeded: the same seed gives the same starts on the same transcription) in the box
of these coordinates:

* every free initial time not linked to the previous phase's end (``t0``),
  in its bounds;
* every free final time: ``T`` when the phase starts at a fixed time, its
  ``duration`` otherwise (a linked phase starts where the previous one ends).
  Its box is what the problem knows of the phase's time scale, not the bounds
  alone (``free_final_time()``'s default, [1e-3, 1e3], spans six decades, and
  starts spread over them rarely land near the optimum): the duration that
  start 0 converged to (else the guessed duration), and the time the dynamics
  need for the change the guess asks of the states (a state's boundary
  values apart by ``D``, its rate at the guess of size ``r``: ``D / r``; see
  :func:`ocp.definition.sizes.transfer_time`); the box runs from the smallest
  of these over :data:`TIME_SPAN` to the largest times :data:`TIME_SPAN`,
  cut by the bounds (a bound narrower than that is a real range and is kept).
  Sampled log-uniformly when the lower end is positive and the upper exceeds
  ten times it. Start 0 is therefore solved first, then the others;
* every state: its value at mid-phase. The start is the default guess plus
  ``sin(pi s) (z - x_default(1/2))`` (``s`` the normalised time), which keeps
  the guess's end values (fixed boundary values) and passes through the
  sampled ``z`` at mid-phase;
* every control: a constant;
* every decision variable.

A state's or control's box is its bounds; an infinite side is replaced by the
default guess's value ``-+ spread * max(1, |value|)`` (``spread = 1`` by
default), and ``box={"name": (lo, hi)}`` sets any coordinate's box by name
(``"T"``, ``"duration"``, ``"t0"`` for the times; in a multi-phase problem
every name is prefixed by its phase's, ``"phase.name"``); a name that is not a
coordinate, or a box that is not ``lo < hi`` in finite numbers, is refused.
:attr:`MultistartResult.boxes` reports the boxes sampled.

What a result means
-------------------
Every optimum multistart returns is *local*: Ipopt's convergence and a PMP
certificate are local statements. ``best`` is the best of the optima the
starts reached, not a proof of a global optimum; more starts (``n``), another
``seed`` or a box narrowed by what one knows (``box={"T": (2, 8)}``) search
further.

Solving on processes or Dask
----------------------------
A transcription holds CasADi and Ipopt objects that are not worth pickling;
to solve on other processes (``workers=k``, a
:class:`concurrent.futures.ProcessPoolExecutor`) or on a Dask cluster
(``client=``, a :class:`dask.distributed.Client`), pass instead of the
transcription a *builder*: a picklable zero-argument callable (a module-level
function) that returns it. Every worker builds it once and returns the raw
result; the solutions are reassembled (and checked between nodes) in the
calling process on its own build. Results do not depend on where starts ran.

Optima
------
Only converged and verified solutions (Ipopt success, path constraints
checked between nodes) count. Two are the same optimum when their objectives
agree to ``objective_rtol * max(1, |J|)`` and their states, compared on a
common normalised time grid relative to ``1 + max |x|``, to ``distance_tol``.
"""

from __future__ import annotations

import math
import multiprocessing
import numbers
import pickle
import time
import warnings
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.stats import qmc

from ..definition.errors import PathViolationWarning, ProblemDefinitionError, SolveError
from ..definition.multiphase import PhaseTimes
from ..definition.scaling import loose_bounds
from ..definition.sizes import transfer_time
from ..definition.symbols import positive_int
from ..definition.trajectory import Trajectory
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from ..transcriptions.transcription import decision_bounds
from ..transcriptions.verify import verify

__all__ = ["LocalOptimum", "MultistartResult", "StartResult", "multistart",
           "trajectory_distance"]

METHODS = ("sobol", "lhs")
MAX_STARTS = 100_000
"""The most starts one call takes (each is an NLP solve; the sampler holds them all)."""
TIME_SPAN = 4.0
"""A free time's box spans its known scales divided and multiplied by this (module doc)."""
Builder = Callable[[], Transcription]


@dataclass
class StartResult:
    """What became of one start.

    ``origin`` is ``"guess"`` (the user's guess), ``"default"`` (the default
    guess) or the sampling method; ``point`` the sampled coordinates by name;
    ``status`` Ipopt's return status (or the exception's name when the start
    could not be solved); ``optimum`` the index in
    :attr:`MultistartResult.optima` of the optimum it reached.

    Attributes
    ----------
    index : int
        The start's number.
    origin, point, status
        As above.
    success, verified : bool
        Ipopt converged; the solution passed the checks between nodes.
    objective : float
        Its objective (NaN when it failed).
    iterations, solve_time
        Ipopt's iterations and time.
    optimum : int or None
        Index of the optimum reached.
    message : str
        Why it failed, when it did.
    """

    index: int
    origin: str
    point: dict[str, float]
    status: str
    success: bool = False
    verified: bool = False
    objective: float = math.nan
    iterations: int = 0
    solve_time: float = 0.0
    optimum: int | None = None
    message: str = ""


@dataclass
class LocalOptimum:
    """One distinct local optimum: its objective, a solution, the starts that reached it.

    Attributes
    ----------
    objective : float
        Its objective.
    solution : Solution
        A solution that reached it.
    starts : list of int
        The starts that reached it.
    """

    objective: float
    solution: Solution
    starts: list[int] = field(default_factory=list)

    @property
    def count(self) -> int:
        """How many starts reached it."""
        return len(self.starts)


@dataclass
class MultistartResult:
    """The outcome of :func:`multistart` (scipy ``OptimizeResult``-like names).

    Attributes
    ----------
    optima : list of LocalOptimum
        The distinct verified local optima, best (lowest objective) first.
    starts : list of StartResult
        Every start, in order.
    method : str
        ``"sobol"`` or ``"lhs"``.
    seed : int or None
        The sampling seed.
    wall_time : float
        Seconds for the whole run.
    boxes : dict
        ``name -> (lo, hi, log)``: the box each coordinate was sampled in, and
        whether log-uniformly.
    """

    optima: list[LocalOptimum]
    starts: list[StartResult]
    method: str
    seed: int | np.random.Generator | None
    wall_time: float
    boxes: dict[str, tuple[float, float, bool]] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """Whether some start reached a verified optimum."""
        return bool(self.optima)

    @property
    def best(self) -> Solution:
        """The verified solution with the lowest objective.

        Raises
        ------
        SolveError
            If no start reached a verified optimum (see :attr:`failures`).
        """
        if not self.optima:
            raise SolveError("No_Verified_Optimum", None, self.message)
        return self.optima[0].solution

    @property
    def fun(self) -> float:
        """The best objective (scipy's name)."""
        return self.best.objective

    @property
    def failures(self) -> list[StartResult]:
        """The starts that did not reach a verified optimum, with their statuses."""
        return [s for s in self.starts if s.optimum is None]

    @property
    def message(self) -> str:
        """A one-line summary."""
        fails: dict[str, int] = {}
        for s in self.failures:
            fails[s.status] = fails.get(s.status, 0) + 1
        what = ", ".join(f"{k} x{v}" for k, v in sorted(fails.items())) or "none"
        if not self.optima:
            return f"no verified optimum from {len(self.starts)} starts (failures: {what})"
        objs = ", ".join(f"{o.objective:.10g} (x{o.count})" for o in self.optima)
        return (f"{len(self.optima)} distinct local optima from {len(self.starts)} starts: "
                f"{objs}; failures: {what}")

    def __repr__(self) -> str:
        return f"MultistartResult({self.message})"


@dataclass
class _Coordinate:
    """One sampled coordinate of a start."""

    name: str
    lo: float
    hi: float
    log: bool = False

    def value(self, r: float) -> float:
        if self.log:
            return float(math.exp(math.log(self.lo) + r * (math.log(self.hi) - math.log(self.lo))))
        return float(self.lo + r * (self.hi - self.lo))


def multistart(transcription: Transcription | Builder, n: int = 16, method: str = "sobol",
               seed: int | np.random.Generator | None = None, guess: Any = None,
               params: dict[str, float] | None = None, workers: int | None = None,
               client: Any = None, spread: float = 1.0,
               box: dict[str, tuple[float, float]] | None = None,
               objective_rtol: float = 1e-6, distance_tol: float = 1e-3) -> MultistartResult:
    """Solve from ``n`` starts spread over what the problem knows; keep the distinct local optima.

    Parameters
    ----------
    transcription : Transcription or callable
        The transcription to solve, or a picklable zero-argument callable
        returning it (needed with ``workers > 1`` or ``client``).
    n : int
        Number of starts, the user's (or the default) guess included; at most
        :data:`MAX_STARTS`.
    method : {"sobol", "lhs"}
        Scrambled Sobol' points or a Latin hypercube.
    seed : int or numpy.random.Generator, optional
        Seed of the sampling (the same seed gives the same starts).
    guess : Solution, Trajectory or decision vector, optional
        Start 0 (by default, the default guess).
    params : dict, optional
        Parameter values.
    workers : int, optional
        Solve on this many processes (default: in this process, one by one).
    client : dask.distributed.Client, optional
        Solve on this Dask cluster instead.
    spread : float
        Half-width of the box of an unbounded state or control, relative to
        ``max(1, |default guess|)`` (positive, finite).
    box : dict, optional
        Boxes ``(lo, hi)`` by coordinate name, overriding the bounds and scales.
    objective_rtol, distance_tol : float
        When two solutions are the same optimum (see the module docstring).

    Returns
    -------
    MultistartResult
        ``best`` (raises :class:`ocp.SolveError` if no start reached a
        verified optimum), ``optima`` best first, ``starts``, ``failures``,
        ``boxes``. Every optimum is local (see the module docstring).

    Raises
    ------
    ProblemDefinitionError
        An invalid argument, named in the message.
    """
    n, workers = _check_arguments(n, method, seed, workers, spread, objective_rtol,
                                  distance_tol)
    parallel = client is not None or (workers is not None and workers > 1)
    if isinstance(transcription, Transcription):
        if parallel:
            raise ProblemDefinitionError(
                "to solve on processes or Dask, pass a picklable zero-argument builder that "
                "returns the transcription (a transcription holds CasADi solvers)")
        tr, builder = transcription, None
    elif callable(transcription):
        if parallel:
            _check_picklable(transcription)
        tr, builder = transcription(), transcription
        if not isinstance(tr, Transcription):
            raise ProblemDefinitionError("the builder must return a transcription, got "
                                         f"{type(tr).__name__}")
    else:
        raise ProblemDefinitionError("transcription must be a Transcription or a builder")
    params = {} if params is None else dict(params)
    box = _check_box(box, [c.name for c in start_coordinates(tr, params, spread)])
    t_start = time.perf_counter()
    first = tr.default_guess(params) if guess is None else _as_vector(tr, params, guess)
    with _Runner(tr, builder, params, client, workers if parallel else None) as run:
        raw = run([first])
        sol0 = raw[0] if isinstance(raw[0], Solution) else _reassemble(tr, params, raw[0])
        scales = _solved_times(tr, sol0) if sol0 is not None and sol0.success else {}
        coords = start_coordinates(tr, params, spread, box, scales)
        origins, points, guesses = _starts(tr, params, coords, n, method, seed, guess)
        raw += run(guesses[1:])
    starts, sols = [], []
    for i, (orig, pt, r) in enumerate(zip(origins, points, raw, strict=True)):
        sol = sol0 if i == 0 else r if isinstance(r, Solution) else _reassemble(tr, params, r)
        rec = _record(i, orig, pt, sol, r)
        starts.append(rec)
        sols.append(sol if rec.verified else None)
    optima = _cluster(starts, sols, objective_rtol, distance_tol)
    boxes = {c.name: (c.lo, c.hi, c.log) for c in coords}
    return MultistartResult(optima, starts, method, seed, time.perf_counter() - t_start, boxes)


class _Runner:
    """Solves lists of starts here, on a process pool (kept for the whole run) or on Dask."""

    def __init__(self, tr: Transcription, builder: Builder | None, params: dict[str, float],
                 client: Any, workers: int | None) -> None:
        self.tr, self.builder, self.params = tr, builder, params
        self.client, self.workers = client, workers
        self.pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> _Runner:
        if self.client is None and self.workers is not None:
            # spawn, not fork: forking a process with Ipopt's and BLAS's threads can deadlock
            self.pool = ProcessPoolExecutor(max_workers=self.workers,
                                            mp_context=multiprocessing.get_context("spawn"))
        return self

    def __exit__(self, *exc: object) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)

    def __call__(self, guesses: list[np.ndarray]) -> list[Any]:
        if not guesses:
            return []
        if self.client is not None:
            return self.client.gather([self.client.submit(solve_start, self.builder,
                                                          self.params, g, pure=False)
                                       for g in guesses])
        if self.pool is not None:
            k = len(guesses)
            return list(self.pool.map(solve_start, [self.builder] * k, [self.params] * k,
                                      guesses))
        return [_solve_here(self.tr, self.params, g) for g in guesses]


def _check_arguments(n: Any, method: Any, seed: Any, workers: Any, spread: Any,
                     objective_rtol: Any, distance_tol: Any) -> tuple[int, int | None]:
    """``n`` and ``workers`` checked; every other argument checked (a clear error naming it)."""
    if method not in METHODS:
        raise ProblemDefinitionError(f"method must be one of {METHODS}, got {method!r}")
    n = positive_int(n, "multistart(n)")
    if n > MAX_STARTS:
        raise ProblemDefinitionError(f"multistart(n) must be at most {MAX_STARTS}, got {n}")
    if workers is not None:
        workers = positive_int(workers, "multistart(workers)")
    if seed is not None and not isinstance(seed, np.random.Generator) and (
            isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0):
        raise ProblemDefinitionError("multistart(seed) must be a non-negative integer, a "
                                     f"numpy Generator or None, got {seed!r}")
    for name, v in (("spread", spread), ("objective_rtol", objective_rtol),
                    ("distance_tol", distance_tol)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) \
                or v <= 0:
            raise ProblemDefinitionError(f"multistart({name}) must be a positive finite "
                                         f"number, got {v!r}")
    return n, workers


def _check_picklable(builder: Builder) -> None:
    """A builder for other processes must pickle (a lambda or a local function does not)."""
    try:
        pickle.dumps(builder)
    except (pickle.PicklingError, AttributeError, TypeError) as err:
        raise ProblemDefinitionError(
            "multistart(transcription): with workers or a Dask client the builder must be "
            f"picklable (a module-level function, not a lambda or a local function): {err}"
        ) from None


def _check_box(box: Any, names: list[str]) -> dict[str, tuple[float, float]]:
    """``box`` checked against the coordinates' names: known names, finite ``lo < hi``."""
    if box is None:
        return {}
    if not isinstance(box, dict):
        raise ProblemDefinitionError(f"multistart(box) must be a dict, got {type(box).__name__}")
    out: dict[str, tuple[float, float]] = {}
    for key, val in box.items():
        if key not in names:
            raise ProblemDefinitionError(f"multistart(box): {key!r} is not a sampled coordinate "
                                         f"(they are {names})")
        try:
            lo, hi = (float(v) for v in val)
        except (TypeError, ValueError):
            raise ProblemDefinitionError(f"multistart(box[{key!r}]) must be a pair (lo, hi) "
                                         f"of numbers, got {val!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ProblemDefinitionError(f"multistart(box[{key!r}]) needs finite lo < hi, "
                                         f"got ({lo!r}, {hi!r})")
        out[key] = (lo, hi)
    return out


def _solved_times(tr: Transcription, sol: Solution) -> dict[str, float]:
    """The durations of a converged solution's phases, by the name of their time coordinate."""
    multi = len(tr.phases) > 1
    out = {}
    for ps in sol.phases:
        pre = f"{ps.problem.name}." if multi else ""
        out[pre + "T"] = out[pre + "duration"] = float(ps.T - ps.t0)
    return out


# ---------------------------------------------------------------------- the starts
def start_coordinates(tr: Transcription, params: dict[str, float], spread: float = 1.0,
                      box: dict[str, tuple[float, float]] | None = None,
                      solved: dict[str, float] | None = None) -> list[_Coordinate]:
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
    """
    box = box or {}
    solved = solved or {}
    pv = tr.param_vector(params)
    base = _default_solution(tr, params)
    w0 = tr.default_guess(params)
    var_values = [float(w0[k]) for k in range(tr.iV.start, tr.iV.stop)]
    multi = len(tr.phases) > 1
    out: list[_Coordinate] = []
    linked = {b for _, b in tr.multiphase.time_links}
    for i, (ps, cp, tm) in enumerate(zip(base.phases, tr.compiled, tr.times, strict=True)):
        pre = f"{ps.problem.name}." if multi else ""
        _, _, xlo, xhi, ulo, uhi, _, _ = (np.array(v, dtype=float).ravel()
                                          for v in cp.bounds(pv))
        xm, _ = ps.at(np.array([0.5 * (ps.t0 + ps.T)]))
        for j, name in enumerate(ps.problem.state_names):
            out.append(_coordinate(pre + name, xlo[j], xhi[j], xm[0, j], spread, box))
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
                box: dict[str, tuple[float, float]]) -> _Coordinate:
    if name in box:
        a, b = (float(v) for v in box[name])
        return _Coordinate(name, a, b)
    if not math.isfinite(centre):
        centre = 0.0
    half = spread * max(1.0, abs(centre))
    a = lo if math.isfinite(lo) else min(centre, hi) - half
    b = hi if math.isfinite(hi) else max(centre, a) + half
    return _Coordinate(name, float(a), float(b))


def _time_coordinates(pre: str, tm: PhaseTimes, linked: bool, spread: float,
                      box: dict[str, tuple[float, float]],
                      scales: list[float]) -> list[_Coordinate]:
    """A phase's sampled times: ``t0`` (free and not linked to the previous phase's end),
    then ``T`` (free, fixed start) or ``duration`` (free, free start), in the box of the
    phase's known durations ``scales`` cut by the bounds (see the module docstring)."""
    out: list[_Coordinate] = []
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
        c = _Coordinate(name, float(a), float(b))
    if c.lo > 0 and c.hi > 10 * c.lo:
        c.log = True
    return out + [c]


def _starts(tr: Transcription, params: dict[str, float], coords: list[_Coordinate], n: int,
            method: str, seed: int | np.random.Generator | None, guess: Any
            ) -> tuple[list[str], list[dict[str, float]], list[np.ndarray]]:
    """Origins, sampled points and decision vectors of the ``n`` starts."""
    first = tr.default_guess(params) if guess is None else _as_vector(tr, params, guess)
    origins = ["default" if guess is None else "guess"]
    points: list[dict[str, float]] = [{}]
    vectors = [first]
    if n > 1:
        d = len(coords)
        sampler = qmc.Sobol(d, scramble=True, rng=seed) if method == "sobol" \
            else qmc.LatinHypercube(d, rng=seed)
        with warnings.catch_warnings():  # Sobol' balance wants powers of 2; any n is fine
            warnings.simplefilter("ignore", UserWarning)
            unit = sampler.random(n - 1)
        base = _default_solution(tr, params)
        for r in unit:
            pt = {c.name: c.value(float(v)) for c, v in zip(coords, r, strict=True)}
            origins.append(method)
            points.append(pt)
            vectors.append(_guess_vector(tr, params, base, pt))
    return origins, points, vectors


def _as_vector(tr: Transcription, params: dict[str, float], guess: Any) -> np.ndarray:
    if isinstance(guess, (Solution, Trajectory)):
        if isinstance(guess, Solution) and guess.transcription is tr:
            return np.asarray(guess.w, dtype=float).copy()
        return tr.guess_from(guess)
    w = np.asarray(guess, dtype=float).ravel()
    if w.shape != (tr.n_w,):
        raise ProblemDefinitionError(f"guess has {w.size} entries, the NLP {tr.n_w}")
    return w


def _default_solution(tr: Transcription, params: dict[str, float]) -> Solution:
    """The default guess unpacked as a (not solved) solution, to sample it."""
    w0 = tr.default_guess(params)
    res = {"x": w0, "f": math.nan, "lam_g": np.zeros(tr.n_g), "lam_x": np.zeros(tr.n_w)}
    stats = {"success": False, "return_status": "Not_Solved", "iter_count": 0}
    return Solution.from_nlp(tr, tr.param_vector(params), res, stats, 0.0)


def _guess_vector(tr: Transcription, params: dict[str, float], base: Solution,
                  pt: dict[str, float], samples: int = 201) -> np.ndarray:
    """The decision vector of one start: the default guess bent through the sampled point."""
    multi = len(base.phases) > 1
    s = np.linspace(0.0, 1.0, samples)
    bump = np.sin(np.pi * s)[:, None]
    t_all, x_all, u_all, ph_all = [], [], [], []
    snames = sorted({n for ps in base.phases for n in ps.problem.state_names})
    cnames = sorted({n for ps in base.phases for n in ps.problem.control_names})
    links = dict((b, a) for a, b in tr.multiphase.time_links)
    ends: list[float] = []
    for i, ps in enumerate(base.phases):
        pre = f"{ps.problem.name}." if multi else ""
        t0 = ends[links[i]] if i in links else pt.get(pre + "t0", ps.t0)
        T = t0 + pt[pre + "duration"] if pre + "duration" in pt else pt.get(pre + "T", ps.T)
        ends.append(T)
        x_def, _ = ps.at(ps.t0 + (ps.T - ps.t0) * s)
        x_mid, _ = ps.at(np.array([0.5 * (ps.t0 + ps.T)]))
        z = np.array([pt[pre + n] for n in ps.problem.state_names])
        x = x_def + bump * (z - x_mid[0])[None, :]
        u = np.array([pt[pre + n] for n in ps.problem.control_names])
        xcol = np.full((samples, len(snames)), np.nan)
        ucol = np.full((samples, len(cnames)), np.nan)
        for j, name in enumerate(ps.problem.state_names):
            xcol[:, snames.index(name)] = x[:, j]
        for j, name in enumerate(ps.problem.control_names):
            ucol[:, cnames.index(name)] = u[j]
        t_all.append(t0 + (T - t0) * s)
        x_all.append(xcol)
        u_all.append(ucol)
        ph_all.append(np.full(samples, i))
    traj = Trajectory(np.concatenate(t_all), np.vstack(x_all), np.vstack(u_all),
                      tuple(snames), tuple(cnames),
                      phase=np.concatenate(ph_all) if multi else None)
    w = tr.guess_from(traj)
    for k, name in zip(range(tr.iV.start, tr.iV.stop), tr.multiphase.var_names, strict=True):
        w[k] = pt[name]
    return w


# ---------------------------------------------------------------------- solving
_BUILT: dict[Any, Transcription] = {}


def solve_start(builder: Builder, params: dict[str, float], w0: np.ndarray) -> dict[str, Any]:
    """Solve one start in a worker process: build (once per process), solve, return raw arrays.

    Parameters
    ----------
    builder : callable
        Zero-argument callable returning the transcription.
    params : dict
        Parameter values.
    w0 : ndarray
        The start's decision vector.
    """
    try:
        tr = _BUILT[builder]
    except (KeyError, TypeError):
        tr = builder()
        try:
            _BUILT[builder] = tr
        except TypeError:  # an unhashable builder is built for every start
            pass
    out = _solve_here(tr, params, w0)
    if isinstance(out, dict):
        return out
    return {"w": out.w, "f": out.objective, "lam_g": out.lam_g, "lam_x": out.lam_x,
            "success": out.success, "status": out.status, "iterations": out.iterations,
            "solve_time": out.solve_time, "message": "",
            "mesh_error": getattr(out, "mesh_error", None)}


def _solve_here(tr: Transcription, params: dict[str, float], w0: np.ndarray
                ) -> Solution | dict[str, Any]:
    """A converged solution, or a dict saying why there is none."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PathViolationWarning)
            return tr.solve(params, guess=w0)
    except SolveError as e:  # includes an infeasible start and a path violation ("raise")
        it = e.iterate if isinstance(e.iterate, Solution) else None
        return {"status": e.status, "message": str(e), "success": False,
                "iterations": it.iterations if it is not None else 0,
                "solve_time": it.solve_time if it is not None else 0.0}
    except ProblemDefinitionError as e:  # a start that makes the dynamics non-finite
        return {"status": type(e).__name__, "message": str(e), "success": False,
                "iterations": 0, "solve_time": 0.0}
    except (RuntimeError, ArithmeticError) as e:  # CasADi's evaluation errors and the like:
        # one bad start is a failed start, not the end of the run
        return {"status": type(e).__name__, "message": (str(e).splitlines() or [""])[0][:200],
                "success": False, "iterations": 0, "solve_time": 0.0}


def _reassemble(tr: Transcription, params: dict[str, float],
                raw: dict[str, Any]) -> Solution | None:
    """The solution of a worker's raw result, on this process's build (checked between nodes)."""
    if not raw.get("success") or "w" not in raw:
        return None
    if np.size(raw["w"]) != tr.n_w:
        raise ProblemDefinitionError(
            f"a worker's build has {np.size(raw['w'])} decision variables, this process's "
            f"{tr.n_w}: the builder must return the same transcription every time")
    res = {k: raw[k] for k in ("f", "lam_g", "lam_x")}
    res["x"] = raw["w"]
    stats = {"success": raw["success"], "return_status": raw["status"],
             "iter_count": raw["iterations"]}
    sol = Solution.from_nlp(tr, tr.param_vector(params), res, stats, raw["solve_time"])
    if raw.get("mesh_error") is not None:
        sol.mesh_error = raw["mesh_error"]
    return sol


def _record(i: int, origin: str, point: dict[str, float], sol: Solution | None,
            raw: Any) -> StartResult:
    if sol is None:
        return StartResult(i, origin, point, raw["status"], False, False, math.nan,
                           raw.get("iterations", 0), raw.get("solve_time", 0.0),
                           message=raw.get("message", ""))
    if sol.verified is None:  # not yet checked between nodes (verify="off", or a worker's)
        tr = sol.transcription
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PathViolationWarning)
            verify(sol, "warn", tr.verify_tol, tr.verify_points)
    ok = bool(sol.success and sol.verified)
    return StartResult(i, origin, point, sol.status, sol.success, ok, sol.objective,
                       sol.iterations, sol.solve_time,
                       message="" if ok else "violates a path constraint between nodes")


# ---------------------------------------------------------------------- distinct optima
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


def _cluster(starts: list[StartResult], sols: list[Solution | None], objective_rtol: float,
             distance_tol: float) -> list[LocalOptimum]:
    """Group the verified solutions into distinct optima (lowest objective first)."""
    order = sorted((i for i, s in enumerate(sols) if s is not None),
                   key=lambda i: (starts[i].objective, i))
    optima: list[LocalOptimum] = []
    for i in order:
        sol = sols[i]
        assert sol is not None
        for opt in optima:
            close = abs(sol.objective - opt.objective) <= objective_rtol * max(
                1.0, abs(opt.objective))
            if close and trajectory_distance(sol, opt.solution) <= distance_tol:
                opt.starts.append(i)
                break
        else:
            optima.append(LocalOptimum(sol.objective, sol, [i]))
    for k, opt in enumerate(optima):
        for i in opt.starts:
            starts[i].optimum = k
    return optima
