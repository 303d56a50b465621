"""Smooth optima: converged on a refined mesh and certified arc by arc.

An optimum whose force is continuous (a cost strictly convex in the force, such as the
actuator energy ``∫u² dt``) has *interior* arcs, where ``H_u = 0`` sets the force: there
are no switching times to refine with exact arcs, and a multi-phase refinement of such
arcs is not available (:func:`ocp.refine_phases` refines bang, singular and boundary
arcs). Its accuracy is then the transcription's, so the pipeline
(:func:`softlanding.optimal.solve_phased`) routes it here:

* :func:`solve_smooth`: the same problem transcribed by Radau collocation and its mesh
  refined until the states and the objective converge (:meth:`ocp.Collocation.refine`,
  confirmed on the mesh halved), started from the shooting solution; the result says
  ``"converged (mesh, estimated error e)"`` or what is not converged;
* :func:`certify_smooth`: Pontryagin's conditions checked on every phase of that solution
  with the per-arc certificate (:func:`ocp.certify` on the phase in its own time, costates
  from the collocation multipliers): stationarity ``H_u = 0`` and Legendre–Clebsch on the
  interior arcs, the conditions of every other arc type, ``H`` constant and equal to its
  free-time value.

A smooth optimum is verified when its mesh converged, its certificate certifies every
arc, and its force replayed in the exact simulator lands at its depth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca

from ocp import Collocation, Solution, SolveError, certify
from ocp.certificate.arc_record import certified_verdict
from ocp.certificate.result import PMPCertificate
from ocp.structure.phase_refinement import detect_phase_structures, local_phase
from softlanding.util.signals import raise_if_interrupted

MESH_TOL = 1e-7
"""Requested accuracy of the states and of the objective (relative to ``max(1, |J|)``)."""
FIRST_INTERVALS = 10
"""Collocation intervals per phase of the first mesh (refinement adds where needed)."""


def convex_in_control(sol: Solution) -> bool:
    """Whether some phase's running cost is curved in a control (``∫u² dt``): the force
    is then set by ``H_u = 0`` wherever it is inside its bounds.

    Parameters
    ----------
    sol : ocp.Solution
        A transcribed (multi-phase) solution.
    """
    for ph in sol.phases:
        pr = ph.problem
        if pr.nu and ca.hessian(pr.lagrange, pr.u)[0].nnz() > 0:
            return True
    return False


def is_smooth(sol: Solution) -> bool:
    """Whether a transcribed solution is a smooth optimum: a running cost curved in the
    control (:func:`convex_in_control`) and interior arcs, where no switching time is to
    be refined. A bang-bang problem (a cost without the control, or linear in it) is never
    routed here, whatever its grid shows between switches.

    Parameters
    ----------
    sol : ocp.Solution
        A transcribed (multi-phase) solution.
    """
    return convex_in_control(sol) and any(
        a.kind == "interior" for st in detect_phase_structures(sol)
        for sc in st.per_control for a in sc.arcs)


@dataclass
class SmoothCertificate:
    """The per-arc PMP certificate of a smooth multi-phase optimum, phase by phase.

    Attributes
    ----------
    verdict : str
        ``"certified (interior, ...)"`` when every phase's arcs are certified (the arc
        types named), else the worst phase's verdict (``"inconclusive"``, ...).
    reasons : list of str
        Every phase's reasons, prefixed with the phase.
    phases : list of ocp.PMPCertificate
        One per phase.
    phase_names : list of str
    source : str
        Where the costates came from, and what is not checked.
    """

    verdict: str
    reasons: list[str]
    phases: list[PMPCertificate]
    phase_names: list[str]
    source: str = ("per phase, costates from the collocation multipliers (the junction "
                   "between phases: H continuous there through each phase's free-time "
                   "value; the costates' jump is the transcription's)")

    @property
    def certified(self) -> bool:
        """Every arc of every phase certified."""
        return self.verdict.startswith("certified")

    @property
    def H_max_abs(self) -> float:
        """The largest ``|H - H_expected| / H_scale`` over the phases."""
        return max((c.H_max_abs for c in self.phases), default=math.nan)

    def rows(self) -> list[tuple[str, object]]:
        """The ``label, value`` rows of the printed table: the verdict, then each arc."""
        out: list[tuple[str, object]] = [("PMP verdict", self.verdict),
                                         ("PMP costate source", self.source),
                                         ("max |H - H_expected| / H_scale", self.H_max_abs)]
        for name, c in zip(self.phase_names, self.phases, strict=True):
            for a in c.arcs:  # each checked condition: residual (tolerance)
                checked = "; ".join(f"{k} {v:.1e} (tol {a.tolerances[k]:.0e})"
                                    for k, v in a.residuals.items() if k in a.tolerances)
                out.append((f"arc ({name}) {a.kind} [{a.start:.6g}, {a.end:.6g}]",
                            f"{a.status}: {checked}"))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: the verdict and each phase's certificate."""
        return {"verdict": self.verdict, "reasons": self.reasons, "source": self.source,
                "H_max_abs": self.H_max_abs,
                "phases": [{"name": n, **c.to_dict()}
                           for n, c in zip(self.phase_names, self.phases, strict=True)]}


def certify_smooth(sol: Solution) -> SmoothCertificate:
    """The per-arc certificate of every phase of a (collocation) solution.

    Parameters
    ----------
    sol : ocp.Solution
        A converged multi-phase solution.
    """
    certs = [certify(local_phase(sol, i), chattering=False) for i in range(len(sol.phases))]
    names = [ph.problem.name for ph in sol.phases]
    reasons = [f"phase {n!r}: {r}" for n, c in zip(names, certs, strict=True)
               for r in c.reasons]
    if all(c.certified for c in certs):
        verdict = certified_verdict([a for c in certs for a in c.arcs])
    else:
        verdict = next(c.verdict for c in certs if not c.certified)
    return SmoothCertificate(verdict, reasons, certs, names)


@dataclass
class SmoothOptimum:
    """A smooth optimum converged on a refined collocation mesh, with its certificate.

    Attributes
    ----------
    solution : ocp.Solution
        On the last mesh (its ``convergence``, ``objective_error``, ``mesh_converged``).
    certificate : SmoothCertificate
        Its per-arc certificate.
    notes : list of str
        What the route noticed.
    """

    solution: Solution
    certificate: SmoothCertificate
    notes: list[str] = field(default_factory=list)

    @property
    def mesh_converged(self) -> bool:
        """The mesh refinement met its tolerances, confirmed on the mesh halved."""
        return bool(self.solution.mesh_converged)

    @property
    def convergence(self) -> str:
        """In words: ``"converged (mesh, estimated error 3e-09)"`` or what is not."""
        return self.solution.convergence

    @property
    def objective_error(self) -> float:
        """The estimate of the objective's absolute error."""
        return float(self.solution.objective_error)

    def reasons(self) -> list[str]:
        """Why it cannot be taken as proven (empty: converged and certified)."""
        out = []
        if not self.mesh_converged:
            out.append(f"the smooth optimum is {self.convergence}")
        if not self.certificate.certified:
            why = f": {self.certificate.reasons[0]}" if self.certificate.reasons else ""
            out.append(f"PMP certificate {self.certificate.verdict}{why}")
        return out

    def rows(self) -> list[tuple[str, object]]:
        """The rows it adds to a result's table."""
        return [("smooth optimum", "interior arcs: converged on a refined collocation mesh"),
                ("mesh", self.convergence),
                ("objective error estimate", self.objective_error),
                ("mesh intervals per phase", ", ".join(str(len(m) - 1) for m in
                                                       self.solution.transcription.meshes))]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (the certificate is under ``pmp`` with ``--pmp``)."""
        e = self.objective_error
        return {"convergence": self.convergence, "mesh_converged": self.mesh_converged,
                "objective_error": e if math.isfinite(e) else None,
                "certificate_verdict": self.certificate.verdict,
                "intervals": [len(m) - 1 for m in self.solution.transcription.meshes]}


def solve_smooth(start: Solution, params: dict[str, float], notes: list[str],
                 tol: float = MESH_TOL) -> SmoothOptimum | None:
    """The problem of ``start`` by collocation, its mesh refined to ``tol``, certified.

    Parameters
    ----------
    start : ocp.Solution
        The transcribed (shooting) solution: the problem and the first guess.
    params : dict
        Parameter values.
    notes : list of str
        Receives what was done, or why there is no smooth optimum (None then).
    tol : float
        Requested accuracy (:meth:`ocp.Collocation.refine`).
    """
    mp = start.transcription.problem
    col = Collocation(mp, intervals=[FIRST_INTERVALS] * len(start.phases))
    try:
        sol = col.refine(params, tol=tol, guess=start.trajectory(400))
    except SolveError as err:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        notes.append(f"the smooth optimum's mesh refinement failed ({err.status}); "
                     "reporting the transcribed solution")
        return None
    notes.append("interior arcs (a continuous force): no switching times to refine; "
                 f"solved by collocation, {sol.convergence}")
    return SmoothOptimum(sol, certify_smooth(sol))


__all__ = ["FIRST_INTERVALS", "MESH_TOL", "SmoothCertificate", "SmoothOptimum",
           "certify_smooth", "convex_in_control", "is_smooth", "solve_smooth"]
