"""Scenario problems: one control for several copies of a problem with different parameters.

A :class:`ScenarioProblem` takes a one-phase :class:`ocp.OptimalControlProblem`
and the values of some of its parameters in ``S`` scenarios (an uncertain mass,
gain or initial state), and poses one problem over all copies:

* **open-loop robust** (``branching=None``): every scenario is driven by the
  same control trajectory;
* **two-stage tree** (``branching=f`` in ``[0, 1]``): the control is shared up
  to the fraction ``f`` of the horizon (non-anticipativity: until then nobody
  knows which scenario holds), then each scenario has its own control;
  ``f = 0`` is ``S`` independent problems, ``f = 1`` the open-loop robust one.

The objective is the worst case (``objective="worst"``: ``min z`` subject to
``J_i <= z``, the epigraph form, smooth for Ipopt) or the expectation
(``objective="expected"``: ``sum_i w_i J_i``). Example, a double integrator
with an uncertain gain ``b``::

    p = OptimalControlProblem()
    x, v = p.state("x"), p.state("v")
    u = p.control("u", -5, 5)
    b = p.parameter("b")
    p.set_dynamics({"x": v, "v": b * u})
    p.initial_constraint(x, 0.0); p.initial_constraint(v, 0.0)
    p.fixed_final_time(1.0)
    p.minimize_terminal((x - 1) ** 2); p.minimize_integral(0.01 * u**2)
    sp = ScenarioProblem(p, [{"b": 1.0}, {"b": 2.0}])       # worst case
    tr = sp.transcribe("multiple_shooting", nodes=20)       # built once
    res = tr.solve()                                        # res.worst, res.active
    res2 = tr.solve(scenarios=[{"b": 1.5}, {"b": 3.0}])     # no rebuild

Construction
------------
The scenarios are stacked into one :class:`ocp.MultiPhaseProblem` (its
``stacked`` attribute): scenario ``i`` has the states ``"x[i]"`` (for each state
``x``) and the parameters ``"b[i]"`` (for each scenario parameter ``b``); the
other parameters are common and keep their names, as do the decision variables
(shared by all scenarios: a design chosen once). Scenario values and weights
are NLP parameters (``"weight[i]"`` for the expected objective), so a re-solve
with new values rebuilds nothing. Each scenario's running cost and declared
integrals are carried by states (``"running_cost[i]"``, ``"integral0[i]"``, ...)
that start at 0, so that every scenario's cost and boundary constraints are
functions of end-point values, checked after each solve. With a branching
time inside the horizon the stacked problem has two phases, ``"shared"``
(controls ``"u"``) and ``"branched"`` (controls ``"u[i]"``), linked by the
states: the branching instant is a phase boundary, hence a node of the grid
of both transcriptions (and of every refined collocation mesh).

Time
----
The stacked problem runs in normalised time ``tau`` in ``[0, 1]``; scenario
``i`` lives on ``t = t0 + tau (T_i - t0)``. With a fixed final time all
``T_i`` are equal and ``tau`` is just time rescaled. With a free final time
(``free_final_time`` or ``free_duration``) each scenario has its own final time
``T_i``, a decision variable ``"T[i]"`` (a landing ends when *each* scenario's
body comes to rest), and the shared control is a function of ``tau``: scenario
``i`` applies ``u(t / T_i)``. This is the design chosen here because it keeps
one grid for all scenarios (a shared control on physical time would need each
scenario's horizon cut at the others' final times, a different grid per
scenario value), and a control schedule stretched to the duration of the
manoeuvre is what an open-loop schedule does in practice. The branching
fraction is likewise a fraction of each scenario's own horizon. A free initial
time is refused.

Results
-------
:meth:`ScenarioTranscription.solve` returns a
:class:`ocp.scenarios.result.ScenarioResult`: per-scenario costs, final times
and trajectories, the worst-case value and the active scenarios (those whose
cost reaches it), Ipopt's status, and for every scenario the violation of its
path constraints and state bounds on the fine check grid of :mod:`ocp.transcriptions.verify`
and of its boundary constraints; ``success`` is Ipopt's success *and* no
scenario violating anything beyond the transcription's ``verify_tol``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..definition.errors import ProblemDefinitionError
from ..definition.multiphase import MultiPhaseProblem
from ..definition.problem import OptimalControlProblem
from ..definition.symbols import positive_int
from ..transcriptions.nlp import Transcription
from ..transcriptions.solution import Solution
from ..transcriptions.transcription import Collocation, transcribe
from .result import ScenarioResult, make_result
from .stack import stack

__all__ = ["OBJECTIVES", "ScenarioProblem", "ScenarioResult", "ScenarioTranscription"]

OBJECTIVES = ("worst", "expected")
WEIGHT_TOL = 1e-9  # |sum(weights) - 1| allowed


class ScenarioProblem:
    """Several scenarios of one problem, sharing a control (up to a branching time).

    Parameters
    ----------
    problem : OptimalControlProblem
        A one-phase problem (a :class:`ocp.MultiPhaseProblem` is refused), with
        a fixed initial time.
    scenarios : sequence of mapping
        One mapping per scenario, ``parameter name -> value``, all with the same
        names (the scenario parameters); the problem's other parameters are common
        to all scenarios and given at solve time. These are the default values of
        :meth:`ScenarioTranscription.solve`.
    objective : {"worst", "expected"}
        Minimise the largest scenario cost, or the weighted sum of the costs.
    weights : sequence of float, optional
        The default scenario weights of the expected objective (non-negative,
        summing to 1; default: equal). Only with ``objective="expected"``.
    branching : float, optional
        Fraction of the horizon in ``[0, 1]`` until which the control is shared
        (a two-stage tree); ``None`` (or 1) shares it over the whole horizon
        (open-loop robust). The transcription's grid must have a node there.

    Attributes
    ----------
    stacked : MultiPhaseProblem
        The problem over all scenarios (see the module's description).
    names : list of str
        The scenario parameters.
    common : list of str
        The problem's other parameters.
    n_scenarios : int
        Number of scenarios.
    scenarios : list of dict
        The default scenario values.
    weights : ndarray or None
        The default weights (expected objective).
    objective : str
        ``"worst"`` or ``"expected"``.
    branching : float
        The branching fraction (1.0 for open loop).
    maps : ScenarioMaps
        Where each scenario lives in the stacked problem (used by the results).
    """

    def __init__(self, problem: OptimalControlProblem, scenarios: Sequence[Mapping[str, float]],
                 *, objective: str = "worst", weights: Sequence[float] | None = None,
                 branching: float | None = None) -> None:
        if isinstance(problem, MultiPhaseProblem) or not isinstance(problem,
                                                                    OptimalControlProblem):
            raise ProblemDefinitionError(
                f"problem: expected a one-phase OptimalControlProblem, got "
                f"{type(problem).__name__} (scenarios of multi-phase problems are not "
                "supported)")
        problem.validate()
        if problem.t0_mode == "free":
            raise ProblemDefinitionError("problem: a free initial time is not supported in "
                                         "scenario problems (fix it)")
        if objective not in OBJECTIVES:
            raise ProblemDefinitionError(f"objective must be one of {OBJECTIVES}, got "
                                         f"{objective!r}")
        self.base = problem
        self.objective = objective
        self.names = _scenario_names(scenarios, problem.param_names)
        self.n_scenarios = len(scenarios)
        self.scenarios = check_scenarios(scenarios, self.names, self.n_scenarios)
        self.common = [n for n in problem.param_names if n not in self.names]
        if objective == "worst" and weights is not None:
            raise ProblemDefinitionError("weights: only with objective='expected' (the worst "
                                         "case weighs no scenario)")
        self.weights = (check_weights(weights, self.n_scenarios)
                        if objective == "expected" else None)
        self.branching = _check_branching(branching)
        self.stacked, self.maps = stack(problem, self.names, self.n_scenarios, objective,
                                        self.branching)

    # ------------------------------------------------------------------ values
    def parameters(self, scenarios: Sequence[Mapping[str, float]] | None = None,
                   params: Mapping[str, float] | None = None,
                   weights: Sequence[float] | None = None) -> dict[str, float]:
        """The stacked problem's parameter values for these scenarios, checked.

        Parameters
        ----------
        scenarios : sequence of mapping, optional
            New scenario values (same count and names as at construction;
            default: those given at construction).
        params : mapping, optional
            Values of the common parameters.
        weights : sequence of float, optional
            Weights of the expected objective (default: those given at
            construction).

        Raises
        ------
        ProblemDefinitionError
            Naming the argument: wrong number of scenarios, other parameter names,
            a scenario parameter among ``params``, bad weights.
        """
        vals = self.scenarios if scenarios is None else check_scenarios(
            scenarios, self.names, self.n_scenarios)
        params = {} if params is None else dict(params)
        clash = sorted(set(params) & set(self.names))
        if clash:
            raise ProblemDefinitionError(f"params: {clash} are scenario parameters; give their "
                                         "values in scenarios")
        out = {k: float(v) for k, v in params.items()}
        for i, sc in enumerate(vals):
            out.update({f"{n}[{i}]": sc[n] for n in self.names})
        if self.objective == "expected":
            w = self.weights if weights is None else check_weights(weights, self.n_scenarios)
            assert w is not None
            out.update({f"weight[{i}]": float(wi) for i, wi in enumerate(w)})
        elif weights is not None:
            raise ProblemDefinitionError("weights: only with objective='expected'")
        return out

    def grid(self, nodes: int) -> list[int]:
        """Intervals per stacked phase for ``nodes`` intervals over the whole horizon.

        Parameters
        ----------
        nodes : int
            Intervals of the shared grid over ``[0, 1]``.

        Raises
        ------
        ProblemDefinitionError
            If the branching fraction is not a node of that grid.
        """
        n = positive_int(nodes, "nodes")
        f = self.branching
        if f in (0.0, 1.0):
            return [n]
        k = f * n
        if abs(k - round(k)) > 1e-9 * n or round(k) in (0, n):
            raise ProblemDefinitionError(
                f"branching={f:g} is not a node of a grid of nodes={n} intervals "
                f"(branching * nodes = {k:g}); choose nodes so that it is an integer")
        return [int(round(k)), n - int(round(k))]

    def transcribe(self, method: str = "multiple_shooting", nodes: int = 50,
                   **options: Any) -> ScenarioTranscription:
        """A transcription of the stacked problem (built once), see
        :class:`ScenarioTranscription`.

        Parameters
        ----------
        method : str
            ``"multiple_shooting"`` or ``"collocation"`` (and their aliases).
        nodes : int
            Intervals over the whole horizon (shooting intervals, or collocation
            mesh intervals).
        **options
            Passed to :class:`ocp.MultipleShooting` or :class:`ocp.Collocation`.
        """
        return ScenarioTranscription(self, method, nodes, **options)

    def __repr__(self) -> str:
        kind = ("open-loop" if self.branching == 1.0
                else f"two-stage tree (branching {self.branching:g})")
        return (f"ScenarioProblem({self.base.name!r}, {self.n_scenarios} scenarios of "
                f"{self.names}, objective={self.objective!r}, {kind})")


class ScenarioTranscription:
    """A transcription of a :class:`ScenarioProblem`, built once, re-solved for new values.

    Parameters
    ----------
    problem : ScenarioProblem
        The scenario problem.
    method : str
        ``"multiple_shooting"`` or ``"collocation"`` (and their aliases).
    nodes : int
        Intervals over the whole horizon; with a branching fraction ``f`` inside
        it, ``f * nodes`` must be an integer (the branching is a node).
    **options
        Passed to :class:`ocp.MultipleShooting` or :class:`ocp.Collocation`
        (``nodes`` / ``intervals`` are set from ``nodes``).

    Attributes
    ----------
    transcription : Transcription
        The transcription of the stacked problem.
    """

    def __init__(self, problem: ScenarioProblem, method: str = "multiple_shooting",
                 nodes: int = 50, **options: Any) -> None:
        if not isinstance(problem, ScenarioProblem):
            raise ProblemDefinitionError(f"problem: expected a ScenarioProblem, got "
                                         f"{type(problem).__name__}")
        for key in ("intervals", "mesh"):
            if key in options:
                raise ProblemDefinitionError(f"{key}: give the grid as nodes= (intervals over "
                                             "the whole horizon)")
        self.problem = problem
        split = problem.grid(nodes)
        m = method.lower()
        key = "intervals" if m in ("collocation", "radau", "lgr") else "nodes"
        self.transcription: Transcription = transcribe(problem.stacked, method,
                                                       **{key: split}, **options)

    @property
    def n_builds(self) -> int:
        """How many times the NLP was built (stays 1: re-solves never rebuild)."""
        return self.transcription.n_builds

    def solve(self, scenarios: Sequence[Mapping[str, float]] | None = None,
              params: Mapping[str, float] | None = None,
              weights: Sequence[float] | None = None, guess: Any = None,
              warm_start: ScenarioResult | Solution | None = None) -> ScenarioResult:
        """Solve for these scenario values (no rebuild).

        Parameters
        ----------
        scenarios : sequence of mapping, optional
            Scenario values (default: those of the problem).
        params : mapping, optional
            Values of the common parameters.
        weights : sequence of float, optional
            Weights of the expected objective (default: the problem's).
        guess : ScenarioResult, Solution, Trajectory or decision vector, optional
            Primal start (see :meth:`ocp.transcriptions.nlp.Transcription.solve`).
        warm_start : ScenarioResult or Solution, optional
            Primal-dual warm start from an earlier solve of this transcription.

        Raises
        ------
        SolveError, InfeasibleError
            If Ipopt fails (with its status and the last iterate of the stacked problem).
        PathViolationError
            With ``verify="raise"``, on a violation between nodes.
        """
        pv = self.problem.parameters(scenarios, params, weights)
        sol = self.transcription.solve(pv, guess=_unwrap(guess),
                                       warm_start=_unwrap(warm_start))
        return make_result(sol, self.problem.maps, self.transcription.verify_tol)

    def refine(self, scenarios: Sequence[Mapping[str, float]] | None = None,
               params: Mapping[str, float] | None = None,
               weights: Sequence[float] | None = None, **options: Any) -> ScenarioResult:
        """Solve with collocation mesh refinement (see :meth:`ocp.Collocation.refine`).

        The branching instant stays a mesh point (it is a phase boundary).

        Parameters
        ----------
        scenarios, params, weights
            As in :meth:`solve`.
        **options
            Passed to :meth:`ocp.Collocation.refine` (``tol``, ``max_rounds``, ...).
        """
        tr = self.transcription
        if not isinstance(tr, Collocation):
            raise ProblemDefinitionError("refine: only a collocation transcription refines "
                                         "its mesh")
        if "guess" in options:
            options["guess"] = _unwrap(options["guess"])
        sol = tr.refine(self.problem.parameters(scenarios, params, weights), **options)
        return make_result(sol, self.problem.maps, tr.verify_tol)

    def __repr__(self) -> str:
        return (f"ScenarioTranscription({self.problem!r}, {self.transcription.method}, "
                f"n_builds={self.n_builds})")


# ------------------------------------------------------------------ checks
def _scenario_names(scenarios: Any, param_names: list[str]) -> list[str]:
    if isinstance(scenarios, Mapping) or not isinstance(scenarios, Sequence) \
            or isinstance(scenarios, str):
        raise ProblemDefinitionError("scenarios: give a sequence of mappings, one per scenario "
                                     "(parameter name -> value)")
    if len(scenarios) == 0:
        raise ProblemDefinitionError("scenarios: the scenario list is empty")
    first = scenarios[0]
    if not isinstance(first, Mapping) or not first:
        raise ProblemDefinitionError("scenarios[0]: give a non-empty mapping parameter name "
                                     "-> value")
    names = [n for n in param_names if n in first]
    unknown = sorted(set(first) - set(param_names))
    if unknown:
        raise ProblemDefinitionError(f"scenarios[0]: {unknown} are not parameters of the "
                                     f"problem (its parameters: {param_names})")
    return names


def check_scenarios(scenarios: Any, names: list[str], n: int) -> list[dict[str, float]]:
    """Scenario values as dicts of floats, checked against the scenario parameters.

    Parameters
    ----------
    scenarios : sequence of mapping
        One mapping per scenario.
    names : list of str
        The scenario parameters (every mapping must give exactly these).
    n : int
        The number of scenarios.

    Raises
    ------
    ProblemDefinitionError
        Naming ``scenarios`` (or ``scenarios[i]``): not a sequence, wrong count,
        mismatched names, non-finite values.
    """
    if isinstance(scenarios, Mapping) or isinstance(scenarios, str) \
            or not isinstance(scenarios, Sequence):
        raise ProblemDefinitionError("scenarios: give a sequence of mappings, one per scenario")
    if len(scenarios) != n:
        raise ProblemDefinitionError(f"scenarios: {len(scenarios)} scenarios given, the problem "
                                     f"was built for {n}")
    out: list[dict[str, float]] = []
    for i, sc in enumerate(scenarios):
        if not isinstance(sc, Mapping):
            raise ProblemDefinitionError(f"scenarios[{i}]: expected a mapping, got "
                                         f"{type(sc).__name__}")
        if set(sc) != set(names):
            raise ProblemDefinitionError(
                f"scenarios[{i}]: parameter names {sorted(sc)} do not match the scenario "
                f"parameters {sorted(names)} (every scenario gives the same names)")
        vals = {k: float(sc[k]) for k in names}
        if not all(math.isfinite(v) for v in vals.values()):
            raise ProblemDefinitionError(f"scenarios[{i}]: values must be finite, got {vals}")
        out.append(vals)
    return out


def check_weights(weights: Sequence[float] | None, n: int) -> np.ndarray:
    """Scenario weights, checked: ``n`` finite non-negative numbers summing to 1.

    Parameters
    ----------
    weights : sequence of float or None
        The weights (None: equal weights).
    n : int
        The number of scenarios.

    Raises
    ------
    ProblemDefinitionError
        Naming ``weights``.
    """
    if weights is None:
        return np.full(n, 1.0 / n)
    try:
        w = np.asarray(weights, dtype=float).ravel()
    except (TypeError, ValueError) as err:
        raise ProblemDefinitionError(f"weights: not numbers: {weights!r}") from err
    if w.size != n:
        raise ProblemDefinitionError(f"weights: {w.size} weights for {n} scenarios")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ProblemDefinitionError(f"weights must be finite and non-negative, got "
                                     f"{w.tolist()}")
    if abs(w.sum() - 1.0) > WEIGHT_TOL:
        raise ProblemDefinitionError(f"weights must sum to 1, got {w.sum():.12g}")
    return w


def _check_branching(branching: float | None) -> float:
    if branching is None:
        return 1.0
    try:
        f = float(branching)
    except (TypeError, ValueError) as err:
        raise ProblemDefinitionError(f"branching: expected a fraction of the horizon in "
                                     f"[0, 1], got {branching!r}") from err
    if not 0.0 <= f <= 1.0:  # NaN fails too
        raise ProblemDefinitionError(f"branching={branching!r} is outside the horizon: give "
                                     "a fraction in [0, 1]")
    return f


def _unwrap(value: Any) -> Any:
    return value.solution if isinstance(value, ScenarioResult) else value
