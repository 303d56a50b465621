"""Multistart: the tool for problems with several extremals (local optima).

A nonlinear optimal control problem can have several local optima -- a
pendulum swung up in two, three or four swings, a path around an obstacle on
either side. Ipopt converges to the one whose basin holds the initial guess,
and a PMP certificate can only say that it is an extremal (a local statement),
not that it is the best. :func:`multistart` solves from up to ``n`` starts spent
where optima differ and returns the best verified solution together with every
distinct local optimum found, its objective and the fraction of the starts
that reached it::

    res = multistart(Collocation(p, intervals=60), n=16, seed=1)
    res.best.objective, [(o.objective, o.fraction) for o in res.optima], res.stopped

Starts
------
Start 0 is the user's ``guess`` (or the default guess); it is solved first
(its converged duration informs the time box). The others are of two kinds:

* *structured starts* (:mod:`ocp.search.structured`, origin ``"bang"``): every
  control piecewise constant at the ends of its box with 0, 1 or 2 switches at
  random times, the states simulated forward from the initial state, a free
  final time where the simulation comes closest to the fixed terminal values;
* *waypoint starts* (:mod:`ocp.search.waypoints`, origin ``"sobol"`` or
  ``"lhs"``): the default guess bent through a scrambled Sobol' point (or a
  Latin hypercube point) of the states' box at mid-phase, with the controls and
  the free time that fit the dynamics along the path (seeded: the same seed
  gives the same starts).

The first round deals the kinds by the share ``structured`` (alternating at the
default 1/2); later rounds give each start to the kind whose starts reached the
best objective so far, by Thompson sampling (:mod:`ocp.search.allocation`;
``adapt=False`` keeps the share). A failed start costs its solve alone: only
start 0 retries a failed scaled solve as posed (``fallback``), and the analysis
of a failed start's last iterate runs when its ``diagnosis`` is read
(:mod:`ocp.search.runner`).

``res.boxes`` reports the waypoints' boxes (a periodic state's spans a turn);
``box={"name": (lo, hi)}`` sets one (it bounds the structured starts' control
levels and time search too).

Stopping early
--------------
With ``stop=(k, m)`` (default :data:`STOP`) the run ends once the best
objective has been reached by ``k`` starts and the last ``m`` starts found no
new objective (:class:`ocp.search.optima.StopRule`); ``res.stopped`` says so
and why (empty when every start ran). ``stop=None`` runs all ``n``.

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
calling process on its own build. Results are taken in the order of the
starts (and the stopping rule applied in that order), so they do not depend
on where starts ran; starts queued past a stop are cancelled.

Optima
------
Only converged and verified solutions (Ipopt success, path constraints
checked between nodes) count. Two are the same optimum when their objectives
agree to ``objective_rtol * max(1, |J|)`` and their states, compared on a
common normalised time grid relative to ``1 + max |x|``, to ``distance_tol``
(:mod:`ocp.search.optima`).
"""

from __future__ import annotations

import math
import numbers
import pickle
import time
from collections.abc import Callable
from contextlib import closing
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..definition.errors import ProblemDefinitionError, SolveError
from ..definition.symbols import positive_int
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from .allocation import BANG, ROUND, Allocation
from .optima import LocalOptimum, Optima, StopRule, trajectory_distance
from .runner import FALLBACKS, Runner, StartResult, record, retries, solution_of
from .starts import (
    TIME_SPAN,
    Coordinate,
    as_vector,
    default_solution,
    start_coordinates,
)
from .structured import StructuredStarts
from .waypoints import WaypointStarts

__all__ = ["STOP", "STRUCTURED", "TIME_SPAN", "LocalOptimum", "MultistartResult",
           "StartResult", "multistart", "start_coordinates", "trajectory_distance"]

METHODS = ("sobol", "lhs")
MAX_STARTS = 100_000
"""The most starts one call takes (each is an NLP solve; the sampler holds them all)."""
STRUCTURED = 0.5
"""Default share of structured starts (bang sequences) in the first round (the rest are
waypoint starts); later rounds follow the kinds' yields (:mod:`ocp.search.allocation`)."""
STOP = (4, 6)
"""Default stopping rule ``(k, m)``: the best objective reached by k starts, none new in m."""
Builder = Callable[[], Transcription]


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
        ``name -> (lo, hi, log)``: the box each coordinate of the waypoint starts was
        sampled in, and whether log-uniformly.
    requested : int
        The ``n`` asked for.
    stopped : str
        Why the run stopped before ``requested`` starts ("" if every start ran).
    """

    optima: list[LocalOptimum]
    starts: list[StartResult]
    method: str
    seed: int | np.random.Generator | None
    wall_time: float
    boxes: dict[str, tuple[float, float, bool]] = field(default_factory=dict)
    requested: int = 0
    stopped: str = ""

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
        for s in self.failures:  # (a converged start that is not verified says so)
            key = s.status if not s.success else f"{s.status} but not verified"
            fails[key] = fails.get(key, 0) + 1
        what = ", ".join(f"{k} x{v}" for k, v in sorted(fails.items())) or "none"
        if not self.optima:
            return f"no verified optimum from {len(self.starts)} starts (failures: {what})"
        objs = ", ".join(f"{o.objective:.10g} (x{o.count}, {o.fraction:.0%})"
                         for o in self.optima)
        tail = f"; {self.stopped}" if self.stopped else ""
        return (f"{len(self.optima)} distinct local optima from {len(self.starts)} starts: "
                f"{objs}; failures: {what}{tail}")

    def __repr__(self) -> str:
        return f"MultistartResult({self.message})"


def multistart(transcription: Transcription | Builder, n: int = 16, method: str = "sobol",
               seed: int | np.random.Generator | None = None, guess: Any = None,
               params: dict[str, float] | None = None, workers: int | None = None,
               client: Any = None, spread: float = 1.0,
               box: dict[str, tuple[float, float]] | None = None,
               objective_rtol: float = 1e-6, distance_tol: float = 1e-3,
               structured: float = STRUCTURED, stop: tuple[int, int] | None = STOP,
               adapt: bool = True, fallback: str = "first") -> MultistartResult:
    """Solve from up to ``n`` starts spent where optima differ; keep the distinct local optima.

    Parameters
    ----------
    transcription : Transcription or callable
        The transcription to solve, or a picklable zero-argument callable
        returning it (needed with ``workers > 1`` or ``client``).
    n : int
        Number of starts, the user's (or the default) guess included; at most
        :data:`MAX_STARTS`.
    method : {"sobol", "lhs"}
        The waypoints: scrambled Sobol' points or a Latin hypercube.
    seed : int or numpy.random.Generator, optional
        Seed of the waypoints, of the structured starts' switch times and of the
        kinds' draws (the same seed gives the same starts).
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
    structured : float
        Share of structured starts (bang sequences simulated) in the first round,
        in [0, 1]; the others are waypoint starts. 0 or 1 gives one kind alone.
    stop : (int, int) or None
        Stop once the best objective has been reached by ``k`` starts and the
        last ``m`` starts found no new objective
        (:class:`~ocp.search.optima.StopRule`); None runs all ``n``.
    adapt : bool
        Deal the later rounds' starts to the kinds by their yields (default); False
        keeps the share ``structured`` throughout.
    fallback : {"first", "all", "none"}
        Which starts retry a failed scaled solve on the NLP as posed (the
        transcription's scaling fallback, where it has it on): start 0 alone
        (default: what a solve from the guess gives), every start, or none.

    Returns
    -------
    MultistartResult
        ``best`` (raises :class:`ocp.SolveError` if no start reached a
        verified optimum), ``optima`` best first with the fraction of starts
        that reached each, ``starts``, ``failures``, ``boxes``, ``stopped``.
        Every optimum is local (see the module docstring).

    Raises
    ------
    ProblemDefinitionError
        An invalid argument, named in the message.
    """
    n, workers = _check_arguments(n, method, seed, workers, spread, objective_rtol,
                                  distance_tol)
    rule = _check_strategy(structured, stop, adapt, fallback)
    parallel = client is not None or (workers is not None and workers > 1)
    tr, builder = _transcription_of(transcription, parallel)
    params = {} if params is None else dict(params)
    box = _check_box(box, [c.name for c in start_coordinates(tr, params, spread)])
    t_start = time.perf_counter()
    first = tr.default_guess(params) if guess is None else as_vector(tr, params, guess)
    optima = Optima(objective_rtol, distance_tol)
    with Runner(tr, builder, params, client, workers if parallel else None) as run:
        raw0 = next(run.each([(first, retries(fallback, 0))]))
        sol0 = solution_of(tr, params, raw0)
        rec = record(tr, params, 0, "default" if guess is None else "guess", {}, sol0, raw0)
        optima.add(0, sol0 if rec.verified else None)
        scales = _solved_times(tr, sol0) if sol0 is not None and sol0.success else {}
        coords = start_coordinates(tr, params, spread, box, scales)
        way = start_coordinates(tr, params, spread, box, scales, turns=True)
        plan = _Plan(tr, params, (coords, way), n, method, seed, structured, adapt, optima)
        size = max(ROUND, _capacity(workers if parallel else None, client))
        starts, stopped = [rec], ""
        while len(starts) < n and not stopped:
            made = plan.next_round(min(size, n - len(starts)), starts)
            jobs = [(w, retries(fallback, len(starts) + k)) for k, (_, _, w) in enumerate(made)]
            with closing(run.each(jobs)) as results:  # closed at a stop: the rest cancelled
                for (origin, pt, _), raw in zip(made, results, strict=False):
                    i = len(starts)
                    sol = solution_of(tr, params, raw)
                    rec = record(tr, params, i, origin, pt, sol, raw)
                    optima.add(i, sol if rec.verified else None)
                    starts.append(rec)
                    stopped = rule.reason(optima, i) if rule is not None and i < n - 1 else ""
                    if stopped:
                        break
    ranked = optima.ranked()
    for k, opt in enumerate(ranked):  # the optima's ranks, best first
        for i in opt.starts:
            starts[i].optimum = k
    boxes = {c.name: (c.lo, c.hi, c.log) for c in way}
    return MultistartResult(ranked, starts, method, seed, time.perf_counter() - t_start, boxes,
                            n, stopped)


class _Plan:
    """The starts after start 0: their kinds dealt by :class:`~.allocation.Allocation`, each
    kind made on demand from its own seeded stream (so the same seed gives the same starts
    whatever the other kind drew)."""

    def __init__(self, tr: Transcription, params: dict[str, float],
                 coords: tuple[list[Coordinate], list[Coordinate]],
                 n: int, method: str, seed: int | np.random.Generator | None,
                 structured: float, adapt: bool, optima: Optima) -> None:
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        way_rng, self.bang_rng, deal_rng = rng.spawn(3)
        base = default_solution(tr, params)
        self.method = method
        self.bang = StructuredStarts(tr, params, coords[0], base) if structured > 0 else None
        self.way = WaypointStarts(tr, params, coords[1], base, method, way_rng, n) \
            if structured < 1 else None
        self.deal = Allocation(structured, adapt, deal_rng, optima.same)
        self.made = {BANG: 0, "waypoint": 0}

    def next_round(self, size: int, starts: list[StartResult]
                   ) -> list[tuple[str, dict[str, float], np.ndarray]]:
        """The next ``size`` starts: ``(origin, point, decision vector)``."""
        results = [(_kind(s.origin), s.objective if s.verified else math.nan) for s in starts]
        out = []
        for kind in self.deal.next_round(size, results):
            number = self.made[kind]
            self.made[kind] += 1
            if kind == BANG:
                assert self.bang is not None
                pt, w = self.bang.make(number, self.bang_rng)
                out.append((BANG, pt, w))
            else:
                assert self.way is not None
                pt, w = self.way.make(number)
                out.append((self.method, pt, w))
        return out


def _kind(origin: str) -> str:
    """The kind of a start's origin ("" for start 0)."""
    return BANG if origin == BANG else "" if origin in ("default", "guess") else "waypoint"


def _capacity(workers: int | None, client: Any) -> int:
    """How many starts run at once: the pool's processes or the Dask cluster's threads."""
    if client is not None:
        try:
            return max(1, int(sum(client.nthreads().values())))
        except (AttributeError, TypeError, ValueError):
            return 1
    return workers or 1


def _transcription_of(transcription: Any, parallel: bool) -> tuple[Transcription,
                                                                     Builder | None]:
    """The transcription (built once here) and the builder the workers use."""
    if isinstance(transcription, Transcription):
        if parallel:
            raise ProblemDefinitionError(
                "to solve on processes or Dask, pass a picklable zero-argument builder that "
                "returns the transcription (a transcription holds CasADi solvers)")
        return transcription, None
    if not callable(transcription):
        raise ProblemDefinitionError("transcription must be a Transcription or a builder")
    if parallel:
        _check_picklable(transcription)
    tr = transcription()
    if not isinstance(tr, Transcription):
        raise ProblemDefinitionError("the builder must return a transcription, got "
                                     f"{type(tr).__name__}")
    return tr, transcription


def _check_strategy(structured: Any, stop: Any, adapt: Any, fallback: Any) -> StopRule | None:
    """``structured`` in [0, 1], ``adapt`` a bool, ``fallback`` one of :data:`FALLBACKS`
    and ``stop`` a pair of positive integers (or None)."""
    if isinstance(structured, bool) or not isinstance(structured, numbers.Real) \
            or not 0.0 <= float(structured) <= 1.0:
        raise ProblemDefinitionError("multistart(structured) must be a fraction in [0, 1], "
                                     f"got {structured!r}")
    if not isinstance(adapt, bool):
        raise ProblemDefinitionError(f"multistart(adapt) must be True or False, got {adapt!r}")
    if fallback not in FALLBACKS:
        raise ProblemDefinitionError(f"multistart(fallback) must be one of {FALLBACKS}, got "
                                     f"{fallback!r}")
    if stop is None:
        return None
    try:
        k, m = stop
    except (TypeError, ValueError):
        raise ProblemDefinitionError("multistart(stop) must be a pair (k, m) of positive "
                                     f"integers or None, got {stop!r}") from None
    return StopRule(positive_int(k, "multistart(stop[0])"),
                    positive_int(m, "multistart(stop[1])"))


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
