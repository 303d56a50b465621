"""ocp: generic multiple-shooting optimal control on CasADi and Ipopt.

Knows nothing of landing. One file per role:

* :mod:`ocp.problem`       -- states, controls, parameters, dynamics, constraints, cost, T;
* :mod:`ocp.transcription` -- multiple shooting -> parametric NLP (built once), Ipopt,
  warm starts and continuation;
* :mod:`ocp.solution`      -- trajectories, multipliers, sampling, export, plots;
* :mod:`ocp.switching`     -- bang-bang structure detection and switching-time
  refinement to machine precision;
* :mod:`ocp.pmp`           -- costates, Hamiltonian and switching function: a
  certificate that proves (or refutes) bang-bang structure.
"""

from .errors import InfeasibleError, SolveError
from .pmp import PMPCertificate, certify
from .problem import OptimalControlProblem, ProblemDefinitionError
from .solution import Solution
from .transcription import MultipleShooting, continuation

__all__ = [
    "InfeasibleError",
    "MultipleShooting",
    "PMPCertificate",
    "OptimalControlProblem",
    "ProblemDefinitionError",
    "Solution",
    "SolveError",
    "certify",
    "continuation",
]
