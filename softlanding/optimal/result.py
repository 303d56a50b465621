"""The result of a phased landing: the fields, checks and JSON every variant shares.

Each variant's result (:class:`~softlanding.optimal.two_phase.TwoPhaseLanding`,
:class:`~softlanding.optimal.leg_extension.LegExtensionLanding`, a user's own) subclasses
:class:`PhasedLanding`, adds its own fields, and fills three class-level hooks: the variant's
name in JSON, what its depth is compared with, and any checks of its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from ocp import Solution
from ocp.structure.phase_refinement import RefinedPhases
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.smooth import SmoothOptimum
from softlanding.optimal.verification import certificate_reasons, refined_result_reasons
from softlanding.simulation.simulator import LandingResult
from softlanding.util.jsonable import json_safe


@dataclass(kw_only=True)
class PhasedLanding:
    """A solved phased landing.

    Attributes
    ----------
    robot, impact : Robot, Impact
        The problem solved.
    depth : float
        Final depth ``-x_f``, refined unless refinement was off or failed.
    depth_transcribed : float
        From the transcription (NaN on the structure path).
    paper_depth : float
        The reference the variant improves on (the paper's optimum, or the two-phase one
        with the paper's initial condition): ``gain = paper_depth - depth``.
    arcs : list of list of str
        Arc kinds per phase.
    switch_times : list of list of float
        Switch times per phase (absolute).
    phase_times : list of float
        Start of every phase, then the end of the last.
    status, iterations, solve_time_s
        Of the solve that produced the result.
    refined : RefinedPhases or None
        The phases refined with exact arcs.
    transcribed : ocp.Solution or None
        The transcription (None on the structure path).
    replay : LandingResult or None
        The schedule replayed in the exact simulator.
    replay_kind : str
        The simulator controller used (or why there is no replay).
    notes : list of str
        What the solve noticed.
    path : str
        ``"transcription"`` or ``"structure"`` (the neighbour's arcs re-solved directly).
    refine_requested : bool
        Whether the switching times were to be refined (False: ``refine=False``, and a
        transcribed result is then what was asked for, not a failure).
    smooth : SmoothOptimum or None
        A smooth optimum (interior arcs: a continuous force, no switching times): the
        collocation solution it was converged on (``transcribed`` is that solution), its
        mesh's convergence and its per-arc certificate
        (:mod:`softlanding.optimal.smooth`), the same with or without ``refine``.
    """

    VARIANT: ClassVar[str] = ""
    """The variant's name in JSON and on the command line."""
    WORSE_THAN_REFERENCE: ClassVar[str] = "the reference by {:.2e}: a local optimum"
    """How to say that ``depth`` is worse than ``paper_depth`` ({} is the gap)."""
    LABEL: ClassVar[str] = "phased landing"
    """What the figure's title calls it."""
    REFERENCE: ClassVar[str] = "paper's depth (same v0)"
    """What the table calls ``paper_depth``."""

    robot: Robot
    impact: Impact
    depth: float
    depth_transcribed: float
    paper_depth: float
    arcs: list[list[str]]
    switch_times: list[list[float]]
    phase_times: list[float]
    status: str
    iterations: int
    solve_time_s: float
    refined: RefinedPhases | None
    transcribed: Solution | None
    replay: LandingResult | None = None
    replay_kind: str = ""
    notes: list[str] = field(default_factory=list)
    path: str = "transcription"
    refine_requested: bool = True
    smooth: SmoothOptimum | None = None

    @property
    def certified_transcription(self) -> Solution | None:
        """The transcription ``refined`` was refined from (what the certificate reads)."""
        return self.transcribed

    @property
    def label(self) -> str:
        """What the figure's title calls this landing (default :attr:`LABEL`)."""
        return self.LABEL

    def certify(self) -> Any:
        """The PMP certificate of the refined phases (None without a refinement: see
        :meth:`uncertified_reason`)."""
        from ocp.certificate.phases import certify_phases

        if self.smooth is not None:
            return self.smooth.certificate
        if self.refined is None or self.certified_transcription is None:
            return None
        return certify_phases(self.certified_transcription, self.refined)

    def uncertified_reason(self) -> str:
        """One line: why :meth:`certify` gives no certificate (empty when it gives one)."""
        if self.smooth is not None:
            return ""
        if self.refined is None:
            if not self.refine_requested:
                return "no PMP certificate: the switching times were not refined (--no-refine)"
            why = "; ".join(n for n in self.notes if "refin" in n) or "see the notes"
            return f"no PMP certificate: the switching times could not be refined ({why})"
        if self.certified_transcription is None:
            return ("no PMP certificate: the refined structure was re-solved from a "
                    "neighbour's, without a transcription to read costates from")
        return ""

    @property
    def force_bound(self) -> float:
        """The largest ``|u|`` the landing may apply: the robot's force limit (a variant
        that bounds the force otherwise, e.g. by a decision variable, says so here)."""
        return math.inf if self.robot.u_max is None else float(self.robot.u_max)

    @property
    def gain(self) -> float:
        """``paper_depth - depth``: what the variant gains (>= 0 up to rounding)."""
        return self.paper_depth - self.depth

    @property
    def replay_difference(self) -> float:
        """``|replay depth - depth|`` (NaN without a replay)."""
        return abs(self.replay.depth - self.depth) if self.replay is not None else math.nan

    def own_reasons(self) -> list[str]:
        """The variant's own reasons to doubt the result (none by default)."""
        return []

    def unverified_reasons(self, certificate: Any = None) -> list[str]:
        """Why this result cannot be taken as proven (empty: every check passed).

        Parameters
        ----------
        certificate : ocp.certificate.phases.PhasesCertificate, optional
            The certificate of this solution.
        """
        out = refined_result_reasons(
            self.refined is not None, self.notes, self.replay, self.replay_kind, self.depth,
            self.gain, self.WORSE_THAN_REFERENCE)
        if not self.refine_requested or self.smooth is not None:
            # a transcribed result is what was asked for; a smooth optimum has no
            # switching times, its mesh's convergence and certificate stand instead
            out = [r for r in out if not r.startswith("switching times not refined")]
        if self.smooth is not None:
            out += self.smooth.reasons()
            if certificate is self.smooth.certificate:
                certificate = None  # (its verdict is among the smooth reasons)
        return out + self.own_reasons() + certificate_reasons(certificate)

    def own_dict(self) -> dict[str, Any]:
        """The variant's own JSON fields (none by default)."""
        return {}

    def own_rows(self) -> list[tuple[str, object]]:
        """The variant's own table rows (none by default)."""
        return []

    def rows(self) -> list[tuple[str, object]]:
        """The ``label, value`` rows of the printed table."""
        rows: list[tuple[str, object]] = [
            ("variant", self.VARIANT),
            ("depth -x_f" + (" (refined)" if self.refined is not None else ""), self.depth),
            ("depth, transcribed", self.depth_transcribed), (self.REFERENCE, self.paper_depth)]
        rows += self.own_rows()
        rows += self.smooth.rows() if self.smooth is not None else []
        rows += [("arcs per phase", " | ".join(" -> ".join(a) for a in self.arcs) or "-"),
                 ("phase start times", ", ".join(f"{t:.9g}" for t in self.phase_times)),
                 ("solved by", self.path), ("Ipopt status", self.status)]
        if self.replay is not None:
            rows += [("simulator replay depth", self.replay.depth),
                     ("replay difference", self.replay_difference),
                     ("replay controller", self.replay_kind)]
        return rows

    def figures(self, certificate: Any = None) -> list[Any]:
        """The figures ``--plot`` writes: the landing, phases shaded.

        Parameters
        ----------
        certificate : PhasesCertificate, optional
            Not drawn (the phases' certificate is printed).
        """
        from softlanding.plots.phased import plot_phased_landing

        return [plot_phased_landing(self)]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: the figures, the refined phases and the replay."""
        d: dict[str, Any] = {
            "variant": self.VARIANT, "depth": self.depth,
            "depth_transcribed": self.depth_transcribed, "paper_depth": self.paper_depth,
            "gain": self.gain, "arcs": self.arcs, "switch_times": self.switch_times,
            "phase_times": self.phase_times, "status": self.status,
            "iterations": self.iterations, "solve_time_s": self.solve_time_s,
            "path": self.path, "notes": self.notes, "robot": self.robot.to_dict(),
            "impact": self.impact.to_dict(), **self.own_dict()}
        if self.refined is not None:
            d["refined"] = self.refined.to_dict()
        if self.smooth is not None:
            d["smooth"] = self.smooth.to_dict()
        if self.replay is not None:
            d["replay"] = {"depth": self.replay.depth, "difference": self.replay_difference,
                           "controller": self.replay_kind, "steps": self.replay.steps,
                           "feasible": self.replay.feasible, "status": self.replay.status}
        return json_safe(d)


__all__ = ["PhasedLanding"]
