"""The two transcriptions -- multiple shooting and Radau collocation -- and continuation.

Both share the problem definition, the NLP assembly (:mod:`ocp.transcriptions.nlp`) and the
solution type; choose with :func:`transcribe` or by class::

    tr = transcribe(problem, "collocation", intervals=20, degree=3)
    sol = tr.refine(params, tol=1e-7)          # mesh refinement to an accuracy
    ms = MultipleShooting(problem, nodes=100)   # or multiple shooting
    sol = ms.solve(params)

The NLP of a transcription is built once; new parameter values re-solve it
without a rebuild (``n_builds`` stays 1). Mesh refinement builds one NLP per
mesh from the problem compiled once (:class:`ocp.transcriptions.nlp.GridFree`),
and starts a round whose previous mesh was already accurate from that mesh's
solution and multipliers interpolated; the final mesh's transcription is
``sol.transcription``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..definition.errors import ProblemDefinitionError, SolveError
from ..definition.multiphase import MultiPhaseProblem
from ..definition.problem import OptimalControlProblem
from ..definition.symbols import positive_int
from .collocation import CollocationPhase
from .discretization import PhaseDiscretization, segment_index
from .integrators import cvodes_function, rk4_function
from .mesh import mesh_error
from .nlp import DEFAULT_IPOPT, INFEASIBLE_STATUSES, GridFree, Transcription, expand_mode
from .refinement import MeshRefinement, NodeDoubling
from .shooting import ShootingPhase
from .solution import Solution

__all__ = ["DEFAULT_IPOPT", "INFEASIBLE_STATUSES", "Collocation", "MultipleShooting",
           "Transcription", "continuation", "cvodes_function", "decision_bounds",
           "rk4_function", "transcribe"]

Problem = OptimalControlProblem | MultiPhaseProblem


def _per_phase(value: Any, n: int, what: str) -> list[Any]:
    if isinstance(value, Sequence) and not isinstance(value, str):
        if len(value) != n:
            raise ProblemDefinitionError(f"{what}: {len(value)} values for {n} phases")
        return list(value)
    return [value] * n


class MultipleShooting(NodeDoubling, Transcription):
    """Multiple-shooting transcription of an optimal control problem.

    Parameters
    ----------
    problem : OptimalControlProblem or MultiPhaseProblem
        The problem.
    nodes : int or sequence of int
        Number of shooting intervals N (per phase, or one for all), with a
        piecewise-constant control on each.
    integrator : {"rk4", "cvodes"}
        RK4 with ``substeps`` steps per interval, or CVODES (stiff problems).
    substeps : int
        RK4 steps per interval.
    ipopt_options : dict, optional
        Overrides of :data:`DEFAULT_IPOPT`.
    expand : bool or "auto"
        Expand the NLP to SX scalar graphs (RK4 only; True with CVODES is refused):
        building takes longer (0.3-0.5 s instead of 0.05-0.1 s for the soft landing at
        N = 100) but every iteration is 2-3x faster. ``"auto"`` (default) solves the
        first time unexpanded and expands from the second solve of the same kind (from a
        guess, or warm-started) on: a one-off solve does not pay the build, re-solves
        (sweeps, continuation, multistart) get the faster graph.
    inner_constraints : bool
        Also impose path constraints and state bounds at the integrator's
        ``substeps - 1`` inner steps of every interval (default: nodes only).
    verify, verify_tol, verify_points
        The post-solve check between nodes (see :class:`ocp.transcriptions.nlp.Transcription`).
    scaling : {"auto", "none"} or dict
        Scaling of the NLP (see :class:`ocp.transcriptions.nlp.Transcription` and
        :mod:`ocp.definition.scaling`).
    codegen : bool
        Compiled NLP functions (RK4 only; see :class:`ocp.transcriptions.nlp.Transcription`).
    grid_free : GridFree, optional
        Reuse another transcription's compiled problem (:meth:`refine`'s doublings).

    Attributes
    ----------
    n_builds : int
        How many times the NLP was built (stays 1: re-solves never rebuild).
    """

    method = "multiple_shooting"

    def __init__(self, problem: Problem, nodes: int | Sequence[int] = 50,
                 integrator: str = "rk4", substeps: int = 4,
                 ipopt_options: dict | None = None, expand: bool | str = "auto", *,
                 inner_constraints: bool = False, verify: str = "warn",
                 verify_tol: float = 1e-6, verify_points: int = 10,
                 scaling: Any = "auto", codegen: bool = False,
                 grid_free: GridFree | None = None) -> None:
        if integrator not in ("rk4", "cvodes"):
            raise ProblemDefinitionError(f"integrator must be 'rk4' or 'cvodes', got "
                                         f"{integrator!r}")
        if codegen is True and integrator == "cvodes":
            raise ProblemDefinitionError("codegen=True applies to integrator='rk4' (CVODES "
                                         "is a solver CasADi cannot generate C for)")
        n_ph = len(problem.phases) if isinstance(problem, MultiPhaseProblem) else 1
        self.nodes = [positive_int(n, "nodes") for n in _per_phase(nodes, n_ph, "nodes")]
        self.integrator = integrator
        self.substeps = positive_int(substeps, "substeps")
        self.inner_constraints = bool(inner_constraints)
        expand = expand_mode(expand)  # refused before the integrator can ignore it
        if expand is True and integrator == "cvodes":  # ("auto", the default, is RK4's)
            raise ProblemDefinitionError("expand=True applies to integrator='rk4' (CVODES is "
                                         "called as a solver, never expanded to SX)")
        self.scaling_arg = scaling
        super().__init__(problem, ipopt_options, expand if integrator == "rk4" else False,
                         verify, verify_tol, verify_points, scaling, grid_free,
                         codegen=codegen)
        self.N: int | list[int] = self.nodes[0] if n_ph == 1 else list(self.nodes)
        self.F = self.phases[0].F  # type: ignore[attr-defined]

    def _discretize(self) -> list[PhaseDiscretization]:
        return [ShootingPhase(cp, tm, n, self.integrator, self.substeps, self.inner_constraints)
                for cp, tm, n in zip(self.compiled, self.times, self.nodes, strict=True)]

    def with_nodes(self, nodes: list[int], ipopt_options: dict | None = None
                   ) -> MultipleShooting:
        """A new multiple shooting of the same problem and options on other node counts.

        Parameters
        ----------
        nodes : list of int
            Nodes per phase.
        ipopt_options : dict, optional
            Override of the Ipopt options (default: this transcription's).
        """
        return MultipleShooting(self.problem, nodes, self.integrator, self.substeps,
                                ipopt_options or self.ipopt_options, self.expand,
                                inner_constraints=self.inner_constraints, verify=self.verify,
                                verify_tol=self.verify_tol, verify_points=self.verify_points,
                                scaling=self.scaling_arg, codegen=self.codegen,
                                grid_free=self.grid_free)

    def initial_guess(self, T: float | None = None, x: Any = None, u: Any = None,
                      params: dict[str, float] | None = None) -> np.ndarray:
        """Decision vector from a final time, states and controls (single phase).

        Parameters
        ----------
        T : float, optional
            Final time (if free).
        x : array (N+1, nx), (nx,) or callable of normalised time in [0, 1], optional
            States at the nodes.
        u : array (N, nu), (nu,) or callable likewise, optional
            Controls on the intervals.
        params : dict, optional
            Parameter values for the defaults of what is not given (see
            :meth:`default_guess`).
        """
        w = self.default_guess(params)
        lay, pr, N = self.layout, self.multiphase.phases[0], self.nodes[0]
        if lay.iT is not None and T is not None:
            w[lay.iT] = T
        s = np.linspace(0, 1, N + 1)
        if x is not None:
            w[lay.iX] = _fill(x, s, pr.nx).ravel()
        if u is not None:
            w[lay.iU] = _fill(u, s[:-1], pr.nu).ravel()
        return w


class Collocation(MeshRefinement, Transcription):
    """Direct collocation on Legendre-Gauss-Radau points, with mesh refinement.

    Parameters
    ----------
    problem : OptimalControlProblem or MultiPhaseProblem
        The problem.
    intervals : int or sequence of int
        Number of (equal) mesh intervals per phase.
    degree : int
        Collocation points per interval (state polynomial degree); 3 gives
        order 5 at the mesh points.
    mesh : array or sequence of arrays, optional
        Normalised mesh points in [0, 1] per phase (overrides ``intervals``).
    ipopt_options : dict, optional
        Overrides of :data:`DEFAULT_IPOPT`.
    expand : bool or "auto"
        Expand the NLP to SX (default True: collocation graphs are small; ``"auto"`` as
        in :class:`MultipleShooting`).
    verify, verify_tol, verify_points
        The post-solve check between nodes (see :class:`ocp.transcriptions.nlp.Transcription`).
    scaling : {"auto", "none"} or dict
        Scaling of the NLP (see :class:`ocp.transcriptions.nlp.Transcription` and
        :mod:`ocp.definition.scaling`).
    grid_free : GridFree, optional
        Reuse another transcription's compiled problem (see
        :class:`ocp.transcriptions.nlp.Transcription`).
    codegen : bool
        Compiled NLP functions (see :class:`ocp.transcriptions.nlp.Transcription`;
        not with :meth:`refine`, which builds an NLP per mesh).
    inner_constraints : bool or sequence of bool arrays
        Also impose the path constraints and state bounds between the collocation
        points, at the midpoints between the state polynomial's nodes (``degree``
        more points per interval; see
        :class:`ocp.transcriptions.collocation.CollocationPhase`): True on every
        interval, or per phase one flag per mesh interval. :meth:`refine` adds them
        by itself on the intervals where it found a violation between the points.

    Notes
    -----
    Every solution carries ``mesh_error``, the largest interval error
    estimate of :mod:`ocp.transcriptions.mesh` (relative; compare it with the accuracy you
    need, or call :meth:`refine`; computed when first read, so a re-solve that does
    not read it does not pay for it), and ``objective_error``, the estimate of
    the objective's error (NaN after one solve: it needs two meshes; see
    :meth:`refine`).
    """

    method = "collocation"

    def __init__(self, problem: Problem, intervals: int | Sequence[int] = 20, degree: int = 3,
                 mesh: Any = None, ipopt_options: dict | None = None,
                 expand: bool | str = True, *,
                 verify: str = "warn", verify_tol: float = 1e-6,
                 verify_points: int = 10, scaling: Any = "auto",
                 grid_free: GridFree | None = None, codegen: bool = False,
                 inner_constraints: bool | Sequence[Any] = False) -> None:
        n_ph = len(problem.phases) if isinstance(problem, MultiPhaseProblem) else 1
        self.scaling_arg = scaling
        self.degree = positive_int(degree, "degree")
        if mesh is None:
            ns = [positive_int(n, "intervals") for n in _per_phase(intervals, n_ph,
                                                                   "intervals")]
            self.meshes = [np.linspace(0.0, 1.0, n + 1) for n in ns]
        else:
            meshes = [mesh] if n_ph == 1 and np.ndim(mesh[0]) == 0 else list(mesh)
            self.meshes = [_check_mesh(m) for m in _per_phase(meshes, n_ph, "mesh")]
        self.inner = _inner_flags(inner_constraints, self.meshes)
        super().__init__(problem, ipopt_options, expand, verify, verify_tol, verify_points,
                         scaling, grid_free, codegen=codegen)
        counts = [m.size - 1 for m in self.meshes]
        self.N: int | list[int] = counts[0] if n_ph == 1 else counts

    def _discretize(self) -> list[PhaseDiscretization]:
        return [CollocationPhase(cp, tm, m, self.degree, self.grid_free.functions, inner)
                for cp, tm, m, inner in zip(self.compiled, self.times, self.meshes,
                                            self.inner, strict=True)]

    def _solve(self, params: dict[str, float] | None, guess: Any,
               warm_start: Solution | None, verify_mode: str,
               expand: bool | None = None, objective_scale: float | None = None) -> Solution:
        """Solve, and attach the discretisation error estimate (``sol.mesh_error``)."""
        sol = super()._solve(params, guess, warm_start, verify_mode, expand, objective_scale)
        sol.defer("mesh_error", mesh_error)  # computed when read (a re-solve need not pay)
        sol.objective_error = math.nan  # one mesh: nothing to compare the objective with
        return sol

    def with_mesh(self, meshes: list[np.ndarray], verify: str | None = None,
                  inner: list[np.ndarray] | None = None,
                  ipopt_options: dict | None = None) -> Collocation:
        """A new collocation of the same problem and options on other meshes.

        Parameters
        ----------
        meshes : list of ndarray
            Normalised mesh points per phase.
        verify : str, optional
            Override of the post-solve check mode.
        inner : list of ndarray, optional
            Per phase, the intervals with constraints between the points (default: those
            inside an interval of this mesh that has them).
        ipopt_options : dict, optional
            Override of the Ipopt options (default: this transcription's).
        """
        if inner is None:
            inner = [old[segment_index(m_old, 0.5 * (m[1:] + m[:-1]))]
                     for old, m_old, m in zip(self.inner, self.meshes, meshes, strict=True)]
        return Collocation(self.problem, degree=self.degree, mesh=meshes,
                           ipopt_options=ipopt_options or self.ipopt_options,
                           expand=self.expand, verify=verify or self.verify,
                           verify_tol=self.verify_tol, verify_points=self.verify_points,
                           scaling=self.scaling_arg, grid_free=self.grid_free,
                           codegen=self.codegen, inner_constraints=inner)


def transcribe(problem: Problem, method: str = "multiple_shooting", **options: Any
               ) -> Transcription:
    """A transcription of ``problem`` by ``method`` ("multiple_shooting" or "collocation").

    Parameters
    ----------
    problem : OptimalControlProblem or MultiPhaseProblem
        The problem.
    method : str
        ``"multiple_shooting"`` (alias ``"ms"``) or ``"collocation"`` (alias ``"radau"``).
    **options
        Passed to :class:`MultipleShooting` or :class:`Collocation`.
    """
    m = method.lower()
    if m in ("multiple_shooting", "ms", "shooting"):
        return MultipleShooting(problem, **options)
    if m in ("collocation", "radau", "lgr"):
        return Collocation(problem, **options)
    raise ProblemDefinitionError(f"method must be 'multiple_shooting' or 'collocation', got "
                                 f"{method!r}")


def decision_bounds(transcription: Transcription, params: dict[str, float] | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of a transcription's decision vector at these parameter values.

    Parameters
    ----------
    transcription : Transcription
        A multiple-shooting or collocation transcription.
    params : dict, optional
        Parameter values (every declared parameter).
    """
    pv = transcription.param_vector({} if params is None else params)
    lbw, ubw = transcription.bounds_function(pv)[:2]
    return np.array(lbw, dtype=float).ravel(), np.array(ubw, dtype=float).ravel()


def _inner_flags(spec: Any, meshes: list[np.ndarray]) -> list[np.ndarray]:
    """Per phase, the intervals with constraints between the points (``inner_constraints``)."""
    if isinstance(spec, bool | np.bool_):
        return [np.full(m.size - 1, bool(spec)) for m in meshes]
    flags = [np.asarray(f) for f in spec] if isinstance(spec, Sequence) else None
    if flags is None or len(flags) != len(meshes) or any(
            f.dtype != bool or f.shape != (m.size - 1,) for f, m in zip(flags, meshes,
                                                                        strict=True)):
        raise ProblemDefinitionError("inner_constraints must be True, False or, per phase, "
                                     "one bool per mesh interval")
    return flags


def _check_mesh(mesh: Any) -> np.ndarray:
    m = np.asarray(mesh, dtype=float).ravel()
    if m.size < 2 or m[0] != 0.0 or m[-1] != 1.0 or np.any(np.diff(m) <= 0):
        raise ProblemDefinitionError("mesh must increase strictly from 0 to 1")
    return m


def _fill(spec: Any, s: np.ndarray, n: int) -> np.ndarray:
    if spec is None:
        return np.zeros((len(s), n))
    if callable(spec):
        return np.array([np.ravel(spec(si)) for si in s], dtype=float).reshape(len(s), n)
    a = np.asarray(spec, dtype=float)
    if a.ndim == 1:
        return np.tile(a.reshape(1, n), (len(s), 1))
    if a.shape != (len(s), n):
        raise ValueError(f"guess has shape {a.shape}, expected {(len(s), n)}")
    return a


def continuation(transcription: Transcription, params: dict[str, float], name: str,
                 values: Any, guess: Solution | np.ndarray | None = None,
                 progress: bool = False) -> list[Solution]:
    """Solve along ``values`` of one parameter, each solve warm-started from the last.

    If a warm-started solve fails, it is retried once from the previous primal
    point only (a cold start), then the error is raised.

    Parameters
    ----------
    transcription : Transcription
        A multiple-shooting or collocation transcription.
    params : dict
        Values of the other parameters.
    name : str
        The parameter to vary.
    values : iterable of float
        Its values, in order.
    guess : Solution or decision vector, optional
        Start of the first solve.
    progress : bool
        Show a progress bar (tqdm).
    """
    out: list[Solution] = []
    prev = guess if isinstance(guess, Solution) else None
    first_guess = guess
    it = values
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(values, desc=f"continuation in {name}", unit="solve")
    for v in it:
        pv = {**params, name: float(v)}
        if prev is None:
            sol = transcription.solve(pv, guess=first_guess)
        else:
            try:
                sol = transcription.solve(pv, warm_start=prev)
            except SolveError:
                sol = transcription.solve(pv, guess=prev)
        out.append(sol)
        prev = sol
    return out
