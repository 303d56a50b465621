"""Assembly of the phases' discretisations into one parametric NLP, and its solution by Ipopt.

The NLP takes the problem's parameters as CasADi NLP parameters ``p``; its
variable and constraint bounds and its default initial guess are CasADi
Functions of ``p`` evaluated at solve time, so a new parameter value (or a
continuation step) re-solves the same NLP object: nothing is rebuilt, and a
solve runs no Python loop over intervals. Ipopt gets exact sparse first and
second derivatives from CasADi's algorithmic differentiation.

Decision vector: the phases' blocks in order, then the decision variables.
Constraint vector: each phase's blocks (``continuity``, ``path`` /
``collocation``, ``path_inner``, then its ``initial``, ``terminal``,
``boundary`` and ``time`` constraints), then the ``link`` constraints.

Ipopt solves a scaled copy of this NLP (:mod:`ocp.definition.scaling`): ``w = D w_s + c``,
rows and objective multiplied by numbers that each solve may take anew from its start
(:mod:`ocp.transcriptions.scaled`); a failed solve is retried as posed and its failure
diagnosed (:mod:`ocp.transcriptions.failure`); every result is mapped back, so
``sol.w``, ``sol.objective``, ``lam_g``, ``lam_x`` and ``multipliers`` are in the
user's units whatever the scaling.
"""

from __future__ import annotations

import math
import re
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import ProblemDefinitionError
from ..definition.multiphase import MultiPhaseProblem, as_multiphase
from ..definition.problem import OptimalControlProblem
from ..definition.scaling import Scaling, check_scaling
from ..definition.symbols import positive_int, relative_tolerance
from .blas import default_blas_threads
from .buffered import BufferedCall
from .codegen import compiled_library
from .discretization import PhaseDiscretization, PhaseLayout, PhaseNLP
from .failure import INFEASIBLE_STATUSES, after_failure, loosened, solve_dropping_dependent
from .grid_free import GridFree, expand_mode
from .scaled import (
    build_scaling,
    carried_scaling,
    graph_of,
    identity,
    scale_args,
    scaled_nlp,
    start_scaling,
    unscale,
)
from .solution import Solution
from .start import TranscriptionStart
from .verify import VERIFY_MODES, verify

# mumps_mem_percent: Ipopt's default (1000) has MUMPS allocate eleven times its workspace
# estimate at every factorisation (13 % of the alp rider's refinement, in CPU time);
# twice the estimate gives the same iterates (Ipopt enlarges it if MUMPS ever asks)
__all__ = ["DEFAULT_IPOPT", "INFEASIBLE_STATUSES", "GridFree", "Transcription", "expand_mode"]

DEFAULT_IPOPT = {"tol": 1e-10, "max_iter": 3000, "print_level": 0, "sb": "yes",
                 "mu_strategy": "adaptive", "mumps_mem_percent": 100}
BOUNDARY_KINDS = ("initial", "terminal", "boundary", "time")




class Transcription(TranscriptionStart):
    """Base of :class:`ocp.MultipleShooting` and :class:`ocp.Collocation`.

    Parameters
    ----------
    problem : OptimalControlProblem or MultiPhaseProblem
        The problem (a single phase or several).
    ipopt_options : dict, optional
        Overrides of :data:`DEFAULT_IPOPT`.
    expand : bool or "auto"
        Expand the NLP to SX scalar graphs (slower build, faster solves); ``"auto"``
        solves the first time unexpanded (cheap to build) and expands from the second
        solve of the same kind (cold or warm-started) on, where the build pays back.
    verify : {"warn", "raise", "off"}
        After each converged solve, check path constraints and state bounds on
        a fine grid; on a violation beyond ``verify_tol`` warn
        (:class:`ocp.PathViolationWarning`) or raise
        (:class:`ocp.PathViolationError`). Either way ``sol.verified`` and
        ``sol.path_violation`` record the outcome.
    verify_tol : float
        Allowed violation, relative to ``max(1, |bound|)``.
    verify_points : int
        Check points per interval.
    scaling : {"auto", "none"} or dict
        How the NLP is scaled for Ipopt (results are always reported in the
        user's units): ``"auto"`` uses the problem's ``ref``/``ref0`` and
        ``minimize(..., ref=)`` and, where none is given, references from bounds
        and guesses that are far from 1 (see :mod:`ocp.definition.scaling`); ``"none"``
        solves the NLP exactly as posed; a dict overrides references by name
        (``{"h": 1e4, "v": (0, 300), "objective": 1e3, "time": 10}``).
    grid_free : GridFree, optional
        The grid-independent part of another transcription of the same problem
        (:attr:`grid_free`), reused instead of compiled again (mesh refinement).
    codegen : bool
        Hand Ipopt the NLP's functions compiled to machine code (CasADi's generated C and
        the system C compiler; see :mod:`ocp.transcriptions.codegen`), cached on disk by
        the generated source's hash. Opt-in: compiling takes seconds to a minute, once per
        NLP and machine, and pays for re-solves (sweeps, MPC); results agree with the
        uncompiled NLP's to rounding.

    Attributes
    ----------
    n_builds : int
        How many times the NLP was built (stays 1: re-solves never rebuild).
    grid_free : GridFree
        What the build does not take from the grid (compiled phases, default guesses,
        scaling sizes), shared with the transcriptions on other meshes it makes.
    """

    method = "base"

    def __init__(self, problem: OptimalControlProblem | MultiPhaseProblem,
                 ipopt_options: dict | None = None, expand: bool | str = False,
                 verify: str = "warn", verify_tol: float = 1e-6,
                 verify_points: int = 10, scaling: Any = "auto",
                 grid_free: GridFree | None = None, *, codegen: bool = False) -> None:
        self.scaling_options = check_scaling(scaling)
        if not isinstance(codegen, bool):
            raise ProblemDefinitionError(f"codegen must be True or False, got {codegen!r}")
        self.codegen = codegen
        self._library: dict[str, Path] = {}  # the compiled NLP functions (codegen)
        if grid_free is None:
            mp = as_multiphase(problem)
            mp.validate()
            grid_free = GridFree.of(mp)
        self.grid_free = grid_free
        self.multiphase = grid_free.multiphase
        if verify not in VERIFY_MODES:
            raise ProblemDefinitionError(f"verify must be one of {VERIFY_MODES}, got {verify!r}")
        self.problem = problem
        self.ipopt_options = {**DEFAULT_IPOPT, **(ipopt_options or {})}
        self.expand = expand_mode(expand)
        self._uses = {False: 0, True: 0}  # solves by kind (cold, warm): expand="auto"
        self.verify = verify
        # (NaN would pass every violation: a false "verified")
        self.verify_tol = relative_tolerance(verify_tol, "verify_tol")
        self.verify_points = positive_int(verify_points, "verify_points")
        self.n_builds = 0
        self.dropped: dict[int, str] = {}  # rows of g left out of this solve (drop_dependent)
        self._solvers: dict[tuple[bool, bool, str], Any] = {}
        self._calls: dict[tuple[bool, bool, str], BufferedCall] = {}  # Ipopt on numpy arrays
        self._nlp_fn = None
        self._grad_fn = None
        self._last_bounds: tuple[bytes, tuple[np.ndarray, ...]] | None = None
        self._last_default = None
        self._last_start = None
        self._last_variation = None  # likewise, its variation
        self.times = grid_free.times
        self.compiled = grid_free.compiled
        self.phases: list[PhaseDiscretization] = self._discretize()
        self._build()

    def _discretize(self) -> list[PhaseDiscretization]:
        raise NotImplementedError

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        mp = self.multiphase
        sizes = [d.size() for d in self.phases]
        self.offsets = [int(o) for o in np.r_[0, np.cumsum(sizes)[:-1]]]
        nw = int(sum(sizes)) + mp.nv
        self.iV = slice(nw - mp.nv, nw)
        w, P = ca.MX.sym("w", nw), ca.MX.sym("p", mp.np)
        V = w[self.iV]
        pieces: list[PhaseNLP] = []
        gf = self.grid_free
        choices = gf.choices
        for i, disc in enumerate(self.phases):
            wb = w[self.offsets[i]:self.offsets[i] + sizes[i]]
            pieces.append(disc.build(wb, P, V, gf.ends[i], gf.controls[i]))
        g, lbg, ubg, J_end = self._constraints(pieces, P, V)
        J = J_end + sum(pn.lagrange for pn in pieces)
        lbw = ca.vertcat(*[pn.lbw for pn in pieces], *self._var_bounds(0))
        ubw = ca.vertcat(*[pn.ubw for pn in pieces], *self._var_bounds(1))
        w0 = ca.vertcat(*[pn.w0 for pn in pieces], gf.variables)
        self._bounds = ca.Function("bounds", [mp.p], [lbw, ubw, lbg, ubg])
        self._guess = ca.Function("guess", [mp.p, *choices.symbols], [w0])
        self._choices = choices
        self._nlp = {"x": w, "p": P, "f": J, "g": g}
        self.n_w, self.n_g = nw, int(g.numel())
        self.scaling = build_scaling(self, gf.plain)
        self.n_builds += 1

    def _var_bounds(self, side: int) -> list[ca.SX]:
        sh = self.multiphase.shared
        return [sh.var_bounds[n][side] for n in sh.var_names]

    @staticmethod
    def _bvalues(pn: PhaseNLP) -> ca.MX:
        return ca.vertcat(pn.x0, pn.u0, pn.xT, pn.uT, pn.t0, pn.T, pn.q)

    def _boundary_fn(self) -> ca.Function:
        """``(end-point values of every phase, p, v) -> (each boundary group..., J)``."""
        mp = self.multiphase
        bsym = ca.vertcat(*[ca.vertcat(ph.x0, ph.u0, ph.xT, ph.uT, ph.t0, ph.T, ph.q)
                            for ph in mp.phases])
        outs = [ca.vertcat(*[c.expr for c in cs]) for _, _, cs in self.groups]
        return ca.Function("boundary", [bsym, mp.p, mp.v], [*outs, mp.objective()])

    def _constraints(self, pieces: list[PhaseNLP], P: ca.MX,
                     V: ca.MX) -> tuple[ca.MX, ca.SX, ca.SX, ca.MX]:
        """Stack g with its bounds; record each phase's blocks and the link blocks.

        Returns g, its lower and upper bounds and the end-point part of the objective.
        """
        mp = self.multiphase
        all_b = mp.boundary_blocks(self.times)
        self.groups = []
        for i in [*range(len(mp.phases)), -1]:
            for kind in (*BOUNDARY_KINDS, "link"):
                cs = [c for j, k, c in all_b if j == i and k == kind]
                if cs:
                    self.groups.append((i, kind, cs))
        bvals = self._boundary_fn()(ca.vertcat(*[self._bvalues(pn) for pn in pieces]), P, V)
        self.layouts = [d.layout(o) for d, o in zip(self.phases, self.offsets, strict=True)]
        for lay in self.layouts:
            lay.iV = self.iV
        self.link_blocks = {}
        g: list[ca.MX] = []
        lbg: list[ca.SX] = []
        ubg: list[ca.SX] = []

        def _add(blocks: dict[str, slice], name: str, expr: ca.MX, lo: ca.SX,
                 hi: ca.SX) -> None:
            n0 = sum(int(e.numel()) for e in g)
            e = ca.vec(expr)
            g.append(e)
            lbg.append(ca.vec(lo))
            ubg.append(ca.vec(hi))
            blocks[name] = slice(n0, n0 + int(e.numel()))

        for i, pn in enumerate(pieces):
            for name, expr, lo, hi in pn.constraints:
                _add(self.layouts[i].blocks, name, expr, lo, hi)
            for gi, (j, kind, cs) in enumerate(self.groups):
                if j == i:
                    _add(self.layouts[i].blocks, kind, bvals[gi],
                        ca.vertcat(*[c.lower for c in cs]), ca.vertcat(*[c.upper for c in cs]))
        for gi, (j, kind, cs) in enumerate(self.groups):
            if j == -1:
                _add(self.link_blocks, kind, bvals[gi], ca.vertcat(*[c.lower for c in cs]),
                    ca.vertcat(*[c.upper for c in cs]))
        return ca.vertcat(*g), ca.vertcat(*lbg), ca.vertcat(*ubg), bvals[-1]

    @property
    def layout(self) -> PhaseLayout:
        """Where the (only) phase lives in ``w`` and ``g`` (single-phase problems)."""
        if len(self.layouts) != 1:
            raise AttributeError("a multi-phase transcription has one layout per phase: "
                                 "use .layouts")
        return self.layouts[0]

    @property
    def bounds_function(self) -> ca.Function:
        """``p -> (lbw, ubw, lbg, ubg)``: the bounds of the decision vector and of the
        constraints at the parameter values ``p`` (unchecked, as posed)."""
        return self._bounds

    def _solver(self, warm: bool, expand: bool | None = None,
                graph: str = "build") -> tuple[Any, bool]:
        """Ipopt on the scaled NLP (built on first use): ``warm`` takes the multipliers
        given; ``expand`` overrides the transcription's for this solver only (mesh
        refinement's warm rounds, where building the expanded graph costs more than the
        few iterations it would speed up); ``graph``: which scaled graph
        (:func:`~ocp.transcriptions.scaled.scaled_nlp`)."""
        if self.codegen:
            expanded = False  # Ipopt calls the compiled functions, whatever graph made them
        elif expand is not None:
            expanded = bool(expand)
        elif self.expand == "auto":
            expanded = self._uses[warm] > 0  # a re-solve: the expanded graph pays back
        else:
            expanded = bool(self.expand)
        self._uses[warm] += 1
        key = (warm, expanded, graph)
        if key not in self._solvers:
            ipopt = dict(self.ipopt_options)
            if warm:
                ipopt.update(warm_start_init_point="yes", warm_start_bound_push=1e-9,
                             warm_start_mult_bound_push=1e-9, mu_init=1e-6)
            opts: dict[str, Any] = {"ipopt": ipopt, "print_time": False,
                                    "error_on_fail": False, "expand": key[1],
                                    "calc_lam_p": False}
            # CasADi names are identifiers; a problem's name is a label ("double integrator")
            label = re.sub(r"[^A-Za-z0-9]+", "_", self.multiphase.name).strip("_") or "ocp"
            name = f"{label if label[0].isalpha() else 'ocp_' + label}_{self.method}"
            nlp: Any = scaled_nlp(self._nlp, self.n_w, self.n_g, graph, self.scaling)
            default_blas_threads()
            solver = ca.nlpsol(name, "ipopt", nlp, opts)
            if self.codegen:  # the same functions for every key of a graph: compiled once
                if graph not in self._library:
                    self._library[graph] = compiled_library(solver)
                del opts["expand"]
                solver = ca.nlpsol(name, "ipopt", str(self._library[graph]), opts)
            self._solvers[key] = solver
            self._calls[key] = BufferedCall(solver)
        return self._solvers[key], expanded

    # ------------------------------------------------------------------ solve

    def solve(self, params: dict[str, float] | None = None, guess: Any = None,
              warm_start: Solution | None = None, *,
              drop_dependent: bool = False) -> Solution:
        """Solve for the given parameter values.

        Parameters
        ----------
        params : dict
            A value for every declared parameter (none needed if there are none).
        guess : Solution, Trajectory or decision vector, optional
            Primal starting point (cold start); a solution of another
            transcription (grid, method) or a trajectory is resampled, and the
            scaling of the states that bounds do not size is taken from it
            (:mod:`ocp.transcriptions.scaled`). By default, the default guess (see
            :mod:`ocp.definition.guess`).
        warm_start : Solution, optional
            Start from this solution's primal and dual values (Ipopt warm start). A
            solution on another collocation mesh of the same problem is resampled, its
            multipliers interpolated (:meth:`dual_from`); one of another method gives
            its primal values only.
        drop_dependent : bool
            Where the end conditions are dependent (a quantity the dynamics conserve
            fixed at both ends, :mod:`ocp.transcriptions.diagnosis`), leave out one of
            them (the terminal row of largest weight) and solve; ``sol.dropped`` names
            it and ``sol.dropped_residual`` says how well the solution meets it anyway.

        Raises
        ------
        InfeasibleError, SolveError
            Carrying Ipopt's status, the last iterate and ``diagnosis`` (what is wrong
            there, in one line in the message).
        PathViolationError
            With ``verify="raise"``, if a path constraint is violated between nodes.
        GuessError
            If the starting point makes an expression non-finite.
        TypeError
            If ``warm_start`` is not a :class:`~ocp.Solution`.
        """
        if warm_start is not None and not isinstance(warm_start, Solution):
            raise TypeError(f"solve: warm_start must be an ocp.Solution or None, got "
                            f"{type(warm_start).__name__} {warm_start!r:.40}")
        if drop_dependent:
            return solve_dropping_dependent(self, params, guess, warm_start)
        return self._solve(params, guess, warm_start, self.verify)

    def solve_once(self, params: dict[str, float] | None, guess: Any,
                   warm_start: Solution | None, dropped: dict[int, str]) -> Solution:
        """One solve with the rows ``dropped`` loosened (:func:`~.failure.loosened`).

        Parameters
        ----------
        params, guess, warm_start
            As for :meth:`solve`.
        dropped : dict
            Rows of ``g`` to leave out, with their labels.
        """
        self.dropped = dict(dropped)
        try:
            return self._solve(params, guess, warm_start, self.verify)
        finally:
            self.dropped = {}

    def _solve(self, params: dict[str, float] | None, guess: Any,
               warm_start: Solution | None, verify_mode: str,
               expand: bool | None = None, objective_scale: float | None = None) -> Solution:
        params = {} if params is None else params
        pv = self.param_vector(params)
        lbw, ubw, lbg, ubg = self.bounds_at(pv)
        if self.dropped:
            lbg, ubg = loosened(lbg, ubg, list(self.dropped), self.scaling.r)
        args = {"p": pv, "lbx": lbw, "ubx": ubw, "lbg": lbg, "ubg": ubg,
                **self._start(pv, params, guess, warm_start)}
        sc, fref = self._solve_scaling(args, pv, guess, warm_start, objective_scale)
        warm = warm_start is not None and "lam_g0" in args
        sol = self._ipopt(args, sc, fref, warm, expand)
        if not sol.success:
            sol = after_failure(self, sol, args, lambda: self._ipopt(
                args, identity(self.n_w, self.n_g), 1.0, warm, sol.expanded))
        verify(sol, verify_mode, self.verify_tol, self.verify_points)
        return sol

    def _solve_scaling(self, args: dict[str, Any], pv: np.ndarray, guess: Any,
                       warm_start: Solution | None,
                       objective_scale: float | None) -> tuple[Scaling, float]:
        """The scaling and objective scale of a solve from ``args`` (see
        :mod:`ocp.transcriptions.scaled`): a re-solve at its own solution keeps that
        solve's; a solve given ``objective_scale`` (a refinement round), or warm-started
        from a solution of the same problem on another grid at the same parameters, keeps
        the scaling of the solution it starts from; any other is sized from its start."""
        if warm_start is not None and warm_start.transcription is self and \
                np.array_equal(pv, self.param_vector(warm_start.params)) and \
                math.isfinite(warm_start.objective) and math.isfinite(warm_start.objective_scale):
            # a re-solve at its own solution: f, g known finite, and the same NLP as the
            # solve that found it, so its multipliers fit as they are
            return getattr(warm_start, "scaling", self.scaling), warm_start.objective_scale
        x0 = np.asarray(args["x0"], dtype=float)
        f0 = self._check_start(x0, pv)
        start = warm_start if warm_start is not None else guess
        carried = carried_scaling(self, start) if objective_scale is not None else None
        if objective_scale is None and warm_start is not None and \
                math.isfinite(warm_start.objective_scale):
            # a warm start from the same problem on another grid at the same parameters
            # keeps its scaling, as a refinement round keeps its first round's (sized again
            # from such a start, a hop's foot speed of 4.2 got the reference 1e3 of its peak
            # rate times the flight, and its doubled grid another local optimum, 0.06 %
            # above the one solved as posed)
            carried = carried_scaling(self, warm_start)
            if carried is not None and np.array_equal(pv, self.param_vector(warm_start.params)):
                objective_scale = warm_start.objective_scale
            else:
                carried = None
        sc = carried if carried is not None else start_scaling(self, x0, pv)
        fref = objective_scale if objective_scale is not None else \
            sc.objective_scale(f0, self._objective_variation(x0, pv, sc))
        return sc, fref

    def _ipopt(self, args: dict[str, Any], sc: Scaling, fref: float, warm: bool,
               expand: bool | None) -> Solution:
        """Ipopt on the NLP scaled by ``sc`` and ``fref``, from ``args`` (user's units)."""
        graph = graph_of(sc, self.scaling)
        expanded = self._solver(warm, expand, graph)[1]
        call = self._calls[(warm, expanded, graph)]  # Ipopt on numpy arrays, no DM conversions
        t0 = time.perf_counter()
        res = unscale(sc, call.named(scale_args(sc, args, fref, graph)), fref)
        elapsed = time.perf_counter() - t0
        sol = Solution.from_nlp(self, args["p"], res, call.stats(), elapsed)
        sol.objective_scale, sol.expanded, sol.scaling = fref, expanded, sc
        sol.scaling_fallback, sol.dropped = None, list(self.dropped.values())
        return sol

    def bounds_at(self, pv: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(lbw, ubw, lbg, ubg)`` at the parameter values ``pv``, checked (the last
        parameter values' are kept: a re-solve at the same values reuses them).

        Parameters
        ----------
        pv : ndarray
            The parameter values.
        """
        key = pv.tobytes()
        last = self._last_bounds  # (read once: another thread may replace it)
        if last is not None and last[0] == key:
            return last[1]
        b = tuple(np.array(v, dtype=float).ravel() for v in self._bounds(pv))
        self._check_bound_order(*b)
        for a in b:
            a.setflags(write=False)
        self._last_bounds = (key, b)
        return b

    def _check_bound_order(self, lbw: np.ndarray, ubw: np.ndarray, lbg: np.ndarray,
                           ubg: np.ndarray) -> None:
        for lo, hi, what in ((lbw, ubw, "variable"), (lbg, ubg, "constraint")):
            bad = np.flatnonzero(lo > hi)
            if bad.size:
                raise ProblemDefinitionError(
                    f"at these parameter values a {what} lower bound exceeds its upper bound "
                    f"(index {int(bad[0])}: {lo[bad[0]]:g} > {hi[bad[0]]:g})")
