"""Refinement until the objective and the trajectory converge, with an honest error estimate.

Collocation (:class:`MeshRefinement`, h-refinement): rounds split the intervals whose
error estimate (:mod:`ocp.transcriptions.mesh`) or whose violation between the points
(:mod:`ocp.transcriptions.extrema`) exceeds the tolerance, then, while the objective's
change between meshes exceeds its tolerance, those with the largest estimates and those
whose constraints between the points cost the objective most
(:mod:`ocp.transcriptions.indicators`). An interval found violating a path constraint or
state bound between its points gets the constraints imposed at its Bernstein control
points from then on (``inner_constraints``; its pieces inherit them): a violation that
comes from the NLP's freedom between the points rather than from the mesh (measured: the
speed limit's state polynomial 1-2e-6 above its bound on intervals of every size from
3e-5 to 3e-3, round after round, refinement never converging) is closed so.

Neither criterion measures the objective's error: the local estimates do not see an
interval whose control kinks inside it while its dynamics are met (the speed limit's
exit junction: 7.4e-7 off with every estimate below 1e-9), and the change between two
meshes that split only some intervals can be small while the error is not (measured
before: goddard's singular arc, 3.9e-7 reported for an error of 2.7e-6). Once both are
met, the result is **confirmed**: the problem is solved again on the mesh with every
interval halved, warm-started, and the objective's error is estimated as
:data:`CONFIRM_SAFETY` times the change (for an error ``C h^p`` the coarse mesh's error is
``2^p / (2^p - 1)`` times the change: twice it for ``p = 1``), never below the last
change between rounds nor below what Ipopt resolves (:meth:`MeshRefinement.resolution`).
If that misses the tolerance, the halved mesh's solution becomes the next round and
refinement goes on, to be confirmed again. The solution returned is the confirmed one
(the coarser of the pair), so the final mesh is the one refinement needed.

Ipopt relaxes every bound by ``bound_relax_factor`` (1e-8 relative by default): an
active bound moves the objective by its multiplier times that (Bryson-Denham's
``x <= 1/9``: 3.6e-7), whatever the mesh. Rounds started from a previous mesh's
multipliers and the confirmation are therefore solved with the relaxation off (unless
``ipopt_options`` sets it), and so is a final polish on the confirmed mesh when the
relaxation moved its objective by more than Ipopt resolves (:func:`relaxation_effect`):
the confirmed objective is the discretisation's, not the relaxed problem's.

Multiple shooting (:class:`NodeDoubling`): the nodes are doubled until the estimate
of :func:`doubling_error` (Richardson's, from the last three solves) meets the tolerance,
its rate is confirmed (:func:`rate_confirmed`) and the RK4 steps resolve the running cost
and the dynamics (:func:`integration_error`); the finest solution is returned.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..definition.errors import ProblemDefinitionError, SolveError
from ..definition.symbols import positive_int, relative_tolerance
from .discretization import segment_index
from .failure import warn_unconverged
from .indicators import conservatism, largest_share
from .mesh import (
    MeshRound,
    interval_errors,
    mesh_error,
    objective_change,
    objective_threshold,
    refine_mesh,
)
from .solution import Solution
from .verify import interval_excess, verify

NOISE = 1e-3
"""Local estimates below this fraction of the tolerance do not localise the objective's
error (measured: 1e-11 to 1e-14 on a third-order state constraint, where splitting
everything within two decades of the largest tripled the mesh each round for nothing)."""
CONFIRM_SAFETY = 3.0
"""The objective's error estimate is this times its change on the mesh halved (see the
module: 2 is exact for first-order convergence, 1.33 for second order)."""
RATIO_MIN = 1.0 / 64.0
"""The smallest ratio of successive changes taken as a doubling's convergence rate (a
sixth-order method's): a faster fall is a plateau the grid has not resolved, and the
estimate is the larger change (another doubling decides)."""

WARM_REFINE_ERROR = 1e-3
"""A refinement round starts from the previous mesh's primal and dual solution (Ipopt's
warm start) when the previous mesh's largest interval error estimate is at most this;
from a coarser solution only its primal values are used. Measured on the alp rider
(Betts, refinement from N = 20): the warm rounds take 12 iterations where the primal
start took 91-156; from meshes with estimates 0.067 and 1.3 the warm start took 117 and
1065 iterations where the primal start took 41 and 134."""


def tight_options(options: dict[str, Any]) -> dict[str, Any]:
    """Ipopt's options with its relaxation of the bounds off, unless they set it.

    Parameters
    ----------
    options : dict
        A transcription's Ipopt options.
    """
    if "bound_relax_factor" in options:
        return options
    return {**options, "bound_relax_factor": 0.0}


def is_tight(sol: Solution) -> bool:
    """Whether a solution was solved with the relaxation :func:`tight_options` sets.

    Parameters
    ----------
    sol : Solution
        A transcription's solution.
    """
    opts = sol.transcription.ipopt_options
    return opts == tight_options(opts)


def relaxation_effect(sol: Solution) -> float:
    """What Ipopt's relaxation of the bounds moved the objective by, to first order: the
    sum over the inequality bounds (of the variables and the constraints) of each
    multiplier times its relaxation ``bound_relax_factor * max(1, |bound|)``.

    Parameters
    ----------
    sol : Solution
        A solution.
    """
    tr = sol.transcription
    relax = float(tr.ipopt_options.get("bound_relax_factor", 1e-8))
    if relax == 0.0:
        return 0.0
    lbw, ubw, lbg, ubg = (np.array(b, dtype=float).ravel()
                          for b in tr.bounds_function(tr.param_vector(sol.params)))

    def moved(lam: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
        bound = np.where(lam > 0, hi, lo)  # CasADi: a positive multiplier holds the upper
        free = np.isfinite(bound) & (lo < hi)  # equalities and fixed variables: not relaxed
        return float(np.sum(np.abs(lam[free]) * np.maximum(1.0, np.abs(bound[free]))))

    return relax * (moved(sol.lam_x, lbw, ubw) + moved(sol.lam_g, lbg, ubg))


def halved(meshes: list[np.ndarray]) -> list[np.ndarray]:
    """Every interval of every mesh cut in two.

    Parameters
    ----------
    meshes : list of ndarray
        Normalised meshes.
    """
    return [np.sort(np.r_[m, 0.5 * (m[1:] + m[:-1])]) for m in meshes]


def doubling_error(values: list[float]) -> float:
    """Estimated error of the last of a sequence of objectives, each on twice the nodes of
    the one before.

    Two values: :data:`CONFIRM_SAFETY` times their change divided by 2 (the error of the
    finer for first-order convergence is the change). Three: the ratio ``r`` of the last
    two changes gives Richardson's error ``r / (1 - r)`` times the last change, times
    :data:`CONFIRM_SAFETY`, never below the last change; a ratio of 1 or more (not yet
    converging) or below :data:`RATIO_MIN` (a plateau, not a rate) gives the larger change
    times :data:`CONFIRM_SAFETY`.

    Parameters
    ----------
    values : list of float
        The objectives, coarsest first.
    """
    if len(values) < 2 or not all(math.isfinite(v) for v in values[-3:]):
        return math.inf
    last = abs(values[-1] - values[-2])
    if len(values) == 2:
        return 0.5 * CONFIRM_SAFETY * last
    before = abs(values[-2] - values[-3])
    if before == 0.0 or last >= before or last < RATIO_MIN * before:
        # (a change that fell by more than RATIO_MIN is no asymptotic rate but a plateau of
        # an unresolved grid: 0.166, 0.1241, 0.1237 for a true 0.0759 read as converged)
        return CONFIRM_SAFETY * max(last, before)
    r = last / before
    return max(last, CONFIRM_SAFETY * last * r / (1.0 - r))


def integration_error(sol: Solution) -> tuple[float, float]:
    """What a multiple-shooting solution owes to its RK4 integrator, not to its control grid:
    every interval integrated again from its node with its control and four times the
    substeps. Returns the absolute change of the running cost's integral (summed over the
    intervals) and the largest change of an interval's end state, relative to ``max(1,
    |x|)``. Both 0 for CVODES (adaptive, to its own tolerance).

    Doubling the nodes halves the control's grid and the RK4 step together; this separates
    the integrator's share, so that a solution whose continuity holds only for its own
    coarse steps (fast dynamics, a running cost varying within a step) is not called
    converged on the objective's change alone.

    Parameters
    ----------
    sol : Solution
        A multiple-shooting solution.
    """
    cost, state = 0.0, 0.0
    for ph in sol.phases:
        disc, d = ph.discretization, ph.data
        if getattr(disc, "integrator", "rk4") != "rk4":
            continue
        n = d.mesh.size - 1
        args = (d.x[:n].T, d.u[:n].T, d.mesh[:n][None, :], np.diff(d.mesh)[None, :], d.s)
        xf, qf = (np.array(v, dtype=float) for v in disc.sampler(disc.M, n)(*args)[:2])
        xf4, qf4 = (np.array(v, dtype=float) for v in disc.sampler(4 * disc.M, n)(*args)[:2])
        if qf.size:
            cost += abs(float(np.sum(qf4[0]) - np.sum(qf[0])))
        scale = np.maximum(1.0, np.abs(xf))
        state = max(state, float(np.max(np.abs(xf4 - xf) / scale, initial=0.0)))
    return cost, state


def _ratios(values: list[float]) -> str:
    """The last two ratios of successive changes, for a message."""
    c = np.abs(np.diff(np.asarray(values[-4:], dtype=float)))
    return ", ".join(f"{b / a:.2g}" if a else "inf" for a, b in zip(c[:-1], c[1:],
                                                                      strict=True))


def rate_confirmed(values: list[float], floor: float) -> bool:
    """Whether a doubling sequence of objectives is in its asymptotic regime, so that its
    Richardson estimate can be believed: the last change at the solver's resolution, or the
    last two ratios of successive changes both in ``[RATIO_MIN, 1)`` and within a factor 4
    of each other (the same rate twice). Needs four objectives (three doublings).

    A sequence still on a plateau of an unresolved grid gives a plausible single ratio
    (0.12376, 0.12444, 0.12429: 0.22) for a true 0.0759; the next doubling breaks it.

    Parameters
    ----------
    values : list of float
        The objectives, coarsest first.
    floor : float
        The absolute change below which the objectives agree to the solver's resolution.
    """
    if len(values) < 4:
        return False
    c = np.abs(np.diff(np.asarray(values[-4:], dtype=float)))
    if c[-1] <= floor:
        return True
    if c[0] == 0.0 or c[1] == 0.0:
        return False
    r1, r2 = c[1] / c[0], c[2] / c[1]
    return bool(RATIO_MIN <= r1 < 1.0 and RATIO_MIN <= r2 < 1.0 and 0.25 <= r2 / r1 <= 4.0)


class RefinementBase:
    """What both refinements read of the transcription they are mixed into (its options,
    its solve) and the objective accuracies they share."""

    # set by the transcription (annotations only: the values are the transcription's)
    codegen: bool
    verify: str
    verify_tol: float
    verify_points: int
    ipopt_options: dict[str, Any]
    _solve: Callable[..., Solution]

    def objective_floor(self) -> float:
        """The relative objective accuracy below which mesh rounds chase the NLP solver's
        own tolerance: ten times the larger of Ipopt's ``tol`` and its relaxation of
        bounds (``bound_relax_factor``, 1e-8 by default), which move the objective of a
        problem with active bounds by about that much whatever the mesh. (The final
        solves are made with the relaxation off, so the result is usually more accurate
        than this: the floor is what ``refine`` aims at by default, not what it reaches.)

        Returns
        -------
        float
        """
        opts = self.ipopt_options
        return 10.0 * max(float(opts.get("tol", 1e-8)),
                          float(opts.get("bound_relax_factor", 1e-8)))

    def resolution(self) -> float:
        """The relative objective accuracy of a solve with the bound relaxation off: ten
        times Ipopt's ``tol`` (no error estimate is reported below it).

        Returns
        -------
        float
        """
        opts = tight_options(self.ipopt_options)
        return 10.0 * max(float(opts.get("tol", 1e-8)),
                          float(opts.get("bound_relax_factor", 0.0)))


class MeshRefinement(RefinementBase):
    """:meth:`refine` for :class:`ocp.Collocation` (see the module)."""

    degree: int  # (set by the transcription)

    def refine(self, params: dict[str, float] | None = None, tol: float = 1e-6,
               max_rounds: int = 10, max_intervals: int = 5000, guess: Any = None,
               max_split: int = 8, objective_tol: float | None = None) -> Solution:
        """Solve, then refine the mesh until the states and the objective are accurate.

        Parameters
        ----------
        params : dict, optional
            Parameter values.
        tol : float
            Requested relative accuracy of the states (and cost quadratures):
            every interval's error estimate must be below it.
        max_rounds : int
            Most refinements (each builds and solves one NLP; the confirmations, on the
            mesh halved, and a final polish on the same mesh are not counted).
        max_intervals : int
            Stop before a mesh (all phases) would exceed this many intervals.
        guess : Solution or decision vector, optional
            Start of the first solve.
        max_split : int
            Most pieces an interval is split into per round.
        objective_tol : float, optional
            Requested accuracy of the objective, relative to ``max(1, |J|)``
            (default: ``tol``, but not below :meth:`objective_floor`, what the NLP
            solver itself resolves; ``math.inf`` switches the criterion and the
            confirmation off).

        Returns
        -------
        Solution
            On the last refined mesh; ``mesh_history`` lists every round (with its
            objective estimate and the criterion that drove the next round; the last
            one, ``kind="confirm"``, the confirmation on the mesh halved),
            ``mesh_error`` is the final state estimate, ``objective_error`` the
            estimate of the objective's absolute error (``inf`` when no confirmation
            could be made) and ``mesh_converged`` tells whether both met their
            tolerances; ``convergence`` says so in words. ``sol.transcription``
            re-solves on that mesh (with Ipopt's bound relaxation off, as it was solved).

        Notes
        -----
        See :mod:`ocp.transcriptions.refinement`. A round whose previous mesh's largest
        estimate is at most :data:`WARM_REFINE_ERROR` starts from that mesh's solution and
        multipliers interpolated (Ipopt's warm start; on the unexpanded graph, cheaper to
        build than its few iterations would gain from expansion), other rounds from its
        primal values. The error of an interval is the larger of its estimate and the
        path-constraint violation found inside it when that exceeds ``verify_tol``
        (Ipopt itself relaxes bounds by about 1e-8).
        """
        if self.codegen:
            raise ProblemDefinitionError(
                "refine() builds a new NLP on every mesh, which codegen=True would compile "
                "each time: refine without it, then re-solve on the final mesh with "
                "Collocation(problem, mesh=sol.transcription.meshes, codegen=True)")
        tol = relative_tolerance(tol, "refine(tol)")
        otol = max(tol, self.objective_floor()) if objective_tol is None \
            else relative_tolerance(objective_tol, "refine(objective_tol)", allow_inf=True)
        # (a split of 1 re-solved one mesh every round; 0 or less failed inside numpy)
        max_split = positive_int(max_split, "refine(max_split)", minimum=2)
        max_rounds = positive_int(max_rounds, "refine(max_rounds)", minimum=0)
        max_intervals = positive_int(max_intervals, "refine(max_intervals)")
        sol = self._solve(params, guess, None, "off")
        run = _Run(self, params, tol, otol, max_split, sol.objective_scale)
        sol = run.loop(sol, max_rounds, max_intervals, guess)
        if not sol.mesh_converged:  # name what the problem suggests as the cause
            warn_unconverged(sol)
        verify(sol, self.verify, self.verify_tol, self.verify_points)
        return sol

    def round_errors(self, sol: Solution) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Per phase, every interval's error (its estimate or its violation between the
        points, whichever is larger) and whether it violates a constraint between them.

        Parameters
        ----------
        sol : Solution
            A solution of this problem on any mesh.
        """
        errs, gaps = [], []
        for ph in sol.phases:
            excess = interval_excess(ph, sol.params, self.verify_points, self.verify_tol)
            gap = excess > self.verify_tol
            errs.append(np.maximum(interval_errors(ph), np.where(gap, excess, 0.0)))
            gaps.append(gap)
        return errs, gaps

    def next_meshes(self, meshes: list[np.ndarray], errs: list[np.ndarray], driver: str,
                    tol: float, change: float, target: float, max_split: int,
                    must: list[np.ndarray] | None = None) -> list[np.ndarray]:
        """The refined meshes for a round driven by the states or by the objective.

        Parameters
        ----------
        meshes : list of ndarray
            The current normalised meshes.
        errs : list of ndarray
            Per phase, each interval's error (or, for ``driver="objective"``, any
            indicator of where the objective's error lies).
        driver : {"state", "objective"}
            What drives the round.
        tol, change, target : float
            The states' tolerance, the objective's error estimate and its target.
        max_split : int
            Most pieces per interval.
        must : list of ndarray, optional
            Per phase, intervals to split in any case (an objective round).
        """
        if driver == "state":
            return [refine_mesh(m, e, tol, self.degree, max_split)
                    for m, e in zip(meshes, errs, strict=True)]
        must = must or [np.zeros(e.size, bool) for e in errs]
        emax = float(max(e.max() for e in errs))
        if emax <= 0.0 and not any(f.any() for f in must):
            return halved(meshes)  # nothing to localise the objective's error by
        cut = objective_threshold(emax, change, target) if emax > 0.0 else 1.0
        return [refine_mesh(m, np.where(f, np.maximum(e, 2.0 * cut), e), cut, self.degree,
                            max_split) for m, e, f in zip(meshes, errs, must, strict=True)]

    def next_solve(self, params: dict[str, float] | None, sol: Solution,
                   guess: Any, close: bool, objective_scale: float) -> Solution:
        """A refinement round's solve: from the previous mesh's solution with its
        multipliers interpolated (Ipopt's warm start) when that solution is ``close``
        (see :data:`WARM_REFINE_ERROR`), else (or if that fails) from its primal values
        only, else from the first round's start.

        Parameters
        ----------
        params : dict, optional
            Parameter values.
        sol : Solution
            The previous round's solution.
        guess : Solution or decision vector, optional
            The first round's start.
        close : bool
            Whether to warm-start from ``sol``'s multipliers.
        objective_scale : float
            The first round's objective scale (kept by every round).
        """
        starts: tuple[tuple[Any, Solution | None], ...] = ((None, sol), (sol, None), (guess, None))
        if not close:
            starts = starts[1:]
        for k, (g, warm) in enumerate(starts):
            try:  # a warm round takes few iterations: the unexpanded graph is cheaper
                return self._solve(params, g, warm, "off", False if warm else None,
                                   objective_scale)
            except SolveError:  # the previous mesh's solution may mislead: start afresh
                if k == len(starts) - 1:
                    raise
        raise AssertionError("unreachable")


class _Run:
    """The state of one :meth:`MeshRefinement.refine` call (its rounds and history)."""

    def __init__(self, origin: Any, params: dict[str, float] | None, tol: float,
                 otol: float, max_split: int, fref: float) -> None:
        self.origin, self.params, self.tol, self.otol = origin, params, tol, otol
        self.max_split, self.fref = max_split, fref
        self.history: list[MeshRound] = []
        self.previous: list[float] = []  # objectives of the earlier rounds

    def record(self, sol: Solution, emax: float, change: float, driver: str,
               kind: str = "refine") -> None:
        """Append one round to the history."""
        self.history.append(MeshRound([ph.mesh.size - 1 for ph in sol.phases], emax,
                                      sol.objective, sol.iterations, sol.solve_time, change,
                                      driver, kind))

    def loop(self, sol: Solution, max_rounds: int, max_intervals: int,
             guess: Any) -> Solution:
        """Refine and confirm until converged or out of rounds (see the module)."""
        tr, error, rounds, confirmed = sol.transcription, math.inf, 0, False
        while True:
            errs, gaps = self.origin.round_errors(sol)
            emax = float(max(e.max() for e in errs))
            change = objective_change(self.previous, sol.objective)
            target = self.otol * max(1.0, abs(sol.objective))
            driver = "state" if emax > self.tol else \
                "objective" if math.isfinite(change) and change > target else ""
            self.record(sol, emax, change, driver)
            inner = [f | g for f, g in zip(tr.inner, gaps, strict=True)]
            if not driver:
                error = change
                if self.otol == math.inf:
                    confirmed = True  # no objective criterion, no confirmation
                    break
                if 2 * _size(tr.meshes) > max_intervals:
                    break  # no confirmation affordable: the estimate stays unconfirmed
                sol, tr = self.polish(sol, tr, inner)
                fine, error = self.confirm(sol, tr, inner, change)
                if error <= target:
                    confirmed = True
                    break
                self.previous.append(sol.objective)  # the halved mesh is the next round
                sol, tr = fine, fine.transcription  # (solved already: not counted)
                continue
            close = emax <= WARM_REFINE_ERROR
            new = self.origin.next_meshes(tr.meshes, errs, "state", self.tol, change, target,
                                          self.max_split) if driver == "state" else \
                self.objective_meshes(tr, sol, change, target, errs)
            if rounds + 1 > max_rounds or _size(new) > max_intervals:
                self.history[-1].refined_for = ""
                break
            tr = self.next_transcription(tr, new, inner, close)
            self.previous.append(sol.objective)
            sol = tr.next_solve(self.params, sol, guess, close, self.fref)
            rounds += 1
        sol.mesh_history, sol.mesh_error, sol.objective_error = self.history, emax, error
        sol.mesh_converged = confirmed and emax <= self.tol and \
            error <= self.otol * max(1.0, abs(sol.objective))
        return sol

    def objective_meshes(self, tr: Any, sol: Solution, error: float, target: float,
                         errs: list[np.ndarray]) -> list[np.ndarray]:
        """The meshes of a round driven by the objective: split where the local estimates
        are largest, and the intervals whose constraints between the points cost the
        objective more than a tenth of its target (:mod:`ocp.transcriptions.indicators`)."""
        errs = [np.where(e >= NOISE * self.tol, e, 0.0) for e in errs]  # else rounding
        cost = [conservatism(ph) for ph in sol.phases]
        share = largest_share(np.concatenate(cost), 0.1 * target)
        bounds = np.cumsum([0] + [c.size for c in cost])
        must = [share[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        return self.origin.next_meshes(tr.meshes, errs, "objective", self.tol, error,
                                       target, self.max_split, must)

    def next_transcription(self, tr: Any, meshes: list[np.ndarray],
                           inner: list[np.ndarray], tight: bool) -> Any:
        """The next round's transcription: the constraints between the points inherited
        (with the intervals found violating now), Ipopt's relaxation off when ``tight``."""
        mapped = [f[segment_index(m_old, 0.5 * (m[1:] + m[:-1]))]
                  for f, m_old, m in zip(inner, tr.meshes, meshes, strict=True)]
        opts = tight_options(self.origin.ipopt_options) if tight else \
            self.origin.ipopt_options
        return tr.with_mesh(meshes, verify="off", inner=mapped, ipopt_options=opts)

    def polish(self, sol: Solution, tr: Any, inner: list[np.ndarray]) -> tuple[Solution, Any]:
        """The solution on its own mesh with Ipopt's bound relaxation off (and the
        constraints between the points where a violation was found), warm-started."""
        same = all(np.array_equal(a, b) for a, b in zip(inner, tr.inner, strict=True))
        negligible = relaxation_effect(sol) <= self.origin.resolution() * max(
            1.0, abs(sol.objective))
        if same and (is_tight(sol) or negligible):
            return sol, tr
        tr = self.next_transcription(tr, tr.meshes, inner, True)
        return tr.next_solve(self.params, sol, None, True, self.fref), tr

    def confirm(self, sol: Solution, tr: Any, inner: list[np.ndarray],
                change: float) -> tuple[Solution, float]:
        """Solve on the mesh halved; the estimate of ``sol``'s objective error."""
        fine_tr = self.next_transcription(tr, halved(tr.meshes), inner, True)
        fine = fine_tr.next_solve(self.params, sol, None, True, self.fref)
        delta = abs(fine.objective - sol.objective)
        scale = max(1.0, abs(sol.objective))  # no estimate below what Ipopt resolves
        error = max(CONFIRM_SAFETY * delta, change if math.isfinite(change) else 0.0,
                    self.origin.resolution() * scale)
        target = self.otol * scale
        self.history.append(MeshRound([ph.mesh.size - 1 for ph in fine.phases],
                                      mesh_error(fine), fine.objective, fine.iterations,
                                      fine.solve_time, error,
                                      "" if error <= target else "objective", "confirm"))
        return fine, error


def _size(meshes: list[np.ndarray]) -> int:
    return sum(m.size - 1 for m in meshes)


class NodeDoubling(RefinementBase):
    """:meth:`refine` for :class:`ocp.MultipleShooting` (see the module)."""

    nodes: list[int]  # per phase (set by the transcription)
    with_nodes: Callable[..., Any]

    def refine(self, params: dict[str, float] | None = None, tol: float = 1e-6,
               max_rounds: int = 6, max_nodes: int = 5000, guess: Any = None) -> Solution:
        """Solve, then double the nodes until the objective's estimated error meets ``tol``.

        Multiple shooting has no error estimate per interval: its piecewise-constant
        control converges at first or second order in the node spacing, and the
        objective's change from one count to its double measures it
        (:func:`doubling_error`: Richardson's estimate from the last three counts, with a
        safety factor, never below the last change), and each interval integrated again
        with four times the RK4 steps measures the integrator's share
        (:func:`integration_error`: its running cost's change, times the safety factor,
        joins the estimate; an end state moved by more than ``tol`` is not converged).
        Converged also needs the rate confirmed (:func:`rate_confirmed`: the same ratio of
        changes twice, so at least three doublings). The finest solution is returned. For
        an accuracy beyond a few digits, :class:`ocp.Collocation`'s :meth:`refine`
        converges faster (high order, local refinement).

        Parameters
        ----------
        params : dict, optional
            Parameter values.
        tol : float
            Requested accuracy of the objective, relative to ``max(1, |J|)`` (not below
            :meth:`objective_floor`).
        max_rounds : int
            Most doublings.
        max_nodes : int
            Stop before the nodes (all phases) would exceed this.
        guess : Solution or decision vector, optional
            Start of the first solve.

        Returns
        -------
        Solution
            On the last (finest) nodes; ``mesh_history`` lists every solve (nodes,
            objective, estimate), ``objective_error`` is the estimate of the objective's
            absolute error, ``mesh_converged`` whether it met the tolerance,
            ``convergence`` says so in words; ``sol.transcription`` re-solves on those nodes.
        """
        if self.codegen:
            raise ProblemDefinitionError(
                "refine() builds a new NLP for every node count, which codegen=True would "
                "compile each time: refine without it, then re-solve with "
                "MultipleShooting(problem, nodes=sol.transcription.nodes, codegen=True)")
        otol = max(relative_tolerance(tol, "refine(tol)"), self.objective_floor())
        max_rounds = positive_int(max_rounds, "refine(max_rounds)", minimum=0)
        max_nodes = positive_int(max_nodes, "refine(max_nodes)")
        sol = self._solve(params, guess, None, "off")
        fref, values = sol.objective_scale, [sol.objective]
        history = [MeshRound(list(self.nodes), math.nan, sol.objective, sol.iterations,
                             sol.solve_time, math.inf, "objective")]
        tr, error, done = self, math.inf, False
        for _ in range(max_rounds):
            nodes = [2 * n for n in tr.nodes]
            if sum(nodes) > max_nodes:
                break
            tr = tr.with_nodes(nodes, tight_options(self.ipopt_options))
            sol = tr._solve(params, sol, None, "off", None, fref)
            values.append(sol.objective)
            error = max(doubling_error(values), self.resolution() * max(1.0, abs(sol.objective)))
            # (the integrator's share: a cost or dynamics the RK4 steps do not resolve)
            cost, state = integration_error(sol)
            error = max(error, CONFIRM_SAFETY * cost)
            scale = max(1.0, abs(sol.objective))
            done = error <= otol * scale and state <= otol and rate_confirmed(
                values, self.resolution() * scale)
            history.append(MeshRound(nodes, math.nan, sol.objective, sol.iterations,
                                     sol.solve_time, error, "" if done else "objective"))
            if done:
                break
        history[-1].refined_for = ""
        sol.mesh_history, sol.objective_error = history, error
        sol.mesh_converged = bool(done) if len(history) > 1 else False
        if not sol.mesh_converged and len(history) > 1 and \
                error <= otol * max(1.0, abs(sol.objective)):
            # (within the tolerance, yet not converged: say which condition is missing)
            sol.mesh_reason = (
                f"the RK4 steps do not resolve the dynamics (an interval's end state moves by "
                f"{state:.2g} with four times the steps)" if state > otol else
                f"estimated error {error:.2g} within the tolerance, but its rate is not "
                f"confirmed (the ratios of the last changes, {_ratios(values)}, differ)")
        verify(sol, self.verify, self.verify_tol, self.verify_points)
        return sol
