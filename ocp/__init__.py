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
* :mod:`ocp.guess`         -- default initial guesses and non-finite-guess diagnosis;
* :mod:`ocp.verify`        -- post-solve check of path constraints between nodes;
* :mod:`ocp.multistart`    -- many starts over the bounds' box: the distinct local
  optima and the best (problems with several extremals);
* :mod:`ocp.solution`      -- trajectories, multipliers, sampling, export, plots;
* :mod:`ocp.trajectory`    -- the sampled-trajectory type;
* :mod:`ocp.switching`     -- bang-bang structure detection and switching-time
  refinement to machine precision;
* :mod:`ocp.pmp`           -- costates, Hamiltonian and switching function: a
  certificate that proves (or refutes) bang-bang structure.
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
    "certify": "pmp", "OptimalControlProblem": "problem", "Solution": "solution",
    "Trajectory": "trajectory", "Collocation": "transcription",
    "MultipleShooting": "transcription", "continuation": "transcription",
    "transcribe": "transcription",
    "multistart": "multistart", "MultistartResult": "multistart",
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
    "Solution",
    "SolveError",
    "Trajectory",
    "certify",
    "continuation",
    "multistart",
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
    from .errors import (
        GuessError,
        InfeasibleError,
        PathViolationError,
        PathViolationWarning,
        ProblemDefinitionError,
        SolveError,
    )
    from .multiphase import MultiPhaseProblem
    from .multistart import MultistartResult, multistart
    from .pmp import PMPCertificate, certify
    from .problem import OptimalControlProblem
    from .solution import Solution
    from .trajectory import Trajectory
    from .transcription import Collocation, MultipleShooting, continuation, transcribe
