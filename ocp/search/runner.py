"""Solving the starts of :func:`ocp.multistart`: here, on a process pool or on Dask, and
what became of each (:class:`StartResult`).

A failed start costs no more than its solve. Its record keeps Ipopt's status and the
error's first line; the analysis of its last iterate (:mod:`ocp.transcriptions.diagnosis`:
dependent end conditions, violated rows, scaling, periodic states) runs only when
:attr:`StartResult.diagnosis` is read. A scaled solve that fails is retried on the NLP
as posed (the transcription's scaling fallback) only for the starts ``fallback`` names
(:func:`retries`): by default the first, which is what a solve from the guess would
give; the other starts are covered by one another, and the retry would double a
failing start's time.
"""

from __future__ import annotations

import math
import multiprocessing
import warnings
from collections.abc import Callable, Generator, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..definition.errors import PathViolationWarning, ProblemDefinitionError, SolveError
from ..transcriptions.diagnosis import diagnose
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from ..transcriptions.verify import verify

__all__ = ["FALLBACKS", "Runner", "StartResult", "record", "retries", "solution_of",
           "solve_start"]

Builder = Callable[[], Transcription]
FALLBACKS = ("first", "all", "none")


@dataclass
class StartResult:
    """What became of one start.

    ``origin`` is ``"guess"`` (the user's guess), ``"default"`` (the default
    guess), ``"bang"`` (a structured start) or the sampling method (a waypoint
    start); ``point`` the start's coordinates by name (a structured start's: its
    times, every control's first level and switch times ``"u.t1"``, ``"u.t2"``;
    a waypoint start's: the waypoint's states, the fitted controls at mid-phase,
    the times); ``status`` Ipopt's return status (or the exception's name when
    the start could not be solved); ``optimum`` the index in
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
        Why it failed, when it did (the error's text, without the diagnosis).
    analyse : callable or None
        ``() -> diagnosis``: the deferred analysis of a failed start's last iterate, run
        (once) when :attr:`diagnosis` is first read.
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
    analyse: Callable[[], Any] | None = field(default=None, repr=False, compare=False)

    @property
    def diagnosis(self) -> Any:
        """What is wrong at a failed start's last iterate
        (:class:`ocp.transcriptions.diagnosis.Diagnosis`), computed when first read; None
        for a start that did not fail in Ipopt (or whose iterate is not known)."""
        if self.analyse is not None:
            analyse, self.analyse = self.analyse, None
            try:
                self._diagnosis = analyse()
            except Exception as exc:  # noqa: BLE001 (an analysis must not hide the failure)
                self._diagnosis = f"no diagnosis ({type(exc).__name__}: {exc})"[:200]
        return getattr(self, "_diagnosis", None)

    def __getstate__(self) -> dict[str, Any]:
        # the analysis is a closure over the transcription: pickled as its result, if read
        return {k: v for k, v in self.__dict__.items() if k != "analyse"} | {"analyse": None}


def retries(fallback: str, index: int) -> bool:
    """Whether start ``index`` may retry a failed scaled solve as posed.

    Parameters
    ----------
    fallback : {"first", "all", "none"}
        Which starts may.
    index : int
        The start's number.
    """
    return fallback == "all" or (fallback == "first" and index == 0)


@contextmanager
def _fallback(tr: Transcription, allowed: bool) -> Iterator[None]:
    """The transcription's scaling fallback, turned off for one solve unless ``allowed``."""
    opts = tr.scaling_options
    if allowed or not opts.get("fallback", True):
        yield
        return
    tr.scaling_options = {**opts, "fallback": False}
    try:
        yield
    finally:
        tr.scaling_options = opts


def solve_here(tr: Transcription, params: dict[str, float], w0: np.ndarray,
               fallback: bool) -> Solution | dict[str, Any]:
    """A converged solution, or a dict saying why there is none (no diagnosis run).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    params : dict
        Parameter values.
    w0 : ndarray
        The start's decision vector.
    fallback : bool
        Whether a failed scaled solve may be retried as posed.
    """
    try:
        with warnings.catch_warnings(), _fallback(tr, fallback):
            warnings.simplefilter("ignore", PathViolationWarning)
            return tr.solve(params, guess=w0)
    except SolveError as e:  # includes an infeasible start and a path violation ("raise")
        it = e.iterate if isinstance(e.iterate, Solution) else None
        return {"status": e.status, "message": str(e.args[0]) if e.args else e.status,
                "success": False, "iterations": it.iterations if it is not None else 0,
                "solve_time": it.solve_time if it is not None else 0.0, "error": e}
    except ProblemDefinitionError as e:  # a start that makes the dynamics non-finite
        return {"status": type(e).__name__, "message": str(e), "success": False,
                "iterations": 0, "solve_time": 0.0}
    except (RuntimeError, ArithmeticError) as e:  # CasADi's evaluation errors and the like:
        # one bad start is a failed start, not the end of the run
        return {"status": type(e).__name__, "message": (str(e).splitlines() or [""])[0][:200],
                "success": False, "iterations": 0, "solve_time": 0.0}


_BUILT: dict[Any, Transcription] = {}


def solve_start(builder: Builder, params: dict[str, float], w0: np.ndarray,
                fallback: bool = False) -> dict[str, Any]:
    """Solve one start in a worker process: build (once per process), solve, return raw arrays.

    Parameters
    ----------
    builder : callable
        Zero-argument callable returning the transcription.
    params : dict
        Parameter values.
    w0 : ndarray
        The start's decision vector.
    fallback : bool
        Whether a failed scaled solve may be retried as posed.
    """
    try:
        tr = _BUILT[builder]
    except (KeyError, TypeError):
        tr = builder()
        try:
            _BUILT[builder] = tr
        except TypeError:  # an unhashable builder is built for every start
            pass
    out = solve_here(tr, params, w0, fallback)
    if isinstance(out, dict):
        err = out.pop("error", None)
        it = getattr(err, "iterate", None)
        if isinstance(it, Solution):  # the parent analyses it if asked
            out["iterate"] = (np.asarray(it.w, dtype=float), it.scaling)
        return out
    return {"w": out.w, "f": out.objective, "lam_g": out.lam_g, "lam_x": out.lam_x,
            "success": out.success, "status": out.status, "iterations": out.iterations,
            "solve_time": out.solve_time, "message": "",
            "mesh_error": getattr(out, "mesh_error", None)}


class Runner:
    """Solves starts here, on a process pool (kept for the whole run) or on Dask, yielding
    the results in the order of the starts (queued ones are cancelled when the caller stops).

    Parameters
    ----------
    tr : Transcription
        The transcription (solved here, or the calling process's build).
    builder : callable or None
        The workers' builder.
    params : dict
        Parameter values.
    client : dask.distributed.Client or None
        A Dask cluster.
    workers : int or None
        Processes of a pool (None: here).
    """

    def __init__(self, tr: Transcription, builder: Builder | None, params: dict[str, float],
                 client: Any, workers: int | None) -> None:
        self.tr, self.builder, self.params = tr, builder, params
        self.client, self.workers = client, workers
        self.pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> Runner:
        if self.client is None and self.workers is not None:
            # spawn, not fork: forking a process with Ipopt's and BLAS's threads can deadlock
            self.pool = ProcessPoolExecutor(max_workers=self.workers,
                                            mp_context=multiprocessing.get_context("spawn"))
        return self

    def __exit__(self, *exc: object) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)

    def each(self, starts: list[tuple[np.ndarray, bool]]) -> Generator[Any, None, None]:
        """The results of solving from ``starts``, in their order.

        Parameters
        ----------
        starts : list of tuple
            ``(decision vector, whether a failed scaled solve may be retried as posed)``.
        """
        if self.client is None and self.pool is None:
            for g, fb in starts:
                yield solve_here(self.tr, self.params, g, fb)
            return
        if self.client is not None:
            futures = [self.client.submit(solve_start, self.builder, self.params, g, fb,
                                          pure=False) for g, fb in starts]
        else:
            assert self.pool is not None and self.builder is not None
            futures = [self.pool.submit(solve_start, self.builder, self.params, g, fb)
                       for g, fb in starts]
        try:
            for f in futures:
                yield f.result()
        finally:  # the caller stopped (or failed): drop what has not run
            if self.client is not None:
                self.client.cancel(futures)
            else:
                for f in futures:
                    f.cancel()


def solution_of(tr: Transcription, params: dict[str, float], raw: Any) -> Solution | None:
    """A start's solution: solved here, or reassembled from a worker's raw result.

    Parameters
    ----------
    tr : Transcription
        This process's build.
    params : dict
        Parameter values.
    raw : Solution or dict
        What the solve returned.
    """
    return raw if isinstance(raw, Solution) else _reassemble(tr, params, raw)


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


def record(tr: Transcription, params: dict[str, float], i: int, origin: str,
           point: dict[str, float], sol: Solution | None, raw: Any) -> StartResult:
    """The record of start ``i``: its solution checked between nodes, or its failure (with
    the analysis of its last iterate deferred until read).

    Parameters
    ----------
    tr : Transcription
        This process's build.
    params : dict
        Parameter values.
    i : int
        The start's number.
    origin : str
        Its kind.
    point : dict
        Its coordinates.
    sol : Solution or None
        Its solution (:func:`solution_of`).
    raw : Solution or dict
        What the solve returned.
    """
    if sol is None:
        return StartResult(i, origin, point, raw["status"], False, False, math.nan,
                           raw.get("iterations", 0), raw.get("solve_time", 0.0),
                           message=raw.get("message", ""), analyse=_analysis(tr, params, raw))
    if sol.verified is None:  # not yet checked between nodes (verify="off", or a worker's)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PathViolationWarning)
            verify(sol, "warn", tr.verify_tol, tr.verify_points)
    ok = bool(sol.success and sol.verified)
    return StartResult(i, origin, point, sol.status, sol.success, ok, sol.objective,
                       sol.iterations, sol.solve_time,
                       message="" if ok else "violates a path constraint between nodes")


def _analysis(tr: Transcription, params: dict[str, float],
              raw: dict[str, Any]) -> Callable[[], Any] | None:
    """The deferred analysis of a failed start's last iterate (None if it has none)."""
    err = raw.get("error")
    if isinstance(err, SolveError):
        return lambda: err.diagnosis
    if "iterate" in raw:
        w, scaling = raw["iterate"]
        pv = np.asarray(tr.param_vector(params), dtype=float)
        return lambda: diagnose(tr, w, pv, scaling)
    return None
