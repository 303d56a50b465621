"""ocp: generic direct optimal control on CasADi and Ipopt.

Knows nothing of landing. One file per role:

* :mod:`ocp.problem`       -- one phase: states, controls, parameters, decision
  variables, dynamics, constraints, costs, times;
* :mod:`ocp.multiphase`    -- phases in sequence, linkage constraints, shared parameters;
* :mod:`ocp.transcription` -- :class:`MultipleShooting` and :class:`Collocation`
  (Radau, with mesh refinement), :func:`transcribe`, :func:`continuation`;
* :mod:`ocp.nlp`           -- assembly of the phases into one parametric NLP (built
  once), Ipopt;
* :mod:`ocp.shooting`, :mod:`ocp.collocation` -- the per-phase discretisations;
* :mod:`ocp.integrators`   -- RK4 and CVODES interval integrators;
* :mod:`ocp.mesh`          -- error estimate and h-refinement of a collocation mesh;
* :mod:`ocp.scaling`       -- scaling of the NLP (references from ``ref=``, bounds,
  guesses), invisible in the solution;
* :mod:`ocp.sizes`         -- sizes of states that bounds and guess leave unknown (from
  boundary constraints, links and the dynamics), for the automatic scaling;
* :mod:`ocp.guess`         -- default initial guesses (moved off non-finite points) and
  non-finite-guess diagnosis;
* :mod:`ocp.verify`        -- post-solve check of path constraints between nodes;
* :mod:`ocp.local_optima` -- many starts over the bounds' box: the distinct local
  optima and the best (problems with several extremals);
* :mod:`ocp.scenario`      -- scenario problems: copies of a problem with other parameter
  values sharing one control (open-loop robust, or up to a branching time: a two-stage
  tree), worst-case or expected objective (:mod:`ocp.scenario_stack` builds the stacked
  problem, :mod:`ocp.scenario_result` splits and checks its solution by scenario);
* :mod:`ocp.solution`      -- trajectories, multipliers, sampling, export, plots;
* :mod:`ocp.gridview`      -- how a solution's grid is read (collocation on its mesh,
  costates from the Radau defect multipliers);
* :mod:`ocp.trajectory`    -- the sampled-trajectory type;
* :mod:`ocp.arcs`, :mod:`ocp.switching` -- bang-bang structure detection
  (:func:`detect_structure`) and switching-time refinement to machine precision
  (:func:`refine_switching`, :func:`refine_structure`; phases: :func:`refine_phases`);
* :mod:`ocp.constraint_kinds` -- path constraints classified as state, mixed or
  control-only; :mod:`ocp.control_set` -- the polytope of coupled controls and
  the Hamiltonian's minimiser over it;
* :mod:`ocp.chattering`    -- switches accumulating at a point (Fuller's phenomenon),
  confirmed on a finer grid;
* :mod:`ocp.costates`      -- costates from the multipliers, or integrated backward along
  the refined arcs; H and the switching functions;
* the Pontryagin certificate, which proves (or refutes) bang-bang structure and refuses
  what it cannot, in layers (each imports only those above it):
  :mod:`ocp.pmp_checks` (the checks on one set of samples: H, sigma, sign agreement,
  switch gap, singular runs; tolerances, judgement, verdict),
  :mod:`ocp.pmp_certificate` (:class:`PMPCertificate`, its assembly and refusal),
  :mod:`ocp.pmp_refined` (from a refined solution) and :mod:`ocp.pmp_transcription`
  (from a transcription alone, re-checked on a finer grid), :mod:`ocp.phase_pmp`
  (phase by phase), and :mod:`ocp.pmp` (:func:`certify`, the entry point, which also
  re-exports the names of the layers below).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# names are imported on first use: `import ocp.trajectory` (a light module) loads neither
# CasADi nor the transcriptions
_WHERE = {
    "GuessError": "errors", "InfeasibleError": "errors", "PathViolationError": "errors",
    "PathViolationWarning": "errors", "ProblemDefinitionError": "errors",
    "SolveError": "errors", "MultiPhaseProblem": "multiphase", "PMPCertificate": "pmp",
    "certify": "pmp", "plot_certificate": "pmp", "OptimalControlProblem": "problem",
    "Solution": "solution",
    "Trajectory": "trajectory", "Collocation": "transcription",
    "MultipleShooting": "transcription", "continuation": "transcription",
    "transcribe": "transcription", "detect_arcs": "arcs", "detect_structure": "arcs",
    "refine_switching": "switching", "refine_structure": "switching",
    "refine_phases": "phase_refinement", "certify_phases": "phase_pmp",
    "multistart": "local_optima", "MultistartResult": "local_optima",
    "ScenarioProblem": "scenario", "ScenarioTranscription": "scenario",
    "ScenarioResult": "scenario_result",
}

__all__ = [
    "Collocation",
    "GuessError",
    "InfeasibleError",
    "MultiPhaseProblem",
    "MultipleShooting",
    "MultistartResult",
    "OptimalControlProblem",
    "PMPCertificate",
    "PathViolationError",
    "PathViolationWarning",
    "ProblemDefinitionError",
    "ScenarioProblem",
    "ScenarioResult",
    "ScenarioTranscription",
    "Solution",
    "SolveError",
    "Trajectory",
    "certify",
    "certify_phases",
    "continuation",
    "detect_arcs",
    "detect_structure",
    "multistart",
    "plot_certificate",
    "refine_phases",
    "refine_structure",
    "refine_switching",
    "transcribe",
]


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'ocp' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{where}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))


if TYPE_CHECKING:
    from .arcs import detect_arcs, detect_structure
    from .errors import (
        GuessError,
        InfeasibleError,
        PathViolationError,
        PathViolationWarning,
        ProblemDefinitionError,
        SolveError,
    )
    from .local_optima import MultistartResult, multistart
    from .multiphase import MultiPhaseProblem
    from .phase_pmp import certify_phases
    from .phase_refinement import refine_phases
    from .pmp import PMPCertificate, certify, plot_certificate
    from .problem import OptimalControlProblem
    from .scenario import ScenarioProblem, ScenarioTranscription
    from .scenario_result import ScenarioResult
    from .solution import Solution
    from .switching import refine_structure, refine_switching
    from .trajectory import Trajectory
    from .transcription import Collocation, MultipleShooting, continuation, transcribe
