"""ocp: generic direct optimal control on CasADi and Ipopt.

Knows nothing of landing. Public names are imported from the top (``from ocp import
OptimalControlProblem, Collocation, certify``); the sub-packages hold one role each, and
their imports run one way, each only from those above it:

* :mod:`ocp.definition`     -- what a problem is: one phase (:mod:`~ocp.definition.problem`),
  phases in sequence (:mod:`~ocp.definition.multiphase`), symbols and bounds, its
  expressions compiled to CasADi Functions, default guesses, the sizes and scaling of
  its unknowns, the sampled :class:`Trajectory`, the errors;
* :mod:`ocp.transcriptions` -- how it becomes an NLP: :class:`MultipleShooting` and
  :class:`Collocation` (Radau, with mesh refinement), the per-phase discretisations,
  integrators, the parametric NLP built once and solved by Ipopt, the check between
  nodes, and the :class:`Solution`;
* :mod:`ocp.structure`      -- what a solution's controls do: bang-bang, boundary and
  vertex arcs (:func:`detect_structure`), the control set of coupled controls, and the
  switching-time refinement to machine precision (:func:`refine_switching`,
  :func:`refine_structure`; phases: :func:`refine_phases`);
* :mod:`ocp.certificate`    -- Pontryagin's conditions: costates, H and the switching
  functions, chattering, and :func:`certify` (proves, refutes, or says inconclusive and
  why);
* :mod:`ocp.scenarios`      -- copies of a problem with other parameter values sharing one
  control (robust open loop, two-stage tree), worst-case or expected objective;
* :mod:`ocp.search`         -- many starts: the distinct local optima and the best
  (:func:`multistart`).

The flat module paths of 0.3 (``ocp.switching``, ``ocp.pmp``, ...) still import, with a
:class:`DeprecationWarning` naming the new path; they go in the next version.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from . import deprecated_paths

# names are imported on first use: `import ocp.definition.trajectory` (a light module) loads neither
# CasADi nor the transcriptions
_WHERE = {
    "ConvergenceWarning": "definition.errors",
    "DroppedConditionWarning": "definition.errors",
    "GuessError": "definition.errors",
    "InfeasibleError": "definition.errors",
    "PathViolationError": "definition.errors",
    "PathViolationWarning": "definition.errors",
    "ProblemDefinitionError": "definition.errors",
    "ScalingFallbackWarning": "definition.errors",
    "SolveError": "definition.errors",
    "MultiPhaseProblem": "definition.multiphase",
    "PMPCertificate": "certificate.certify",
    "certify": "certificate.certify",
    "plot_certificate": "certificate.certify",
    "OptimalControlProblem": "definition.problem",
    "Solution": "transcriptions.solution",
    "Trajectory": "definition.trajectory",
    "Collocation": "transcriptions.transcription",
    "MultipleShooting": "transcriptions.transcription",
    "continuation": "transcriptions.transcription",
    "transcribe": "transcriptions.transcription",
    "detect_arcs": "structure.arcs",
    "detect_structure": "structure.arcs",
    "refine_switching": "structure.switching",
    "refine_structure": "structure.switching",
    "refine_phases": "structure.phase_refinement",
    "certify_phases": "certificate.phases",
    "multistart": "search.multistart",
    "MultistartResult": "search.multistart",
    "ScenarioProblem": "scenarios.scenario",
    "ScenarioTranscription": "scenarios.scenario",
    "ScenarioResult": "scenarios.result",
    "blas_threads": "transcriptions.blas",
    "set_blas_threads": "transcriptions.blas",
}

__all__ = [
    "Collocation",
    "ConvergenceWarning",
    "DroppedConditionWarning",
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
    "ScalingFallbackWarning",
    "ScenarioProblem",
    "ScenarioResult",
    "ScenarioTranscription",
    "Solution",
    "SolveError",
    "Trajectory",
    "blas_threads",
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
    "set_blas_threads",
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
    from .certificate.certify import PMPCertificate, certify, plot_certificate
    from .certificate.phases import certify_phases
    from .definition.errors import (
        ConvergenceWarning,
        DroppedConditionWarning,
        GuessError,
        InfeasibleError,
        PathViolationError,
        PathViolationWarning,
        ProblemDefinitionError,
        ScalingFallbackWarning,
        SolveError,
    )
    from .definition.multiphase import MultiPhaseProblem
    from .definition.problem import OptimalControlProblem
    from .definition.trajectory import Trajectory
    from .scenarios.result import ScenarioResult
    from .scenarios.scenario import ScenarioProblem, ScenarioTranscription
    from .search.multistart import MultistartResult, multistart
    from .structure.arcs import detect_arcs, detect_structure
    from .structure.phase_refinement import refine_phases
    from .structure.switching import refine_structure, refine_switching
    from .transcriptions.blas import blas_threads, set_blas_threads
    from .transcriptions.solution import Solution
    from .transcriptions.transcription import (
        Collocation,
        MultipleShooting,
        continuation,
        transcribe,
    )


# the flat module paths of 0.3 import for one more version, with a DeprecationWarning
deprecated_paths.install(__name__)
