"""Switching-time refinement across the phases of a :class:`ocp.MultiPhaseProblem`.

The NLP is :mod:`ocp.structure.phase_nlp`; this module solves it from a transcription
(:func:`refine_phases`) or a given structure (:func:`refine_phase_structure`) and
assembles the :class:`RefinedPhases`. Each phase has its own arcs (bang, boundary and
singular arcs, one :class:`~ocp.structure.flows.Mode`
per control and interval, as in :mod:`ocp.structure.refinement`); the unknowns are the
interval durations of every phase, the state at the start of every phase and
the problem's decision variables. The phases' own initial, terminal, boundary
and duration constraints and the linkage constraints are imposed on the
end-point values exactly as the transcription does (:meth:`MultiPhaseProblem.
boundary_blocks`); a time link ``t0 of b = T of a`` is used directly (``t0``
of the later phase *is* the earlier phase's ``T``), every other link is a
constraint of the NLP. Path constraints are sampled inside every interval and
at the start of every phase but the first. The NLP is built once per problem,
structure and step counts and cached, so a new parameter value re-solves it
(Newton's fast path first, as in the single-phase case).

Decision variables may appear in a phase's dynamics, running cost, path
constraints and control limits (``-peak <= u <= peak``, the epigraph form of
``min max |u|``): that phase's arcs are flowed on the phase with the variables
as constant states (:func:`flow_problem`, as the single-phase refinement does,
:mod:`ocp.structure.variables`), their values being the NLP's own unknowns, so
the switching times, the phase durations and the variables are refined
together, and an arc at ``u = peak`` is a bang arc.

Limitations (each raises a clear error): dynamics may not depend on time
(``t``, ``t0``, ``T``), and a phase may not declare integrals used in boundary
terms; a phase's initial time must be fixed (the first phase) or time-linked
to an earlier phase.

Example (accelerate, then brake with no control; :func:`refine_phases` of a
transcribed solution)::

    sol = MultipleShooting(mp, nodes=[20, 10]).solve({"d": 2.0})
    r = refine_phases(sol)            # r.phases[0].kinds == ["max"], r.T == 2 sqrt(2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import InfeasibleError, SolveError
from ..definition.multiphase import MultiPhaseProblem
from ..definition.trajectory import Trajectory
from ..transcriptions.solution import Solution
from .arcs import ArcStructure, control_bounds_at, detect_structure
from .interior_arcs import refinable_arcs
from .phase_nlp import (
    Modes,
    PhaseModes,
    PhaseRows,
    PhaseSwitchingNLP,
    check_phase_problem,
    clear_cache,
    flow_problem,
    phase_switching_nlp,
)
from .refinement import DEFAULT_TOL, required_substeps
from .switching import RefinedSwitching, insert_extra_arcs


# ------------------------------------------------------------------ result
@dataclass
class RefinedPhases:
    """Switching times of every phase refined to machine precision.

    Attributes
    ----------
    problem : MultiPhaseProblem
    params : dict
        Parameter values.
    phases : list of RefinedSwitching
        One per phase, in the phase's own time (from 0 to its duration), with the
        transversality conditions of the whole problem (``terminal_costate``).
    t0 : ndarray
        Start time of every phase.
    T, objective : float
        Final time of the last phase and the refined objective.
    variables : dict
        Decision variables.
    exact : bool
        Every interval of every phase integrated by the matrix exponential.
    status, iterations, solve_time, path : Ipopt's (or the Newton fast path's) figures.
        ``status`` says ``"Solve_Succeeded (KKT residual ...; Ipopt said ...)"`` when Ipopt
        stopped on another message at a point our own KKT check accepts.
    success : bool
        Converged to the requested accuracy (False on the iterate of a
        :class:`~ocp.definition.errors.SolveError`: :func:`ocp.certify` refuses it).
    transcribed_objective : float
        The objective of the transcription it started from (NaN without one).
    junction_costates : list of ndarray
        ``lambda_i(t0_i) = -dB/dx0_i`` from the multipliers (a check of the adjoint sweep).
    integration_error : float
        Largest RK8 end-state error estimate (0 when every arc is exact).
    notes : list of str
    nlp : PhaseSwitchingNLP
    w, lam_g, lam_x : ndarray
        The NLP's solution and multipliers.
    """

    problem: MultiPhaseProblem
    params: dict
    phases: list[RefinedSwitching]
    t0: np.ndarray
    T: float
    objective: float
    variables: dict
    exact: bool
    status: str
    iterations: int
    solve_time: float
    path: str
    transcribed_objective: float
    junction_costates: list[np.ndarray]
    integration_error: float = 0.0
    notes: list[str] = field(default_factory=list)
    nlp: PhaseSwitchingNLP | None = field(repr=False, default=None)
    w: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    lam_g: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    lam_x: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    success: bool = True

    @property
    def xT(self) -> np.ndarray:
        """Final state of the last phase (its own states: the decision variables are in
        :attr:`variables`)."""
        return self.phases[-1].xT[:self.problem.phases[-1].nx]

    @property
    def durations(self) -> list[np.ndarray]:
        """Interval durations of every phase."""
        return [r.durations for r in self.phases]

    @property
    def modes(self) -> tuple[Modes, ...]:
        """Interval modes of every phase."""
        return tuple(r.modes for r in self.phases)

    @property
    def kinds(self) -> list[list]:
        """Arc kinds of every phase."""
        return [r.kinds for r in self.phases]

    @property
    def switch_times(self) -> list[list[float]]:
        """Switch times of every phase, in absolute time."""
        return [[float(t0 + t) for t in r.switch_times] for t0, r in zip(self.t0, self.phases,
                                                                        strict=True)]

    def trajectory(self, n: int = 1000) -> Trajectory:
        """The refined trajectory of every phase joined (absolute time, ``phase`` column,
        ``mode`` = arc kind), states and controls by the union of the phases' names.

        Parameters
        ----------
        n : int
            About how many samples in all.
        """
        snames: list[str] = []
        cnames: list[str] = []
        for own in self.problem.phases:  # (not the variables a flow problem carries)
            snames += [s for s in own.state_names if s not in snames]
            cnames += [c for c in own.control_names if c not in cnames]
        total = max(self.T - float(self.t0[0]), 1e-300)
        ts, xs, us, ph, md = [], [], [], [], []
        for i, (t0, r) in enumerate(zip(self.t0, self.phases, strict=True)):
            k = max(20, int(n * r.T / total))
            tr = r.trajectory(k)
            X = np.full((len(tr.t), len(snames)), np.nan)
            U = np.full((len(tr.t), len(cnames)), np.nan)
            own = self.problem.phases[i]  # a flow problem's states begin with the phase's
            X[:, [snames.index(s) for s in own.state_names]] = tr.x[:, :own.nx]
            if tr.control_names:
                U[:, [cnames.index(c) for c in tr.control_names]] = tr.u
            ts.append(tr.t + t0)
            xs.append(X)
            us.append(U)
            ph.append(np.full(len(tr.t), i))
            md.append(tr.mode if tr.mode is not None else np.full(len(tr.t), ""))
        return Trajectory(np.concatenate(ts), np.vstack(xs), np.vstack(us), tuple(snames),
                          tuple(cnames), mode=np.concatenate(md), phase=np.concatenate(ph))

    def path_violation(self, n: int = 4000) -> float:
        """Largest path-constraint or control-bound violation over every phase.

        Parameters
        ----------
        n : int
            Samples per phase.
        """
        return max(r.path_violation(n) for r in self.phases)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (one entry per phase)."""
        return {"T": self.T, "objective": self.objective, "t0": self.t0.tolist(),
                "variables": self.variables, "exact_arcs": self.exact, "status": self.status,
                "iterations": self.iterations, "solve_time_s": self.solve_time,
                "path": self.path, "transcribed_objective": self.transcribed_objective,
                "integration_error": self.integration_error, "notes": self.notes,
                "phases": [{"name": r.problem.name, **r.to_dict()} for r in self.phases]}


def _phase_result(nlp: PhaseSwitchingNLP, i: int, res: dict, pv: np.ndarray, params: dict,
                  outs: dict, lam_end: np.ndarray, H: float | None, err: float,
                  transcribed_objective: float) -> RefinedSwitching:
    """Phase ``i`` of a solved multi-phase NLP as a :class:`RefinedSwitching` (local time).

    Its ``problem`` is the phase's flow problem (:func:`flow_problem`; ``origin`` the phase
    when that was derived, its states then carrying the variables after the phase's)."""
    mp = nlp.multiphase
    ph, q = mp.phases[i], nlp.flow_problems[i]
    w = res["w"]
    sl = nlp.phase_slice(i)
    K = nlp.phase_K[i]
    V = w[nlp.n_w - mp.nv:]
    variables = dict(zip(mp.var_names, map(float, V), strict=True))
    carried = V if q is not ph else np.zeros(0)  # the flow problem's variable states
    values, kinds = [], []
    single = ph.nu == 1
    for modes in nlp.phase_modes[i]:
        vals = []
        for name, m in zip(ph.control_names, modes, strict=True):
            lo, hi = control_bounds_at(ph, name, {**params, **variables})
            vals.append(hi if m.kind == "max" else lo if m.kind == "min" else math.nan)
        values.append(vals[0] if single else tuple(vals))
        kinds.append(modes[0].kind if single else tuple(m.kind for m in modes))
    rows = nlp.phase_rows[i]
    local = {k: np.flatnonzero(np.isin(rows, v)) for k, v in nlp.blocks.items()
             if np.isin(rows, v).any()}
    dur = w[sl][:K].copy()
    return RefinedSwitching(
        problem=q, params=dict(params), control=ph.control_names[0] if ph.nu else "",
        kinds=kinds, values=values, durations=dur, T=float(np.sum(dur)),
        objective=outs["J"], x0=np.r_[w[sl][K:], carried], xT=np.r_[outs["xT"][i], carried],
        variables=variables, origin=ph if q is not ph else None, exact=all(
            d.exact for d in nlp.phase_dyns[i]), status=res["status"],
        iterations=res["iterations"], solve_time=res["time"],
        transcribed_objective=transcribed_objective, lam_g=res["lam_g"][rows], blocks=local,
        modes=nlp.phase_modes[i], controls=tuple(ph.control_names), integration_error=err,
        path=res["path"], build_time=nlp.build_time, nlp=PhaseRows(nlp, i),  # type: ignore
        w=w[sl].copy(), lam_x=res["lam_x"][sl].copy(), terminal_costate=(lam_end, H))


def refine_phase_structure(mp: MultiPhaseProblem, modes: PhaseModes, durations: list,
                           x0s: list, params: dict[str, float], *,
                           variables: dict[str, float] | None = None,
                           transcribed_objective: float = math.nan, interior_samples: int = 16,
                           ipopt_options: dict | None = None, tol: float = DEFAULT_TOL,
                           fast: bool = True, max_rebuilds: int = 4) -> RefinedPhases:
    """Refine a given multi-phase arc structure from guesses of durations and phase starts.

    Parameters
    ----------
    mp : MultiPhaseProblem
    modes : tuple of Modes
        Per phase, per interval, one :class:`Mode` per control.
    durations : list of array
        Guessed interval durations per phase.
    x0s : list of array
        Guessed initial state of every phase (its states; a refined phase's ``x0``, with
        the decision variables after them, is read for its states).
    params : dict
        A value for every parameter.
    variables : dict, optional
        Guesses of the decision variables (default: their declared guesses).
    transcribed_objective : float
        Recorded in the result.
    interior_samples : int
        Path constraints are imposed at about this many points inside each interval.
    ipopt_options : dict, optional
        Overrides of :data:`ocp.structure.refinement.REFINE_IPOPT`.
    tol : float
        Relative accuracy required of the RK8 intervals' end states.
    fast : bool
        Try the Newton fast path first.
    max_rebuilds : int
        How often the step counts may be doubled to meet ``tol``.

    Returns
    -------
    RefinedPhases

    Raises
    ------
    SolveError, InfeasibleError
        If Ipopt fails or the accuracy is not reached.
    ProblemDefinitionError
        If the problem is outside what the refinement represents.
    """
    check_phase_problem(mp)  # before the arcs' flows are built from what it refuses
    pv = mp.param_vector(params)
    durs = [np.maximum(np.asarray(d, dtype=float), 1e-6) for d in durations]
    # a phase's own states (a refined phase's x0 has the variables after them)
    starts = [np.asarray(x, dtype=float)[:ph.nx] for ph, x in zip(mp.phases, x0s, strict=True)]
    vguess = _variable_guess(mp, pv, variables)
    flows = [flow_problem(ph) for ph in mp.phases]
    need = tuple(required_substeps(q, m, pv, d, x if q is ph else np.r_[x, vguess],
                                   interior_samples, tol)
                 for ph, q, m, d, x in zip(mp.phases, flows, modes, durs, starts, strict=True))
    w0 = np.concatenate([np.r_[d, x] for d, x in zip(durs, starts, strict=True)] + [vguess])
    notes: list[str] = []
    warm: tuple[Any, Any] = (None, None)
    for _ in range(max_rebuilds + 1):
        nlp = phase_switching_nlp(mp, modes, need, interior_samples, ipopt_options)
        fast_res = nlp.newton(pv, w0) if fast else None
        res = fast_res if fast_res is not None else nlp.solve(pv, w0, *warm)
        ok, err, bad = nlp.accuracy(res["w"], pv, tol)
        if ok or not res["success"]:
            break
        notes.append(f"interval(s) {bad} needed more RK8 steps; re-solved")
        need = tuple(tuple(2 * n if (i, k) in bad else n for k, n in enumerate(s))
                     for i, s in enumerate(nlp.phase_substeps))
        w0, warm = res["w"], (res["lam_g"], res["lam_x"])
    out = _assemble(nlp, res, pv, dict(params), err, notes, transcribed_objective)
    out.success = bool(res["success"] and ok)
    for ph in out.phases:
        ph.success = out.success
    if not res["success"]:
        cls = InfeasibleError if "Infeasible" in res["status"] else SolveError
        raise cls(res["status"], out, f"multi-phase switching refinement failed: "
                                      f"{res['status']}")
    if not ok:
        raise SolveError("Integration_Accuracy_Not_Reached", out,
                         f"multi-phase switching refinement: RK8 error {err:.1e} above tol")
    return out


def _variable_guess(mp: MultiPhaseProblem, pv: np.ndarray,
                    variables: dict[str, float] | None) -> np.ndarray:
    if not mp.nv:
        return np.zeros(0)
    from ..definition.guess import variable_guess

    g = np.array(ca.Function("vg", [mp.p], [variable_guess(mp.shared)])(pv),
                 dtype=float).ravel()
    for k, name in enumerate(mp.var_names):
        if variables is not None and name in variables:
            g[k] = variables[name]
    return g


def _assemble(nlp: PhaseSwitchingNLP, res: dict, pv: np.ndarray, params: dict, err: float,
              notes: list[str], transcribed_objective: float) -> RefinedPhases:
    mp = nlp.multiphase
    w = res["w"]
    outs = nlp.phase_outputs(w, pv)
    lam_end, lam_start, H = nlp.transversality(w, res["lam_g"], pv)
    phases = [_phase_result(nlp, i, res, pv, params, outs, lam_end[i], H[i], err,
                            transcribed_objective) for i in range(len(mp.phases))]
    tiny = [(i, k) for i, r in enumerate(phases) for k, d in enumerate(r.durations)
            if d <= 1e-10 * max(outs["T"][-1], 1.0)]
    if tiny:
        notes = [*notes, f"interval(s) {tiny} (phase, interval) shrank to zero length"]
    V = w[nlp.n_w - mp.nv:]
    return RefinedPhases(
        problem=mp, params=params, phases=phases, t0=outs["t0"], T=float(outs["T"][-1]),
        objective=outs["J"], variables=dict(zip(mp.var_names, map(float, V), strict=True)),
        exact=all(nlp.exact), status=res["status"], iterations=res["iterations"],
        solve_time=res["time"], path=res["path"], transcribed_objective=transcribed_objective,
        junction_costates=lam_start, integration_error=err, notes=notes, nlp=nlp, w=w,
        lam_g=res["lam_g"], lam_x=res["lam_x"])


# --------------------------------------------------------- from a transcription
def local_phase(sol: Solution, i: int) -> Solution:
    """Phase ``i`` of a multi-phase solution in its own time (``t0 = 0``), so the
    single-phase structure detection and certificate read it as a one-phase solution.

    Parameters
    ----------
    sol : Solution
        A multi-phase (or single-phase) solution.
    i : int
        Phase index.
    """
    ph = sol.phases[i]
    d = dict(ph.__dict__)
    d.update(t=ph.t - ph.t0, T=ph.T - ph.t0, t0=0.0, mesh=ph.mesh - ph.t0)
    d.pop("phases", None)
    out = Solution(**d)
    out.phases = [out]
    return out


def detect_phase_structures(sol: Solution, tol: float = 1e-4) -> list[ArcStructure]:
    """The arc structure of every phase of a transcribed multi-phase solution.

    Parameters
    ----------
    sol : Solution
        A transcribed multi-phase solution.
    tol : float
        As in :func:`ocp.structure.arcs.detect_arcs`.
    """
    out = []
    for i, ph in enumerate(sol.phases):
        if ph.problem.nu == 0:
            T = float(ph.T - ph.t0)
            out.append(ArcStructure.from_modes((), [()], [T]))
        else:
            out.append(detect_structure(local_phase(sol, i), tol=tol))
    return out


def refine_phases(sol: Solution, structures: list[ArcStructure] | None = None, *,
                  extra_arcs: int = 0, interior_samples: int = 16,
                  ipopt_options: dict | None = None, tol: float = DEFAULT_TOL,
                  params: dict[str, float] | None = None, fast: bool = True) -> RefinedPhases:
    """Refine the switching times of every phase of a transcribed multi-phase solution.

    Parameters
    ----------
    sol : Solution
        A transcribed multi-phase solution (its phases' arcs, end states and
        parameters start the refinement).
    structures : list of ArcStructure, optional
        One per phase (default: :func:`detect_phase_structures`). Interior arcs are
        refined as singular arcs where the control enters H linearly with a singular
        order (:func:`ocp.structure.interior_arcs.refinable_arcs`).
    extra_arcs : int
        Single-control phases: this many more bang arcs in every phase that has a bang
        arc (see :func:`ocp.structure.switching.refine_switching`).
    interior_samples : int
        Path-constraint samples per interval.
    ipopt_options : dict, optional
        Overrides of :data:`ocp.structure.refinement.REFINE_IPOPT`.
    tol : float
        Relative accuracy of the RK8 intervals.
    params : dict, optional
        Parameter values (default: ``sol.params``).
    fast : bool
        Try the Newton fast path first.

    Raises
    ------
    ValueError
        If a phase has an interior arc that is not singular.
    SolveError, InfeasibleError
        If the refinement fails.
    """
    sts = detect_phase_structures(sol) if structures is None else list(structures)
    modes, durs = [], []
    for i, st in enumerate(sts):
        try:  # interior arcs of a control with a singular order are singular arcs
            st = refinable_arcs(sol.phases[i].problem, st)
        except ValueError as err:
            raise ValueError(f"phase {sol.phases[i].problem.name!r}: {err}") from None
        if any(m.kind == "interior" for ms in st.modes for m in ms):
            raise ValueError(f"phase {sol.phases[i].problem.name!r}: a regular interior arc "
                             "is refined in a single-phase problem only (refine_switching)")
        m, d = list(st.modes), list(st.durations)
        if extra_arcs and len(st.controls) == 1 and any(x[0].kind in ("max", "min")
                                                        for x in m):
            insert_extra_arcs(m, d, extra_arcs)
        modes.append(tuple(m))
        durs.append(np.asarray(d, dtype=float))
    x0s = [np.asarray(ph.x[0], dtype=float) for ph in sol.phases]
    return refine_phase_structure(
        sol.problem, tuple(modes), durs, x0s, dict(sol.params if params is None else params),
        variables=sol.variables, transcribed_objective=float(sol.objective),
        interior_samples=interior_samples, ipopt_options=ipopt_options, tol=tol, fast=fast)


__all__ = ["PhaseSwitchingNLP", "RefinedPhases", "clear_cache", "detect_phase_structures",
           "flow_problem",
           "local_phase", "phase_switching_nlp", "refine_phase_structure", "refine_phases"]
