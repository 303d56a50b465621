"""Bang-bang and boundary-arc structure, and switching times refined to machine precision.

The pieces live in three modules; this one is the entry point:

* :mod:`ocp.structure.arcs` -- :func:`detect_arcs` (one control) and :func:`detect_structure`
  (every control, switch events merged) read the arc structure off a
  transcribed solution: bang arcs ``"max"``/``"min"``, boundary arcs (a path
  constraint held at a limit) and interior arcs;
* :mod:`ocp.structure.flows` -- the closed-loop dynamics of an arc (boundary control
  laws from the constraint's derivatives along the dynamics), exact
  matrix-exponential and fixed-step 8th-order Runge-Kutta flows;
* :mod:`ocp.structure.refinement` -- the switching-time NLP, built once per problem and
  structure and reused for every parameter value.

:func:`refine_switching` solves that NLP from a transcribed solution and
returns a :class:`RefinedSwitching`. Example (minimum-time double integrator)::

    sol = MultipleShooting(p, nodes=40).solve({"d": 2.0})
    r = refine_switching(sol)           # kinds ['max', 'min'], T = 2 sqrt(2) to 1e-15
    traj = r.trajectory(n=500)          # ocp.definition.trajectory.Trajectory, mode = arc kind

Several controls: each control has its own arcs; the unknowns are the
durations of the intervals between consecutive switch events of any control
(``r.kinds`` then lists one kind per control and interval).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import InfeasibleError, ProblemDefinitionError, SolveError
from ..definition.problem import OptimalControlProblem
from ..definition.symbols import positive_int, relative_tolerance
from ..definition.trajectory import Trajectory
from ..transcriptions.gridview import grid_spacing
from ..transcriptions.solution import along
from .arcs import (
    Arc,
    ArcStructure,
    Interval,
    SolutionLike,
    SwitchingStructure,
    TranscribedSolution,
    active_path_constraints,
    control_bounds_at,
    detect_arcs,
    detect_structure,
    path_activity,
    transcribed,
)
from .costate_copies import costate_guess, costates_as_states
from .flows import Mode, has_running_cost, numeric_affine_flow, numeric_rk8_flow
from .interior_arcs import refinable_arcs
from .refinement import (
    DEFAULT_TOL,
    REFINE_IPOPT,
    SwitchingNLP,
    arc_dynamics,
    check_control_set,
    clear_cache,
    refuse_shifted_time,
    required_substeps,
    rk8_of,
    solved_nlp,
    switching_nlp,
)
from .variables import variables_as_states

__all__ = [
    "Arc", "ArcStructure", "DEFAULT_TOL", "Interval", "Mode", "REFINE_IPOPT", "RefinedSwitching",
    "SwitchingNLP", "SwitchingStructure", "active_path_constraints", "clear_cache",
    "control_bounds_at", "detect_arcs", "detect_structure", "note_above_transcription",
    "path_activity", "refine_switching", "refine_structure",
]


@dataclass
class RefinedSwitching:
    """Switching times and arcs refined to machine precision.

    Attributes
    ----------
    kinds : list
        Per interval: the arc kind (``"max"``, ``"min"``, ``"boundary"``,
        ``"vertex"``) for a single-control problem, a tuple of kinds (one per
        control) otherwise.
    values : list
        Per interval: the control value (a tuple for several controls); NaN
        where the control follows a boundary law (see :attr:`control_laws`).
        On a vertex arc, the value the control-only constraint fixes.
    modes : tuple of tuple of Mode
        Per interval, each control's :class:`~ocp.structure.flows.Mode` (with the held constraint).
    durations : ndarray
        Interval lengths; ``switch_times`` are the times between them.
    T, objective : float
        Final time and refined objective.
    x0, xT : ndarray
        Initial and final states.
    exact : bool
        Every interval integrated by the matrix exponential (affine arcs).
    integration_error : float
        Largest relative end-state error of the RK8 intervals, estimated by
        halving at the solution (0 when every interval is exact).
    status, iterations, solve_time : Ipopt's figures (or the Newton fast path's).
        ``status`` says ``"Solve_Succeeded (KKT residual ...; Ipopt said ...)"`` when Ipopt
        stopped on another message at a point our own KKT check accepts
        (:func:`ocp.structure.refinement.kkt_converged`).
    success : bool
        Converged to the requested accuracy (False on the iterate of a
        :class:`~ocp.definition.errors.SolveError`: :func:`ocp.certify` refuses it).
    path : str
        ``"ipopt"`` or ``"newton"`` (the fast path): what produced the result.
    transcribed_objective : float
        The objective of the solution it started from.
    terminal_multipliers : ndarray
        Multipliers of the terminal constraints (CasADi sign: ``J + nu^T G``).
    terminal_costate : (ndarray, float or None) or None
        ``(lambda(T), H expected)`` when the transversality conditions come from
        elsewhere (a phase of a multi-phase problem, :mod:`ocp.structure.phase_refinement`);
        None: from this problem's own terminal constraints and Mayer term.
    notes : list of str
        E.g. intervals that shrank to zero length, rebuilds for accuracy.
    problem, params
        The problem and parameter values refined.
    variables : dict
        The decision variables' refined values (refined together with the switching
        times: ``problem`` is then :func:`ocp.structure.variables.variables_as_states` of
        ``origin``, or :func:`~ocp.structure.variables.phase_variables_as_states` of a
        phase, the variables its last states; a phase's result has them also when its
        problem does not involve them).
    origin : OptimalControlProblem or None
        The problem (or phase) as the user wrote it, when ``problem`` was derived from it.
    control, controls
        The (first) control's name and every control's name.
    lam_g, lam_x : ndarray
        The refinement NLP's multipliers.
    blocks : dict
        Constraint name -> rows of the refinement NLP.
    end_path_violation : float
        Path-constraint violation at the arcs' ends.
    build_time : float
        Time to build the refinement NLP.
    nlp : SwitchingNLP
        The refinement NLP.
    w : ndarray
        Its solution.
    """

    problem: OptimalControlProblem
    params: dict
    control: str
    kinds: list
    values: list
    durations: np.ndarray
    T: float
    objective: float
    x0: np.ndarray
    xT: np.ndarray
    exact: bool
    status: str
    iterations: int
    solve_time: float
    transcribed_objective: float
    lam_g: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    blocks: dict = field(repr=False, default_factory=dict)
    end_path_violation: float = 0.0
    modes: tuple = field(repr=False, default=())
    controls: tuple[str, ...] = ()
    integration_error: float = 0.0
    path: str = "ipopt"
    notes: list[str] = field(default_factory=list)
    build_time: float = 0.0
    nlp: SwitchingNLP | None = field(repr=False, default=None)
    w: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    lam_x: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    terminal_costate: tuple[np.ndarray, float | None] | None = field(repr=False, default=None)
    success: bool = True
    variables: dict[str, float] = field(default_factory=dict)
    origin: OptimalControlProblem | None = field(repr=False, default=None)

    # ------------------------------------------------------------- structure
    @property
    def switch_times(self) -> list[float]:
        """Times between consecutive intervals (switch events of any control)."""
        return [float(t) for t in np.cumsum(self.durations)[:-1]]

    @property
    def pv(self) -> np.ndarray:
        """Parameter vector in the problem's order."""
        return np.array([self.params[k] for k in self.problem.param_names], dtype=float)

    @property
    def terminal_multipliers(self) -> np.ndarray:
        """Multipliers of the terminal constraints."""
        idx = self.blocks.get("terminal", np.zeros(0, dtype=int))
        return self.lam_g[np.asarray(idx, dtype=int)] if len(self.lam_g) else np.zeros(0)

    def switch_times_of(self, control: str) -> list[float]:
        """Switch times of one control (its own arc boundaries).

        Parameters
        ----------
        control : str
            Control name.
        """
        j = self.controls.index(control)
        edges = np.cumsum(self.durations)[:-1]
        return [float(edges[k]) for k in range(len(self.modes) - 1)
                if self.modes[k][j] != self.modes[k + 1][j]]

    @property
    def control_laws(self) -> list[dict[str, Any] | None]:
        """Per interval: None on bang intervals, else the boundary control law.

        Each entry has ``controls`` (names), ``constraints`` (held, with side and
        relative degree), ``expression`` (CasADi text of ``u(x, p)``) and, when
        the law is affine in the state, ``gain`` K and ``offset`` k0 with
        ``u = K x + k0`` at this solution's parameters (a replay can use them).
        With decision variables refined as constant states (:attr:`origin`), ``x``
        is the origin's states and k0 holds the variables' part at their values.
        """
        nx = self.origin.nx if self.origin is not None else self.problem.nx
        out: list[dict[str, Any] | None] = []
        for modes in self.modes:
            if all(m.kind != "boundary" for m in modes):
                out.append(None)
                continue
            d = arc_dynamics(self.problem, modes)
            aff = d.control_law_affine(self.pv)
            names = [c for c, m in zip(self.controls, modes, strict=True) if m.kind == "boundary"]
            idx = [self.controls.index(c) for c in names]
            entry: dict[str, Any] = {
                "controls": names,
                "constraints": [{"name": m.constraint, "side": m.side,
                                 "relative_degree": d.orders[m.constraint]}
                                for m in modes if m.constraint is not None],
                "expression": [str(d.u[i]) for i in idx]}
            if aff is not None:
                K, k0 = aff[0][idx], aff[1][idx] + aff[0][idx][:, nx:] @ self.x0[nx:]
                entry["gain"] = K[:, :nx].tolist()
                entry["offset"] = k0.tolist()
            out.append(entry)
        return out

    # --------------------------------------------------------------- samples
    @property
    def interval_modes(self) -> tuple[tuple[Mode, ...], ...]:
        """Per interval, each control's mode, read off :attr:`values` where they are bang
        values (so a copy with edited ``values`` describes what its values say)."""
        out = []
        for k, modes in enumerate(self.modes):
            vals = self.values[k] if len(self.controls) != 1 else (self.values[k],)
            ms = []
            for name, m, v in zip(self.controls, modes, vals, strict=True):
                lo, hi = control_bounds_at(self.problem, name, {**self.params,
                                                                **self.variables})
                if m.kind in ("max", "min") and np.isfinite(v):
                    m = Mode("max") if abs(v - hi) <= abs(v - lo) else Mode("min")
                ms.append(m)
            out.append(tuple(ms))
        return tuple(out)

    def rk8_steps(self, k: int) -> int:
        """RK8 steps of interval ``k`` in the refinement (64 where it has none), for the flows
        of non-affine arcs.

        Parameters
        ----------
        k : int
            The interval.
        """
        if self.nlp is not None and k < len(self.nlp.substeps):
            return int(self.nlp.substeps[k])
        return 64

    def _flow(self, k: int, modes: tuple[Mode, ...], z: np.ndarray, tau: float,
              points: int) -> np.ndarray:
        d = arc_dynamics(self.problem, modes)
        if d.exact:
            A, b = d.affine_numeric(self.pv)
            return numeric_affine_flow(A, b, z, tau, points)
        per = max(1, -(-self.rk8_steps(k) // points))
        return numeric_rk8_flow(rk8_of(d), z, tau, per * points, self.pv)[::per]

    def junctions(self) -> np.ndarray:
        """States (with the running cost's quadrature, if any) at the interval ends, (K+1, nz),
        propagated from :attr:`x0` over :attr:`durations`."""
        z = np.r_[self.x0, 0.0] if has_running_cost(self.problem) else self.x0.copy()
        out = [z]
        for k, modes in enumerate(self.interval_modes):
            z = self._flow(k, modes, z, float(self.durations[k]), 1)[-1]
            out.append(z)
        return np.array(out)

    def samples(self, n: int = 1000, focus: tuple[int, int] | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Times, states, controls and interval index, sampled arc by arc (exact arcs exact).

        Junction times appear twice: the end of one interval and the start of the next.

        Parameters
        ----------
        n : int
            About how many sample points (default 1000).
        focus : (int, int), optional
            Intervals ``first..last`` (inclusive) that get about ``n`` points between them,
            whatever their share of the horizon (a short arc checked closely); the others
            keep their share of ``n``.
        """
        pr = self.problem
        ts, xs, us, ks = [], [], [], []
        z = np.r_[self.x0, 0.0] if has_running_cost(pr) else self.x0.copy()
        start = 0.0
        T = float(np.sum(self.durations))
        span = T if focus is None else float(np.sum(self.durations[focus[0]:focus[1] + 1]))
        for k, modes in enumerate(self.interval_modes):
            tau = float(self.durations[k])
            whole = span if focus and focus[0] <= k <= focus[1] else T
            pts = max(2, int(math.ceil(n * tau / max(whole, 1e-300))))  # (n * tau first: as
            # before focus, to the last bit: a sample more or less moves a check's maximum)
            Z = self._flow(k, modes, z, tau, pts)
            U = along(arc_dynamics(pr, modes).u_fn, Z[:, :pr.nx], self.pv)[0]
            ts.append(start + np.linspace(0.0, tau, pts + 1))
            xs.append(Z[:, :pr.nx])
            us.append(U)
            ks.append(np.full(pts + 1, k))
            z = Z[-1]
            start += tau
        return np.concatenate(ts), np.vstack(xs), np.vstack(us), np.concatenate(ks)

    def trajectory(self, n: int = 1000) -> Trajectory:
        """The refined trajectory on about ``n`` points (mode = arc kind per sample).

        Parameters
        ----------
        n : int
            About how many sample points (default 1000).
        """
        t, x, u, k = self.samples(n)
        labels = ["/".join(m.label() for m in modes) for modes in self.modes]
        pr = self.problem
        return Trajectory(t, x, u, tuple(pr.state_names), tuple(pr.control_names),
                          mode=np.array([labels[i] for i in k]))

    def sample(self, n: int = 1000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``t, x, u`` on about ``n`` points (``u`` 1-D for a single control).

        Parameters
        ----------
        n : int
            About how many sample points (default 1000).
        """
        t, x, u, _ = self.samples(n)
        return t, x, (u[:, 0] if u.shape[1] == 1 else u)

    def control_at(self, t: np.ndarray) -> np.ndarray:
        """Bang values at times ``t`` (NaN on boundary intervals, whose control depends on x).

        Parameters
        ----------
        t : ndarray
            Times.
        """
        edges = np.cumsum(self.durations)
        idx = np.minimum(np.searchsorted(edges, t, side="right"), len(self.values) - 1)
        return np.asarray(self.values, dtype=float)[idx]

    def path_violation(self, n: int = 4000) -> float:
        """Largest violation of any path constraint or control bound on about ``n`` points.

        Parameters
        ----------
        n : int
            About how many sample points (default 4000).
        """
        pr = self.problem
        t, x, u, _ = self.samples(n)
        viol = 0.0
        cons = [(c.expr, c.lower, c.upper) for c in pr.structure_path]
        cons += [(pr.u[j], *pr.control_limits[nm]) for j, nm in enumerate(pr.control_names)]
        for e, lo, hi in cons:
            fn = ca.Function("c", [pr.x, pr.u, pr.p], [e, lo, hi])
            v, a, b = along(fn, x, u, self.pv)
            scale = np.maximum(1.0, np.abs(v))
            viol = max(viol, float(np.max(np.r_[(a - v) / scale, (v - b) / scale, [[0.0]]])))
        return viol

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict."""
        def clean(v: Any) -> Any:
            if isinstance(v, tuple | list):
                return [clean(x) for x in v]
            return float(v) if isinstance(v, float | np.floating) and math.isfinite(v) else (
                None if isinstance(v, float | np.floating) else v)

        return {"arcs": clean(self.kinds), "values": clean(self.values),
                "durations": self.durations.tolist(), "switch_times": self.switch_times,
                "T": self.T, "objective": self.objective, "x0": self.x0.tolist(),
                "xT": self.xT.tolist(), "exact_arcs": self.exact, "status": self.status,
                "iterations": self.iterations, "solve_time_s": self.solve_time,
                "transcribed_objective": self.transcribed_objective,
                "end_path_violation": self.end_path_violation,
                "controls": list(self.controls),
                "modes": [[m.label() for m in ms] for ms in self.modes],
                "control_laws": self.control_laws, "integration_error": self.integration_error,
                "path": self.path, "notes": self.notes, "success": self.success}


# ------------------------------------------------------------------ refine
def _as_structure(sol: TranscribedSolution, structure: Any) -> ArcStructure:
    if structure is None:
        structure = detect_structure(sol)
    if isinstance(structure, SwitchingStructure):
        if sol.problem.nu != 1:
            raise ValueError("a SwitchingStructure describes one control; pass an ArcStructure "
                             "(detect_structure) for a problem with several controls")
        structure = ArcStructure.from_controls([structure])
    # interior arcs: singular, or regular with costate copies (or a ValueError)
    return refinable_arcs(sol.problem, structure)


def insert_extra_arcs(modes: list, durs: list, extra_arcs: int) -> None:
    """Insert ``extra_arcs`` bang arcs (single control): pairs inside the longest bang arc,
    an odd one at the end.

    Used by :func:`refine_switching` and :func:`ocp.structure.phase_refinement.refine_phases` to
    start a refinement with more arcs than the transcription shows.

    Parameters
    ----------
    modes : list of tuple of Mode
        Per interval, its (single) mode; modified in place.
    durs : list of float
        Per interval, its duration; modified in place (the total is kept).
    extra_arcs : int
        How many arcs to insert.

    Raises
    ------
    ValueError
        If ``extra_arcs`` is not 0 and the structure has no bang arc.
    """
    flip = {"max": Mode("min"), "min": Mode("max")}
    if extra_arcs and not any(m[0].kind in flip for m in modes):
        raise ValueError(f"extra_arcs={extra_arcs}: the structure has no bang arc to insert "
                         f"them beside (its arcs: {', '.join(m[0].kind for m in modes)})")
    for _ in range(extra_arcs // 2):
        bang = [k for k, m in enumerate(modes) if m[0].kind in flip]
        i = max(bang, key=lambda k: durs[k])
        d = durs[i]
        modes[i:i + 1] = [modes[i], (flip[modes[i][0].kind],), modes[i]]
        durs[i:i + 1] = [0.495 * d, 0.01 * d, 0.495 * d]
    if extra_arcs % 2:
        last = [k for k, m in enumerate(modes) if m[0].kind in flip][-1]
        modes.append((flip[modes[last][0].kind],))
        cut = 0.01 * durs[-1]
        durs[-1] -= cut
        durs.append(cut)


def refine_switching(sol: SolutionLike, structure: SwitchingStructure | ArcStructure | None = None,
                     extra_arcs: int = 0, interior_samples: int = 16,
                     ipopt_options: dict | None = None, *, tol: float = DEFAULT_TOL,
                     params: dict[str, float] | None = None, fast: bool = True,
                     repair: bool = True,
                     repair_length: float | None = None) -> RefinedSwitching:
    """Re-solve with the interval durations as unknowns and the controls on their arcs.

    Parameters
    ----------
    sol : Solution
        A transcribed solution (parameters, bounds and starting guess).
    structure : SwitchingStructure or ArcStructure, optional
        Default: :func:`detect_structure` of ``sol``. Its interior arcs are refined as
        singular arcs where the control enters H linearly with a singular order
        (:func:`ocp.structure.interior_arcs.refinable_arcs`); regular interior arcs are
        flown with ``H_u = 0`` and the costate as extra states
        (:mod:`ocp.structure.costate_copies`).
    extra_arcs : int
        Single control only: try this many more bang arcs, to test whether more
        switches improve the objective (pairs are inserted inside the longest
        bang arc, an odd one is appended at the end).
    interior_samples : int
        Path constraints are imposed at about this many points inside each interval.
    ipopt_options : dict, optional
        Overrides of :data:`REFINE_IPOPT`.
    tol : float
        Relative accuracy required of the non-affine (RK8) intervals' end states,
        verified by halving at the solution (more steps and a re-solve if not met).
    params : dict, optional
        Parameter values that differ from ``sol.params`` (the others are the solution's;
        a name that is not a parameter is refused).
    fast : bool
        Try the Newton fast path first when the cached NLP was solved before
        with a square active set (falls back to Ipopt if a check fails).
    repair : bool
        If the detected structure fails, retry without each arc shorter than
        ``repair_length`` (default 2.5 shooting or mesh intervals) in turn, keeping the
        best success (a note says which arc was dropped).
    repair_length : float, optional
        See ``repair``.

    Raises
    ------
    ValueError
        If the structure has an interior arc that is not singular (a control that enters
        H nonlinearly, or has no singular order).
    SolveError, InfeasibleError
        If Ipopt fails, or the integration accuracy cannot be reached.
    """
    if getattr(sol, "is_multiphase", False):
        raise ValueError("a multi-phase solution is refined phase by phase with "
                         "ocp.structure.phase_refinement.refine_phases(sol)")
    tsol = transcribed(sol)
    refuse_shifted_time(tsol.problem)
    tol = relative_tolerance(tol, "refine_switching(tol)")
    interior_samples = positive_int(interior_samples, "refine_switching(interior_samples)")
    extra_arcs = positive_int(extra_arcs, "refine_switching(extra_arcs)", minimum=0)
    unknown = sorted(set(params or {}) - set(tsol.problem.param_names))
    if unknown:  # (ignored, a misspelt name left its parameter at the solution's value)
        raise ProblemDefinitionError(f"refine_switching(params): {unknown} are not parameters "
                                     f"of the problem ({sorted(tsol.problem.param_names)})")
    st = _as_structure(tsol, structure)
    params = {**tsol.params, **(params or {})}
    opts: dict[str, Any] = {"transcribed_objective": float(tsol.objective),
                            "interior_samples": interior_samples,
                            "ipopt_options": ipopt_options, "tol": tol, "fast": fast}

    pr, x0 = tsol.problem, np.asarray(tsol.x[0], dtype=float)
    if pr.nv or pr.boundary or not ca.SX(pr.boundary_cost).is_zero():
        # decision variables: refined with the switching times, as constant states; end-point
        # terms (p.minimize, boundary_constraint) read at T (refused if they cannot be)
        pr = variables_as_states(tsol.problem)
        x0 = np.r_[x0, [float(tsol.variables[n]) for n in tsol.problem.var_names]]

    def attempt(s: ArcStructure) -> RefinedSwitching:
        s = refinable_arcs(tsol.problem, s)
        modes, durs = list(s.modes), list(s.durations)
        if extra_arcs:
            if len(s.controls) != 1:
                raise ValueError("extra_arcs supports single-control problems")
            insert_extra_arcs(modes, durs, extra_arcs)
        starts = [iv.start for k, iv in enumerate(s.intervals) if any(
            m.kind == "interior" for m in iv.modes) and (k == 0 or all(
                m.kind != "interior" for m in s.intervals[k - 1].modes))]
        if starts:  # regular interior arcs: a costate copy per run, from the transcription's
            return refine_structure(costates_as_states(pr, len(starts)), tuple(modes),
                                    np.asarray(durs, dtype=float),
                                    np.r_[x0, costate_guess(tsol, starts)], params, **opts)
        out = refine_structure(pr, tuple(modes), np.asarray(durs, dtype=float), x0, params,
                               **opts)
        if pr is not tsol.problem:
            nx = tsol.problem.nx
            out.origin = tsol.problem
            out.variables = dict(zip(tsol.problem.var_names, map(float, out.x0[nx:]),
                                     strict=True))
        return out

    try:
        out = attempt(st)
    except SolveError as err:
        if repair_length is None and not repair:
            raise
        # 2.5 shooting intervals, or mesh intervals of a collocation solution
        short = 2.5 * grid_spacing(tsol) if repair_length is None else repair_length
        out = _repair(st, attempt, err, short)
    if params == tsol.params:
        note_above_transcription(out, float(tsol.objective))
    return out


ABOVE = 1e-3
"""A refined objective above the transcription's by more than this (relative) is noted."""


def note_above_transcription(out: RefinedSwitching, transcribed: float) -> None:
    """Note on ``out`` a refined objective well above the transcription's it started from.

    The exact arcs' objective is normally at or below the grid's (the grid holds the control
    piecewise constant); well above it, the detected structure likely misses an arc the grid
    resolves (an oscillator's short first arc: 7.4502 refined against 7.4102 transcribed),
    and the refined candidate is not the better one: said, not hidden.

    Parameters
    ----------
    out : RefinedSwitching
        The refinement (its ``notes`` extended).
    transcribed : float
        The transcription's objective at the same parameters.
    """
    gap = float(out.objective) - transcribed
    if math.isfinite(gap) and gap > ABOVE * max(1.0, abs(transcribed)):
        out.notes.append(f"the refined objective {out.objective:.10g} is above the "
                         f"transcription's {transcribed:.10g} (by {gap:.3g}): the detected "
                         "structure may lack an arc the grid resolves (compare a finer grid, "
                         "or extra_arcs)")


def _without_arc(st: ArcStructure, j: int, i: int) -> ArcStructure:
    """The structure with arc i of control j removed (its time given to its neighbours)."""
    per = list(st.per_control)
    arcs = [Arc(a.kind, a.start, a.end, a.active, a.constraint, a.side) for a in per[j].arcs]
    gone = arcs.pop(i)
    if 0 < i < len(arcs) and arcs[i - 1].mode_key() == arcs[i].mode_key():
        arcs[i - 1].end = arcs[i].end
        del arcs[i]
    elif i > 0:
        mid = 0.5 * (gone.start + gone.end)
        arcs[i - 1].end = mid if i < len(arcs) else gone.end
        if i < len(arcs):
            arcs[i].start = mid
    else:
        arcs[0].start = gone.start
    per[j] = SwitchingStructure(per[j].control, arcs, per[j].lower, per[j].upper)
    return ArcStructure.from_controls(per)


def _repair(st: ArcStructure, attempt: Any, err: SolveError, short: float) -> RefinedSwitching:
    """Retry without one short arc at a time (a grid artefact, e.g. the zig-zag of the
    transcription next to a boundary arc); keep the best success, else re-raise ``err``."""
    best: RefinedSwitching | None = None
    tried = []
    for j, s in enumerate(st.per_control):
        for i, a in enumerate(s.arcs):
            if a.duration > short or len(s.arcs) < 2:
                continue
            tried.append(f"{s.control} arc {i} ({a.kind}, {a.duration:.3g} long)")
            try:
                r = attempt(_without_arc(st, j, i))
            except SolveError:
                continue
            if best is None or r.objective < best.objective:
                best = r
                best.notes.append(f"the detected structure failed ({err.status}); refined "
                                  f"without {tried[-1]}, a transcription artefact")
    if best is None:
        raise err
    return best


def refine_structure(problem: OptimalControlProblem, modes: tuple, durations: np.ndarray,
                     x0: np.ndarray, params: dict[str, float], *,
                     transcribed_objective: float = math.nan, interior_samples: int = 16,
                     ipopt_options: dict | None = None, tol: float = DEFAULT_TOL,
                     fast: bool = True, max_rebuilds: int = 4,
                     ipopt: bool = True) -> RefinedSwitching:
    """Refine a given interval structure from a guess of durations and initial state.

    The workhorse of :func:`refine_switching`, usable without a transcription
    (e.g. to re-solve a known structure for new parameter values).

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one :class:`Mode` per control.
    durations : ndarray
        Guessed interval lengths (at least 1e-6 each is used).
    x0 : ndarray
        Guessed initial state.
    params : dict
        A value for every parameter.
    transcribed_objective : float
        Recorded in the result (NaN when there is no transcription).
    interior_samples : int
        Path constraints are imposed at about this many points inside each interval.
    ipopt_options : dict, optional
        Overrides of :data:`REFINE_IPOPT`.
    tol : float
        Relative accuracy required of the RK8 intervals' end states.
    fast : bool
        Try the Newton fast path first (see :meth:`SwitchingNLP.newton`).
    max_rebuilds : int
        How often the step counts may be doubled to meet ``tol``.
    ipopt : bool
        False: the Newton re-solve of an NLP of this structure solved before, and nothing
        else (no build, no Ipopt): about a millisecond, or a :class:`SolveError` with status
        ``"newton_failed"`` (a controller trying several structures within a sample).

    Returns
    -------
    RefinedSwitching

    Raises
    ------
    SolveError, InfeasibleError
        If Ipopt fails, or the accuracy is not reached after ``max_rebuilds``.
    """
    if problem.nv:
        raise ValueError(
            "a problem with decision variables is refined as "
            "ocp.structure.variables.variables_as_states(problem), with the variables' "
            "guesses after the states in x0 (refine_switching does this)")
    pv = np.array([float(params[k]) for k in problem.param_names])
    check_control_set(problem, modes, pv)
    durations = np.maximum(np.asarray(durations, dtype=float), 1e-6)
    w0 = np.r_[durations, x0]
    solved = solved_nlp(problem, modes, interior_samples, ipopt_options) if fast else None
    if solved is not None:  # re-solve the last solved NLP of this structure (re-checked)
        quick = solved.newton(pv, w0)
        if quick is not None:
            ok, err, _ = solved.accuracy(quick["w"], pv, tol)
            if ok:
                return _result(problem, solved, quick, pv, params, transcribed_objective,
                               err, [])
    if not ipopt:
        raise SolveError("newton_failed", message="no Newton re-solve of this structure "
                         "(none solved before, or its active set changed)")
    need = required_substeps(problem, modes, pv, durations, x0, interior_samples, tol)
    notes: list[str] = []
    warm: tuple[np.ndarray, np.ndarray] | tuple[None, None] = (None, None)
    for _ in range(max_rebuilds + 1):
        nlp = switching_nlp(problem, modes, need, interior_samples, ipopt_options)
        fast_res = nlp.newton(pv, w0) if fast else None
        res = fast_res if fast_res is not None else nlp.solve(pv, w0, *warm)
        ok, err, bad = nlp.accuracy(res["w"], pv, tol)
        if ok or not res["success"]:
            break
        notes.append(f"interval(s) {bad} needed more RK8 steps than {nlp.substeps} "
                     f"(error {err:.1e} > {tol:g}); re-solved")
        need = tuple(2 * n if k in bad else n for k, n in enumerate(nlp.substeps))
        w0, warm = res["w"], (res["lam_g"], res["lam_x"])
    out = _result(problem, nlp, res, pv, params, transcribed_objective, err, notes)
    out.success = bool(res["success"] and ok)
    if not res["success"]:
        cls = InfeasibleError if "Infeasible" in out.status else SolveError
        why = ""
        if out.status == "Not_Enough_Degrees_Of_Freedom":
            b = nlp.bounds(pv)
            why = (f": the structure's {len(modes)} interval(s) leave "
                   f"{int(np.sum(b['lbx'] < b['ubx']))} unknowns (durations and free initial "
                   f"states) to {int(np.sum(b['lbg'] == b['ubg']))} equality conditions, so "
                   "its end conditions fix it with nothing left to refine (one arc from a "
                   "start on a switching curve); the transcription's candidate stands, and "
                   "certify(sol) checks it alone")
        raise cls(out.status, out, f"switching-time refinement failed: {out.status}{why}")
    if not ok:
        raise SolveError("Integration_Accuracy_Not_Reached", out,
                         f"switching-time refinement: RK8 error {err:.1e} above tol {tol:g} "
                         f"after {max_rebuilds} rebuilds")
    return out


def _result(pr: OptimalControlProblem, nlp: SwitchingNLP, res: dict, pv: np.ndarray,
            params: dict, transcribed_objective: float, err: float,
            notes: list[str]) -> RefinedSwitching:
    w = res["w"]
    K = nlp.K
    summ = nlp.summary(w, pv)
    xT, T, J, bounds = summ["xT"], summ["T"], summ["J"], summ["control_bounds"]
    single = pr.nu == 1
    values, kinds = [], []
    for modes, d in zip(nlp.modes, nlp.dyns, strict=True):
        vertex = np.array(d.u_fn(np.zeros(pr.nx), pv), dtype=float).ravel() \
            if any(m.kind == "vertex" for m in modes) else None
        vals = [hi if m.kind == "max" else lo if m.kind == "min" else
                float(vertex[j]) if m.kind == "vertex" and vertex is not None else math.nan
                for j, ((lo, hi), m) in enumerate(zip(bounds, modes, strict=True))]
        values.append(vals[0] if single else tuple(vals))
        kinds.append(modes[0].kind if single else tuple(m.kind for m in modes))
    tiny = [k for k in range(K) if w[k] <= 1e-10 * max(T, 1.0)]
    if tiny:
        notes = [*notes, f"interval(s) {tiny} shrank to zero length: those arcs are not needed"]
    end_viol = summ["end_violation"]
    return RefinedSwitching(
        problem=pr, params=dict(params), control=pr.control_names[0], kinds=kinds,
        values=values, durations=w[:K].copy(), T=T, objective=J, x0=w[K:].copy(), xT=xT,
        exact=all(nlp.exact), status=res["status"], iterations=res["iterations"],
        solve_time=res["time"], transcribed_objective=transcribed_objective,
        lam_g=res["lam_g"], blocks=nlp.blocks, end_path_violation=end_viol, modes=nlp.modes,
        controls=tuple(pr.control_names), integration_error=err, path=res["path"],
        notes=list(notes), build_time=nlp.build_time, nlp=nlp, w=w, lam_x=res["lam_x"])

