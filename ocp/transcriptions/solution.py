"""The result of a transcribed solve: trajectories, multipliers, solver figures, checks."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..definition.trajectory import Trajectory

# attributes a multi-phase solution keeps per phase only
_PER_PHASE = ("t", "x", "u", "T", "t0", "N", "mesh", "multipliers")


def along(fn: ca.Function, *args) -> list[np.ndarray]:
    """Evaluate ``fn`` at n samples in one mapped call.

    Each argument is an (n, k) array of per-sample rows or a single vector
    broadcast to every sample. Returns one (n, m) array per output.

    Parameters
    ----------
    fn : casadi.Function
        The function.
    *args : array_like
        Its arguments, one per input.
    """
    n = max(np.atleast_2d(a).shape[0] if np.ndim(a) == 2 else 1 for a in args)
    cols = [np.asarray(a, dtype=float).T if np.ndim(a) == 2 else np.asarray(a, dtype=float)
            for a in args]
    out = fn.map(n)(*cols)
    out = out if isinstance(out, tuple | list) else [out]
    return [np.array(o, dtype=float).T.reshape(n, -1) for o in out]


class Solution:
    """A solved (or failed) transcribed NLP, scipy-``OptimizeResult``-like.

    Attributes
    ----------
    t : (N+1,) discretisation times; ``x`` : (N+1, nx) states there; ``u`` :
        (N, nu) the control on ``[t_k, t_k+1]`` (multiple shooting: the
        piecewise-constant value; collocation: the value at the collocation
        point ``t_k+1``); ``T`` final and ``t0`` initial time; ``mesh``: the
        shooting nodes or collocation mesh points; ``fun``/``objective``.
    success, status, message, iterations, solve_time
        Ipopt's outcome: ``status`` is its return status string.
    w, lam_x, lam_g : the raw primal vector and multipliers. CasADi's
        Lagrangian is ``f + lam_g^T g + lam_x^T w``.
    multipliers : dict
        ``lam_g`` split by constraint block: ``continuity`` (N, nx), ``path``
        (N+1, n_path) for multiple shooting, ``collocation`` and ``path`` at
        the collocation points, ``initial``, ``terminal``, ``boundary``,
        ``time``; ``link`` on a multi-phase solution.
    params, variables : dicts of the parameter values and the optimised
        decision variables.
    objective_scale : float
        What the objective was divided by for Ipopt (:mod:`ocp.definition.scaling`); the
        objective and multipliers here are unscaled.
    expanded : bool
        Whether Ipopt evaluated the NLP's SX-expanded graph (the transcription's
        ``expand``; with ``"auto"``, from its second solve of a kind on; False with
        ``codegen=True``: compiled functions).
    scaling, scaling_fallback : Scaling, str or None
        The scaling the solve used (:mod:`ocp.transcriptions.scaled`), and, where a
        scaled solve failed and the NLP as posed solved, why it is the identity.
    dropped, dropped_residual : list of str, float
        End conditions loosened by ``solve(drop_dependent=True)`` and how well the
        solution meets them anyway (:mod:`ocp.transcriptions.failure`).
    path_violation : float
        Largest violation of a path constraint or state bound along the solution's
        interpolant, its maximum located between the nodes (relative to
        ``max(1, |bound|)``; :mod:`ocp.transcriptions.verify`); ``verified``
        is True when it is within the transcription's ``verify_tol``;
        ``violations`` names the offending constraints. ``unchecked`` names the
        constraints ``verified`` does not cover between the nodes (collocation:
        those on the controls alone, checked at the collocation points only).
    mesh_converged, objective_error, convergence
        Whether the discretisation converged: after ``refine()``, whether the states'
        and the objective's estimates met their tolerances (collocation: confirmed on
        the mesh halved; :mod:`ocp.transcriptions.refinement`), the estimate of the
        objective's absolute error, and both in words; after a single solve, False,
        NaN and ``"not converged: one grid, ..."``.
    phases : list of Solution
        One per phase (a single-phase solution is its own only phase). A
        multi-phase solution has no ``t``, ``x``, ``u``: use ``phases[i]`` or
        :meth:`trajectory`.

    Parameters
    ----------
    **kw
        The attributes above, as the transcription sets them (a solution is made by
        a transcription's ``solve``, not by users).
    """

    phases: list[Solution]
    t: np.ndarray  # (a single phase's; see the attributes above)
    x: np.ndarray
    u: np.ndarray
    problem: Any
    transcription: Any
    objective: float
    status: str
    success: bool
    params: dict[str, float]
    variables: dict[str, float]
    path_violation: float
    verified: bool | None
    violations: dict[str, tuple[float, float]]
    unchecked: list[str]
    mesh_history: list[Any]
    mesh_error: float
    objective_error: float = math.nan  # refine()'s estimate of the objective's error
    mesh_converged: bool = False  # refine() met its tolerances (a single solve: False)
    mesh_reason: str  # why a refinement within its tolerance is not converged (if it says)
    objective_scale: float
    expanded: bool
    scaling: Any
    scaling_fallback: str | None
    dropped: list[str]

    def __init__(self, **kw: Any) -> None:
        self.__dict__.update(kw)

    def __getattr__(self, name: str) -> Any:
        deferred = self.__dict__.get("deferred")
        if deferred and name in deferred:
            value = deferred[name](self)  # not popped: a copy of __dict__ shares the dict
            self.__dict__[name] = value
            return value
        if name in _PER_PHASE and "phases" in self.__dict__:
            raise AttributeError(f"a multi-phase solution has no {name!r}; use "
                                 f"sol.phases[i].{name} or sol.trajectory()")
        raise AttributeError(name)

    def defer(self, name: str, compute: Any) -> None:
        """Compute the attribute ``name`` as ``compute(self)`` when it is first read.

        Parameters
        ----------
        name : str
            The attribute (setting it directly overrides the deferred value).
        compute : callable
            ``solution -> value``.
        """
        self.__dict__.setdefault("deferred", {})[name] = compute

    @property
    def convergence(self) -> str:
        """Whether the discretisation converged, in words: ``"converged (mesh, estimated
        error 3.2e-09)"`` after a :meth:`~ocp.Collocation.refine` (or
        :meth:`~ocp.MultipleShooting.refine`) that met its tolerances with that estimate
        of the objective's absolute error (``objective_error``), else what it is not."""
        history = self.__dict__.get("mesh_history")
        e = self.objective_error
        if not history:
            return "not converged: one grid, no estimate of its error (refine() converges)"
        if self.mesh_converged and not math.isfinite(e):  # (objective_tol=math.inf)
            return "converged (mesh; the objective's error not estimated: objective_tol off)"
        if self.mesh_converged:
            return f"converged (mesh, estimated error {e:.2g})"
        reason = self.__dict__.get("mesh_reason")
        if reason:  # (a refinement that says which of its conditions is missing)
            return f"not converged (mesh): {reason}, after {len(history)} solves"
        if not math.isfinite(e):
            return ("not converged (mesh): no estimate of the objective's error could be "
                    f"confirmed within the rounds and intervals allowed ({len(history)} solves)")
        return (f"not converged (mesh): estimated error {e:.2g} above the tolerance after "
                f"{len(history)} solves")

    # python-control / scipy style aliases
    @property
    def fun(self) -> float:
        """The objective (scipy's name)."""
        return self.objective

    @property
    def message(self) -> str:
        """Ipopt's return status (scipy's name)."""
        return self.status

    @classmethod
    def from_nlp(cls, tr: Any, pv: np.ndarray, res: dict, stats: dict,
                 elapsed: float) -> Solution:
        """Unpack Ipopt's result for the transcription ``tr`` (parameters ``pv``).

        Parameters
        ----------
        tr : Transcription
            The transcription that was solved.
        pv : ndarray
            The parameter values.
        res : dict
            Ipopt's result (``x``, ``f``, ``lam_g``, ``lam_x``).
        stats : dict
            The solver's statistics.
        elapsed : float
            Solve wall time in seconds.
        """
        w = np.array(res["x"]).ravel()
        lam_g = np.array(res["lam_g"]).ravel()
        mp = tr.multiphase
        vv = w[tr.iV]
        common = dict(
            objective=float(res["f"]), w=w, lam_x=np.array(res["lam_x"]).ravel(), lam_g=lam_g,
            success=bool(stats["success"]), status=str(stats["return_status"]),
            iterations=int(stats["iter_count"]), solve_time=elapsed, transcription=tr,
            params=dict(zip(mp.param_names, (float(v) for v in pv), strict=True)),
            variables=dict(zip(mp.var_names, (float(v) for v in vv), strict=True)),
            path_violation=math.nan, verified=None, violations={},
            unchecked=[])
        phases = []
        for i, (disc, lay) in enumerate(zip(tr.phases, tr.layouts, strict=True)):
            data = disc.unpack(w[tr.offsets[i]:tr.offsets[i] + disc.size()], pv, vv)
            mult = disc.multipliers({k: lam_g[sl] for k, sl in lay.blocks.items()})
            phases.append(cls(problem=mp.phases[i], phase_index=i, discretization=disc,
                              data=data, t=data.t, x=data.x, u=data.u, T=data.T,
                              t0=data.t0, N=len(data.t) - 1, mesh=data.mesh,
                              multipliers=mult, **common))
        if len(phases) == 1:
            phases[0].phases = [phases[0]]
            return phases[0]
        links = {k: lam_g[sl] for k, sl in tr.link_blocks.items()}
        return cls(problem=tr.problem, phases=phases, link_multipliers=links, **common)

    # ------------------------------------------------------------------ access
    @property
    def is_multiphase(self) -> bool:
        """True if the problem has more than one phase."""
        return len(self.phases) > 1

    def state(self, name: str) -> np.ndarray:
        """A state's values at the discretisation points.

        Parameters
        ----------
        name : str
            A state of the phase.
        """
        return self.x[:, self.problem.state_names.index(name)]

    def control(self, name: str) -> np.ndarray:
        """A control's values, one per interval (see the class attributes).

        Parameters
        ----------
        name : str
            A control of the phase.
        """
        return self.u[:, self.problem.control_names.index(name)]

    def sample(self, n: int = 1000, substeps: int = 8) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
        """Trajectory on ``n`` equally spaced times of a phase.

        Multiple shooting: re-integrated from each node with the dynamics (RK4,
        ``substeps`` per sub-interval), control held constant. Collocation: the
        state and control polynomials of each mesh interval.

        Returns ``t`` (n,), ``x`` (n, nx), ``u`` (n, nu).

        Parameters
        ----------
        n : int
            Number of samples.
        substeps : int
            RK4 steps per sub-interval (multiple shooting).
        """
        t = np.linspace(self.t0, self.T, n)
        x, u = self.discretization.sample(self.data, t, substeps)
        return t, x, u

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """States and controls of a phase at the times ``t`` (see :meth:`sample`).

        Parameters
        ----------
        t : array_like
            Times within the phase.

        Raises
        ------
        ValueError
            For a time outside ``[t0, T]`` (it was extrapolated: shooting integrated on with
            the last control, collocation's polynomial continued).
        """
        ts = np.atleast_1d(np.asarray(t, float))
        slack = 1e-12 * max(1.0, abs(self.t0), abs(self.T))
        bad = ts[~((ts >= self.t0 - slack) & (ts <= self.T + slack))]
        if bad.size:
            raise ValueError(f"at: t = {bad[0]:.12g} is outside the phase [{self.t0:.12g}, "
                             f"{self.T:.12g}] (a solution is not extrapolated)")
        return self.discretization.sample(self.data, ts)

    def resample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """States and controls of a phase at the times ``t`` as the method represents them,
        what a guess on another grid is resampled from (collocation: the control's
        polynomial through its collocation points, extrapolated before the first; see
        :meth:`ocp.transcriptions.collocation.CollocationPhase.local`; multiple
        shooting: :meth:`at`).

        Parameters
        ----------
        t : array_like
            Times within the phase.
        """
        return self.discretization.resample(self.data, np.atleast_1d(np.asarray(t, float)))

    def trajectory(self, n: int = 1000) -> Trajectory:
        """The solution as a :class:`ocp.definition.trajectory.Trajectory` on about ``n`` samples.

        A multi-phase solution is sampled phase by phase (in proportion to the
        phase durations, each phase's ends included) and joined; columns are
        the union of the phases' states and controls (NaN where a phase lacks
        one) and ``phase`` holds the phase index.

        Parameters
        ----------
        n : int
            Number of samples (about; each phase gets at least 2).
        """
        if not self.is_multiphase:
            t, x, u = self.sample(max(int(n), 2))
            pr = self.problem
            return Trajectory(t, x, u, tuple(pr.state_names), tuple(pr.control_names))
        return _join_phases(self.phases, n)

    def evaluate(self, expr: ca.SX) -> np.ndarray:
        """An expression of (x, u, t, p, v, t0, T) at every discretisation point.

        Multiple shooting: the last node uses the last control; collocation:
        the first point uses the control polynomial extrapolated to ``t0``.

        Parameters
        ----------
        expr : SX
            The expression.
        """
        pr = self.problem
        s = ca.vertcat(pr.p, pr.v, pr.t0, pr.T)
        fn = ca.Function("e", [pr.t, pr.x, pr.u, s], [expr])
        return along(fn, self.t[:, None], self.x, self.data.u_points, self.data.s)[0].ravel()

    def to_dict(self) -> dict[str, Any]:
        """Plain, JSON-able dict."""
        def _clean(v: float) -> float | None:
            return v if math.isfinite(v) else None

        d: dict[str, Any] = {
            "status": self.status, "success": self.success, "iterations": self.iterations,
            "solve_time_s": self.solve_time, "objective": _clean(self.objective),
            "params": self.params, "variables": self.variables,
            "path_violation": _clean(self.path_violation), "verified": self.verified,
            "unchecked": list(self.__dict__.get("unchecked", [])),
            # (whether the discretisation converged: a refined solution's JSON lost it)
            "mesh_converged": bool(self.mesh_converged),
            "objective_error": _clean(float(self.objective_error)),
            "convergence": self.convergence}
        if self.is_multiphase:
            d["phases"] = [{**_phase_dict(p), "name": p.problem.name} for p in self.phases]
            return d
        return {**d, **_phase_dict(self)}

    def plot(self, fig: Any = None) -> Any:
        """States and controls against time (one axis each); returns the figure.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Draw into this figure (default: a new one).
        """
        import matplotlib.pyplot as plt

        traj = self.trajectory(400)
        names = list(traj.state_names) + list(traj.control_names)
        n = len(names)
        if fig is None:
            fig, axes = plt.subplots(n, 1, sharex=True, figsize=(7, 1.6 * n + 1))
        else:
            axes = fig.subplots(n, 1, sharex=True)
        axes = np.atleast_1d(axes)
        for ax, name in zip(axes, names, strict=True):
            ax.plot(traj.t, traj[name])
            ax.set_ylabel(name)
        axes[-1].set_xlabel("time")
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        T = self.phases[-1].T
        return (f"Solution(status={self.status!r}, objective={self.objective:.10g}, "
                f"T={T:.6g}, iterations={self.iterations}, verified={self.verified})")


def _phase_dict(ph: Solution) -> dict[str, Any]:
    pr = ph.problem
    return {"T": ph.T, "t0": ph.t0, "t": ph.t.tolist(),
            "states": {n: ph.x[:, i].tolist() for i, n in enumerate(pr.state_names)},
            "controls": {n: ph.u[:, i].tolist() for i, n in enumerate(pr.control_names)}}


def _join_phases(phases: list[Solution], n: int) -> Trajectory:
    """Sample each phase and join them with a union of columns and a phase index."""
    snames: list[str] = []
    cnames: list[str] = []
    for ph in phases:
        snames += [s for s in ph.problem.state_names if s not in snames]
        cnames += [c for c in ph.problem.control_names if c not in cnames]
    total = sum(max(ph.T - ph.t0, 0.0) for ph in phases) or 1.0
    ts, xs, us, idx = [], [], [], []
    for i, ph in enumerate(phases):
        k = max(2, int(round(n * max(ph.T - ph.t0, 0.0) / total)))
        t, x, u = ph.sample(k)
        X = np.full((k, len(snames)), np.nan)
        U = np.full((k, len(cnames)), np.nan)
        X[:, [snames.index(s) for s in ph.problem.state_names]] = x
        if ph.problem.nu:
            U[:, [cnames.index(c) for c in ph.problem.control_names]] = u
        ts.append(t)
        xs.append(X)
        us.append(U)
        idx.append(np.full(k, i))
    return Trajectory(np.concatenate(ts), np.vstack(xs), np.vstack(us), tuple(snames),
                      tuple(cnames),
                      phase=np.concatenate(idx))
