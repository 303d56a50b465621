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
seeded: the same seed gives the same starts) in the box of these coordinates:

* every free initial time not linked to the previous phase's end (``t0``),
  and every free final time: ``T`` when the phase starts at a fixed time,
  its ``duration`` otherwise (a linked phase starts where the previous one
  ends). Box: the bounds (for a duration, the duration bounds); sampled
  log-uniformly when the lower bound is positive and the upper exceeds ten
  times it (a box [0.01, 100] would otherwise put nearly every start above
  10);
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
every name is prefixed by its phase's, ``"phase.name"``).

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
from ..definition.trajectory import Trajectory
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from ..transcriptions.transcription import decision_bounds
from ..transcriptions.verify import verify

__all__ = ["LocalOptimum", "MultistartResult", "StartResult", "multistart",
           "trajectory_distance"]

METHODS = ("sobol", "lhs")
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
    """

    optima: list[LocalOptimum]
    starts: list[StartResult]
    method: str
    seed: int | None
    wall_time: float

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
        return (f"{len(self.optima)} distinct optima from {len(self.starts)} starts: {objs}; "
                f"failures: {what}")

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
               seed: int | None = None, guess: Any = None,
               params: dict[str, float] | None = None, workers: int | None = None,
               client: Any = None, spread: float = 1.0,
               box: dict[str, tuple[float, float]] | None = None,
               objective_rtol: float = 1e-6, distance_tol: float = 1e-3) -> MultistartResult:
    """Solve from ``n`` starts spread over the bounds' box; keep the distinct local optima.

    Parameters
    ----------
    transcription : Transcription or callable
        The transcription to solve, or a picklable zero-argument callable
        returning it (needed with ``workers > 1`` or ``client``).
    n : int
        Number of starts, the user's (or the default) guess included.
    method : {"sobol", "lhs"}
        Scrambled Sobol' points or a Latin hypercube.
    seed : int, optional
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
        ``max(1, |default guess|)``.
    box : dict, optional
        Boxes ``(lo, hi)`` by coordinate name, overriding the bounds.
    objective_rtol, distance_tol : float
        When two solutions are the same optimum (see the module docstring).

    Returns
    -------
    MultistartResult
        ``best`` (raises :class:`ocp.SolveError` if no start reached a
        verified optimum), ``optima`` best first, ``starts``, ``failures``.
    """
    if method not in METHODS:
        raise ProblemDefinitionError(f"method must be one of {METHODS}, got {method!r}")
    if int(n) < 1:
        raise ProblemDefinitionError(f"n must be a positive integer, got {n!r}")
    parallel = client is not None or (workers is not None and int(workers) > 1)
    if isinstance(transcription, Transcription):
        if parallel:
            raise ProblemDefinitionError(
                "to solve on processes or Dask, pass a picklable zero-argument builder that "
                "returns the transcription (a transcription holds CasADi solvers)")
        tr, builder = transcription, None
    elif callable(transcription):
        tr, builder = transcription(), transcription
        if not isinstance(tr, Transcription):
            raise ProblemDefinitionError("the builder must return a transcription, got "
                                         f"{type(tr).__name__}")
    else:
        raise ProblemDefinitionError("transcription must be a Transcription or a builder")
    params = {} if params is None else dict(params)
    t_start = time.perf_counter()
    coords = start_coordinates(tr, params, spread, box or {})
    origins, points, guesses = _starts(tr, params, coords, int(n), method, seed, guess)
    if client is not None:
        raw = client.gather([client.submit(solve_start, builder, params, g, pure=False)
                             for g in guesses])
    elif parallel:
        # spawn, not fork: forking a process with Ipopt's and BLAS's threads can deadlock
        with ProcessPoolExecutor(max_workers=int(workers or 1),
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            raw = list(pool.map(solve_start, [builder] * len(guesses), [params] * len(guesses),
                                guesses))
    else:
        raw = [_solve_here(tr, params, g) for g in guesses]
    starts, sols = [], []
    for i, (orig, pt, r) in enumerate(zip(origins, points, raw, strict=True)):
        sol = r if isinstance(r, Solution) else _reassemble(tr, params, r)
        rec = _record(i, orig, pt, sol, r)
        starts.append(rec)
        sols.append(sol if rec.verified else None)
    optima = _cluster(starts, sols, objective_rtol, distance_tol)
    return MultistartResult(optima, starts, method, seed, time.perf_counter() - t_start)


# ---------------------------------------------------------------------- the starts
def start_coordinates(tr: Transcription, params: dict[str, float], spread: float = 1.0,
                      box: dict[str, tuple[float, float]] | None = None) -> list[_Coordinate]:
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
    """
    box = box or {}
    pv = tr.param_vector(params)
    base = _default_solution(tr, params)
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
        out.extend(_time_coordinates(pre, tm, i in linked, spread, box))
    if tr.multiphase.var_names:
        lbw, ubw = decision_bounds(tr, params)
        w0 = tr.default_guess(params)
        for k, name in zip(range(tr.iV.start, tr.iV.stop), tr.multiphase.var_names,
                           strict=True):
            out.append(_coordinate(name, lbw[k], ubw[k], w0[k], spread, box))
    return out


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
                      box: dict[str, tuple[float, float]]) -> list[_Coordinate]:
    """A phase's sampled times: ``t0`` (free and not linked to the previous phase's end),
    then ``T`` (free, fixed start) or ``duration`` (free, free start)."""
    out: list[_Coordinate] = []
    if tm.t0_free and not linked:
        lo, hi = tm.t0_bounds
        out.append(_coordinate(pre + "t0", lo, hi, tm.t0_guess, spread, box))
    if not tm.T_free:
        return out
    if tm.t0_free:
        lo, hi = tm.span if tm.span is not None else (0.0, math.inf)
        c = _coordinate(pre + "duration", max(lo, 0.0), hi, tm.T_guess - tm.t0_guess,
                        spread, box)
    else:
        lo, hi = tm.T_bounds
        c = _coordinate(pre + "T", lo, hi, tm.T_guess, spread, box)
    if c.name not in box and c.lo > 0 and c.hi > 10 * c.lo:
        c.log = True
    return out + [c]


def _starts(tr: Transcription, params: dict[str, float], coords: list[_Coordinate], n: int,
            method: str, seed: int | None, guess: Any
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
