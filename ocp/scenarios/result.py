"""The result of a scenario solve: each scenario's cost, trajectory and constraint check.

Made by :meth:`ocp.scenarios.scenario.ScenarioTranscription.solve` from the solution of
the stacked problem (see :mod:`ocp.scenarios.scenario`). Names follow scipy's
``OptimizeResult`` as :class:`ocp.Solution` does (``fun``, ``success``,
``status``, ``message``). After every solve each scenario is checked on its
own: its path constraints and state bounds on the fine grid of
:mod:`ocp.transcriptions.verify` (between the nodes), its initial, terminal and boundary
constraints at the end points, all relative to ``max(1, |bound|)``. A
constraint the scenarios share (one on the shared control only) counts for
every scenario. ``success`` is Ipopt's success *and* every scenario within the
transcription's ``verify_tol``: Ipopt's ``Solve_Succeeded`` never hides a
violated constraint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..definition.trajectory import Trajectory
from ..transcriptions.solution import Solution
from ..transcriptions.verify import path_excess

__all__ = ["ACTIVE_TOL", "ScenarioMaps", "ScenarioResult", "make_result"]

ACTIVE_TOL = 1e-6
"""A scenario is active when its cost is within ``ACTIVE_TOL * max(1, |worst|)`` of the worst."""


@dataclass
class ScenarioMaps:
    """Where each scenario lives in the stacked problem (made by :mod:`ocp.scenarios.scenario`).

    Attributes
    ----------
    names : list of str
        The scenario parameters.
    n_scenarios : int
        Number of scenarios.
    objective : str
        ``"worst"`` or ``"expected"``.
    state_names, control_names : list of str
        The original problem's states and controls.
    t0 : float
        The (fixed) initial time.
    final_times : list of float or str
        Each scenario's final time: a number (fixed) or the name of its decision
        variable (free).
    ends : casadi.Function
        ``(x0, u0 of the first phase, xT, uT of the last, p, v) -> (costs, g, lower,
        upper)``: each scenario's cost and its end-point constraints with bounds.
    checks : list of (int or None, str)
        Owner scenario (None: shared) and name of each row of ``g``.
    path_owner : dict
        Stacked path-constraint name -> owner scenario (None: shared).
    state_owner : dict
        Stacked state name -> owner scenario.
    phase_names : list of str
        The stacked phases (one, or ``"shared"`` and ``"branched"``).
    branching : float
        Fraction of the horizon until which the control is shared.
    """

    names: list[str]
    n_scenarios: int
    objective: str
    state_names: list[str]
    control_names: list[str]
    t0: float
    final_times: list[float | str]
    ends: ca.Function
    checks: list[tuple[int | None, str]]
    path_owner: dict[str, int | None]
    state_owner: dict[str, int]
    phase_names: list[str]
    branching: float


@dataclass
class ScenarioResult:
    """A solved scenario problem (scipy ``OptimizeResult``-like names).

    Attributes
    ----------
    solution : Solution
        The solution of the stacked problem (``solution.phases``, multipliers, ...).
    maps : ScenarioMaps
        Where each scenario lives in it.
    costs : ndarray, shape (S,)
        Each scenario's cost ``J_i`` at the optimum.
    scenarios : list of dict
        The scenario values solved for.
    weights : ndarray or None
        The weights (expected objective).
    final_times : ndarray, shape (S,)
        Each scenario's final time ``T_i``.
    violations : list of dict
        Per scenario, ``constraint name -> (relative violation, time)`` of every
        violated row (time NaN for an end-point constraint), however small.
    constraint_violation : ndarray, shape (S,)
        Each scenario's largest relative violation.
    verify_tol : float
        The tolerance ``success`` and ``verified`` use.
    """

    solution: Solution
    maps: ScenarioMaps
    costs: np.ndarray
    scenarios: list[dict[str, float]]
    weights: np.ndarray | None
    final_times: np.ndarray
    violations: list[dict[str, tuple[float, float]]]
    constraint_violation: np.ndarray
    verify_tol: float

    # ------------------------------------------------------------ outcome
    @property
    def n_scenarios(self) -> int:
        """Number of scenarios."""
        return self.maps.n_scenarios

    @property
    def verified(self) -> np.ndarray:
        """Per scenario: every constraint holds within ``verify_tol`` (bool array)."""
        return self.constraint_violation <= self.verify_tol

    @property
    def success(self) -> bool:
        """Ipopt converged and no scenario violates a constraint beyond ``verify_tol``."""
        return bool(self.solution.success and np.all(self.verified))

    @property
    def status(self) -> str:
        """Ipopt's return status."""
        return self.solution.status

    @property
    def message(self) -> str:
        """Ipopt's status, and the scenarios that violate a constraint if any."""
        bad = [i for i in range(self.n_scenarios) if not self.verified[i]]
        if not bad:
            return self.status
        worst = {i: max(self.violations[i].items(), key=lambda kv: kv[1][0]) for i in bad}
        what = "; ".join(f"scenario {i}: {k} by {v[0]:.3g}" for i, (k, v) in worst.items())
        return f"{self.status}, but constraints are violated ({what})"

    @property
    def iterations(self) -> int:
        """Ipopt's iterations."""
        return int(self.solution.iterations)

    @property
    def solve_time(self) -> float:
        """Ipopt's wall time in seconds."""
        return float(self.solution.solve_time)

    @property
    def objective(self) -> float:
        """What Ipopt minimised: the epigraph variable ``z`` (worst case; within Ipopt's
        bound relaxation, about 1e-8, below :attr:`worst`) or the expected cost."""
        return float(self.solution.objective)

    @property
    def fun(self) -> float:
        """The objective (scipy's name)."""
        return self.objective

    @property
    def worst(self) -> float:
        """The largest scenario cost (recomputed from the end points)."""
        return float(np.max(self.costs))

    @property
    def expected(self) -> float:
        """The weighted (default: equal-weight) mean of the scenario costs."""
        w = self.weights if self.weights is not None else np.full(self.n_scenarios,
                                                                    1.0 / self.n_scenarios)
        return float(w @ self.costs)

    @property
    def active(self) -> list[int]:
        """The scenarios whose cost is the worst (within :data:`ACTIVE_TOL`)."""
        w = self.worst
        return [i for i, J in enumerate(self.costs)
                if J >= w - ACTIVE_TOL * max(1.0, abs(w))]

    @property
    def active_scenario(self) -> int:
        """The scenario with the largest cost."""
        return int(np.argmax(self.costs))

    # ------------------------------------------------------- trajectories
    def _time(self, i: int, tau: np.ndarray) -> np.ndarray:
        t0 = self.maps.t0
        return t0 + np.asarray(tau, dtype=float) * (self.final_times[i] - t0)

    def _check(self, i: int) -> None:
        if not isinstance(i, int | np.integer) or not 0 <= i < self.n_scenarios:
            raise IndexError(f"scenario index {i!r} outside 0..{self.n_scenarios - 1}")

    def nodes(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Scenario ``i`` at the discretisation points, in its own time.

        Parameters
        ----------
        i : int
            The scenario.

        Returns
        -------
        t : ndarray, shape (M,)
            Times (``t0 + tau (T_i - t0)``).
        x : ndarray, shape (M, nx)
            States (the original problem's, in order).
        u : ndarray, shape (M - 1, nu)
            Controls (see :class:`ocp.Solution`: on each interval).
        """
        self._check(i)
        ts, xs, us = [], [], []
        for j, ph in enumerate(self.solution.phases):
            pr = ph.problem
            cx = [pr.state_names.index(f"{k}[{i}]") for k in self.maps.state_names]
            cu = [pr.control_names.index(k if k in pr.control_names else f"{k}[{i}]")
                  for k in self.maps.control_names]
            t, x = ph.t, ph.x[:, cx]
            if j:
                t, x = t[1:], x[1:]
            ts.append(t)
            xs.append(x)
            us.append(ph.u[:, cu])
        return self._time(i, np.concatenate(ts)), np.vstack(xs), np.vstack(us)

    def state(self, name: str, i: int) -> np.ndarray:
        """A state of scenario ``i`` at the discretisation points.

        Parameters
        ----------
        name : str
            A state of the original problem.
        i : int
            The scenario.
        """
        return self.nodes(i)[1][:, self.maps.state_names.index(name)]

    def control(self, name: str, i: int) -> np.ndarray:
        """A control of scenario ``i``, one value per interval.

        Parameters
        ----------
        name : str
            A control of the original problem.
        i : int
            The scenario.
        """
        return self.nodes(i)[2][:, self.maps.control_names.index(name)]

    def trajectory(self, i: int, n: int = 1000) -> Trajectory:
        """Scenario ``i`` sampled on about ``n`` points of its own time.

        Parameters
        ----------
        i : int
            The scenario.
        n : int
            Number of samples (about).
        """
        self._check(i)
        tr = self.solution.trajectory(n)
        x = np.column_stack([tr[f"{k}[{i}]"] for k in self.maps.state_names])
        cols: list[np.ndarray] = []
        for k in self.maps.control_names:
            # the shared column before the branching, the scenario's own after it
            parts = [tr[c] for c in (k, f"{k}[{i}]") if c in tr.control_names]
            col = parts[0]
            for other in parts[1:]:
                col = np.where(np.isnan(col), other, col)
            cols.append(col)
        u = np.column_stack(cols) if cols else np.zeros((len(tr), 0))
        return Trajectory(self._time(i, tr.t), x, u, tuple(self.maps.state_names),
                          tuple(self.maps.control_names), phase=tr.phase)

    def to_dict(self) -> dict[str, Any]:
        """Plain, JSON-able summary (no trajectories)."""
        def _clean(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"status": self.status, "success": self.success,
                "objective_kind": self.maps.objective, "objective": _clean(self.objective),
                "worst": _clean(self.worst), "expected": _clean(self.expected),
                "active": self.active, "costs": [_clean(v) for v in self.costs],
                "final_times": [_clean(v) for v in self.final_times],
                "scenarios": self.scenarios,
                "weights": None if self.weights is None else self.weights.tolist(),
                "constraint_violation": [_clean(v) for v in self.constraint_violation],
                "iterations": self.iterations, "solve_time_s": self.solve_time}

    def __repr__(self) -> str:
        return (f"ScenarioResult(status={self.status!r}, objective={self.objective:.10g}, "
                f"costs={np.array2string(self.costs, precision=8)}, active={self.active}, "
                f"success={self.success})")


def make_result(sol: Solution, maps: ScenarioMaps, verify_tol: float) -> ScenarioResult:
    """Split the stacked solution by scenario and check every scenario's constraints.

    Parameters
    ----------
    sol : Solution
        A converged solution of the stacked problem.
    maps : ScenarioMaps
        Where each scenario lives in it.
    verify_tol : float
        Allowed relative violation.
    """
    S = maps.n_scenarios
    first, last = sol.phases[0], sol.phases[-1]
    ends = np.r_[first.x[0], first.data.u_points[0], last.x[-1], last.data.u_points[-1]]
    pv = np.array(list(sol.params.values()), dtype=float)
    vv = np.array(list(sol.variables.values()), dtype=float)
    J, g, lo, hi = (np.array(v, dtype=float).ravel() for v in maps.ends(ends, pv, vv))
    final = np.array([v if isinstance(v, float) else sol.variables[v]
                      for v in maps.final_times], dtype=float)
    violations: list[dict[str, tuple[float, float]]] = [{} for _ in range(S)]

    def _record(owner: int | None, name: str, value: float, t: float) -> None:
        for i in (range(S) if owner is None else [owner]):
            violations[i][name] = (value, t)

    with np.errstate(invalid="ignore"):
        excess = np.maximum(np.maximum(lo - g, g - hi), 0.0)
        scale = np.maximum(1.0, np.where(g < lo, np.abs(lo), np.abs(hi)))
        rel = np.where(np.isfinite(g), excess / np.where(np.isfinite(scale), scale, 1.0),
                       np.inf)
    for (owner, name), r in zip(maps.checks, rel, strict=True):
        if r > 0:
            _record(owner, name, float(r), math.nan)
    per_interval = int(getattr(sol.transcription, "verify_points", 10))
    for key, (r, tau) in path_excess(sol, per_interval).items():
        name = _strip_phase(key, maps.phase_names) if sol.is_multiphase else key
        owner = _owner(name, maps)
        t = float(tau) if owner is None else float(maps.t0 + tau * (final[owner] - maps.t0))
        _record(owner, name, r, t)
    worst = np.array([max((v for v, _ in d.values()), default=0.0) for d in violations])
    scen = [{k: sol.params[f"{k}[{i}]"] for k in maps.names} for i in range(S)]
    weights = (np.array([sol.params[f"weight[{i}]"] for i in range(S)])
               if maps.objective == "expected" else None)
    return ScenarioResult(sol, maps, J, scen, weights, final, violations, worst,
                          float(verify_tol))


def _strip_phase(key: str, phases: list[str]) -> str:
    for p in phases:
        if key.startswith(f"{p}: "):
            return key[len(p) + 2:]
    return key


def _owner(name: str, maps: ScenarioMaps) -> int | None:
    """The scenario a checked row belongs to (None: shared by all)."""
    prefix = "bounds of state "
    if name.startswith(prefix):
        return maps.state_owner.get(name[len(prefix):].strip("'\""))
    if name in maps.path_owner:
        return maps.path_owner[name]
    base = name.rsplit("[", 1)[0]  # a row of a vector constraint
    return maps.path_owner.get(base)
