"""Pre-impact leg extension: the landing with the leg's state at touchdown optimised.

**This changes the paper's initial condition** (see
:mod:`softlanding.optimal.leg_extension_problem` for both formulations). :func:`solve_leg_extension`
starts from the full two-phase landing at the paper's ``l0 = s/2``
(:func:`softlanding.optimal.two_phase.solve_two_phase`), solves the transcription, refines
every phase with exact arcs (a stroke touch point where the leg reaches full
extension is imposed exactly) and replays the landing in the exact simulator
from the refined touchdown state (after, in ``mode="drop"``, propagating the
release state through the refined flight arcs exactly with the flight mode's
matrix exponential). :func:`sweep_leg_extension` sweeps impact velocities by
continuation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp import Solution, Trajectory
from ocp.phase_refinement import RefinedPhases
from softlanding.errors import ParameterError
from softlanding.model.dynamics import mode_matrices
from softlanding.model.ground import LINEAR_GROUND
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import _ocp_params, _validate
from softlanding.optimal.leg_extension_problem import (
    MODES,
    leg_extension_transcription,
    leg_extension_transcription_inner,
)
from softlanding.optimal.phase_schedule import ArcLaw, arc_laws, propagate, replay_controller
from softlanding.optimal.phase_solve import (
    phase_guess,
    refined_phases,
    second_start,
    structure_resolve,
    transcribed_solve,
)
from softlanding.optimal.two_phase import FullLanding, solve_two_phase
from softlanding.optimal.verification import certificate_reasons, refined_result_reasons
from softlanding.simulation.simulator import LandingResult, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.progress import progress as show_progress


@dataclass
class LegExtensionLanding:
    """A landing whose touchdown leg state was optimised.

    Attributes
    ----------
    robot, impact : Robot, Impact
        The problem (``impact.v0``: the centre of mass's impact velocity in
        ``mode="impact"``, the unactuated drop's in ``mode="drop"``).
    mode : str
        ``"impact"`` or ``"drop"``.
    bounds : dict
        ``l_min, l_max, w_min, w_max`` (``mode="impact"``).
    depth, depth_transcribed : float
        Final depth (refined; transcribed).
    paper_depth : float
        The depth with the paper's initial condition (leg ``s/2``, no relative velocity):
        the two-phase optimum, equal to the paper's.
    extension, rate : float
        Leg length ``x_b - x_f`` and relative velocity ``v_b - v_f`` at touchdown.
    touchdown : ndarray (4,)
        State at touchdown.
    com_velocity : float
        Centre of mass's velocity at touchdown.
    arcs, switch_times, phase_times
        Per phase, as :class:`softlanding.optimal.two_phase.FullLanding`.
    status, iterations, solve_time_s, refined, transcribed, notes, path
        As :class:`softlanding.optimal.two_phase.FullLanding`.
    replay : LandingResult or None
        The landing replayed in the exact simulator from the touchdown state.
    replay_kind : str
        The simulator controller (or why there is no replay).
    flight_check : float
        ``mode="drop"``: largest difference between the touchdown state of the solution
        and the release state propagated exactly through its flight arcs (NaN otherwise).
    flight_arcs : list of ArcLaw
        ``mode="drop"``: the flight's force, arc by arc (refined arcs; or, where the
        flight's force is not unique, the transcription's piecewise-constant force).
    refined_of : ocp.Solution or None
        The transcription ``refined`` was refined from (``transcribed``, or, with a
        non-unique flight, the landing's from the reached touchdown state).
    """

    robot: Robot
    impact: Impact
    mode: str
    bounds: dict[str, float]
    depth: float
    depth_transcribed: float
    paper_depth: float
    extension: float
    rate: float
    touchdown: np.ndarray
    com_velocity: float
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
    flight_check: float = math.nan
    flight_arcs: list[ArcLaw] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    path: str = "transcription"
    refined_of: Solution | None = None

    def certify(self) -> Any:
        """The PMP certificate of the refined phases (None without a refinement)."""
        from ocp.phase_pmp import certify_phases

        if self.refined is None:
            return None
        return certify_phases(self.refined_of, self.refined)

    @property
    def gain(self) -> float:
        """``paper_depth - depth``: the depth gained by the extension."""
        return self.paper_depth - self.depth

    @property
    def replay_difference(self) -> float:
        """``|replay depth - depth|`` (NaN without a replay)."""
        return abs(self.replay.depth - self.depth) if self.replay is not None else math.nan

    def unverified_reasons(self, certificate: Any = None) -> list[str]:
        """Why this result cannot be taken as proven (empty: every check passed).

        Parameters
        ----------
        certificate : ocp.phase_pmp.PhasesCertificate, optional
            The certificate of this solution.
        """
        out = refined_result_reasons(
            self.refined is not None, self.notes, self.replay, self.replay_kind, self.depth,
            self.gain, "with the paper's initial condition by {:.2e}: a local optimum (the "
            "paper's touchdown state is admissible)")
        if self.mode == "drop" and not self.flight_check <= 1e-9 * max(1.0, abs(
                self.impact.v0) ** 2):
            out.append(f"the flight arcs propagated exactly miss the touchdown state by "
                       f"{self.flight_check:.2e}")
        return out + certificate_reasons(certificate)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        d: dict[str, Any] = {
            "variant": "leg-extension", "mode": self.mode, "bounds": self.bounds,
            "depth": self.depth, "depth_transcribed": self.depth_transcribed,
            "paper_depth": self.paper_depth, "gain": self.gain, "extension": self.extension,
            "rate": self.rate, "touchdown": self.touchdown.tolist(),
            "com_velocity": self.com_velocity, "arcs": self.arcs,
            "switch_times": self.switch_times, "phase_times": self.phase_times,
            "status": self.status, "iterations": self.iterations,
            "solve_time_s": self.solve_time_s, "path": self.path, "notes": self.notes,
            "flight_check": self.flight_check, "robot": self.robot.to_dict(),
            "impact": self.impact.to_dict()}
        if self.refined is not None:
            d["refined"] = self.refined.to_dict()
        if self.replay is not None:
            d["replay"] = {"depth": self.replay.depth, "difference": self.replay_difference,
                           "controller": self.replay_kind, "feasible": self.replay.feasible,
                           "status": self.replay.status}
        return json_safe(d)


def _bounds(robot: Robot, extension: Any, rate: Any) -> dict[str, float]:
    """``l_min, l_max, w_min, w_max`` from the user's choices (checked)."""
    def pair(name: str, v: Any, default: tuple[float, float]) -> tuple[float, float]:
        if v is None:
            return default
        lo, hi = (float(v), float(v)) if np.ndim(v) == 0 else (float(v[0]), float(v[1]))
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
            raise ParameterError(name, f"needs a value or a (low, high) pair, got {v!r}")
        return lo, hi

    lmin, lmax = pair("extension", extension, (0.0, robot.s))
    if lmin < 0 or lmax > robot.s:
        raise ParameterError("extension", f"the leg length at impact must lie within the "
                                          f"stroke [0, {robot.s:g}], got [{lmin:g}, {lmax:g}]")
    wmin, wmax = pair("rate", rate, (0.0, 0.0))
    return {"l_min": lmin, "l_max": lmax, "w_min": wmin, "w_max": wmax}


def _guess(two: FullLanding, mode: str, robot: Robot, impact: Impact) -> Trajectory:
    """The paper-condition two-phase optimum (exact arcs), after a free fall in ``drop``."""
    assert two.refined is not None
    tr = two.refined.trajectory(400)
    if mode == "impact":
        return tr
    h = impact.v0 ** 2 / 2
    tf = math.sqrt(2 * h)
    t = np.linspace(0.0, tf, 60)
    fall = np.column_stack([h + robot.rest_length - t**2 / 2, -t, h - t**2 / 2, -t])
    joined = Trajectory(np.r_[t, tr.t + tf], np.vstack([fall, tr.x]),
                        np.r_[np.zeros(len(t)), tr.u[:, 0]][:, None], tr.state_names,
                        tr.control_names)
    return phase_guess(joined, [tf, tf + two.T1])


def _assemble(robot: Robot, impact: Impact, mode: str, bounds: dict, sol: Solution | None,
              ref: RefinedPhases | None, paper_depth: float, notes: list[str],
              path: str) -> LegExtensionLanding:
    iy = 1 if mode == "drop" else 0
    if ref is not None:
        xT, x0 = ref.xT, ref.phases[iy].x0
        times = [float(t) for t in ref.t0] + [ref.T]
        arcs = [[str(k) for k in r.kinds] for r in ref.phases]
        sw = ref.switch_times
    else:
        assert sol is not None
        xT, x0 = sol.phases[-1].x[-1], sol.phases[iy].x[0]
        times = [float(p.t0) for p in sol.phases] + [float(sol.phases[-1].T)]
        arcs, sw = [], []
    mb = robot.body_mass
    src: Any = sol if sol is not None else ref
    return LegExtensionLanding(
        robot=robot, impact=impact, mode=mode, bounds=bounds, depth=float(-xT[2]),
        depth_transcribed=float(-sol.phases[-1].x[-1, 2]) if sol is not None else math.nan,
        paper_depth=paper_depth, extension=float(x0[0] - x0[2]), rate=float(x0[1] - x0[3]),
        touchdown=np.asarray(x0, dtype=float).copy(),
        com_velocity=float(mb * x0[1] + (1 - mb) * x0[3]), arcs=arcs, switch_times=sw,
        phase_times=times, status=src.status, iterations=int(src.iterations),
        solve_time_s=float(src.solve_time), refined=ref, transcribed=sol, notes=notes,
        path=path, refined_of=sol)


def _release(robot: Robot, impact: Impact) -> np.ndarray:
    """The state at release: at rest, leg at ``l0``, foot at the drop height ``v0^2 / 2``."""
    h = impact.v0 ** 2 / 2
    return np.array([h + robot.rest_length, 0.0, h, 0.0])


def _flight_touchdown(out: LegExtensionLanding) -> np.ndarray:
    """The release state propagated exactly through the flight arcs (flight mode's expm)."""
    mats = mode_matrices(out.robot.r_m)
    return propagate(out.flight_arcs, mats["A"][2], mats["B"][2],
                     _release(out.robot, out.impact))


def _replay(out: LegExtensionLanding) -> None:
    """Flight arcs propagated exactly (drop), then the landing in the exact simulator."""
    if out.refined is None:
        out.replay_kind = "no refined schedule"
        return
    x0 = out.touchdown
    if out.mode == "drop":
        x0 = _flight_touchdown(out)
        out.flight_check = float(np.max(np.abs(x0 - out.touchdown)))
    first = len(out.refined.phases) - 2  # the yielding phase
    try:
        ctrl, kind = replay_controller(out.refined, out.robot.body_mass, first)
    except NotImplementedError as err:
        out.replay_kind = str(err)
        return
    out.replay_kind = kind
    robot = out.robot.replace(l0=min(max(float(x0[0] - x0[2]), 0.0), out.robot.s))
    out.replay = simulate(robot, out.impact, ctrl, LINEAR_GROUND, x0=x0)


def _transcribed_flight(sol: Solution) -> list[ArcLaw]:
    """The transcription's flight force (piecewise constant) as arcs."""
    ph = sol.phases[0]
    h = float(ph.T - ph.t0) / ph.N
    return [ArcLaw(0, h, np.r_[0.0, 0.0, 0.0, 0.0, float(u)], float(u), "transcribed")
            for u in ph.u[:, 0]]


def _fixed_flight(out: LegExtensionLanding, robot: Robot, impact: Impact,
                  two: FullLanding) -> LegExtensionLanding:
    """The landing refined from the touchdown state that the transcription's flight force
    reaches exactly (used when the flight's force is not unique, so not refinable)."""
    assert out.transcribed is not None
    out.flight_arcs = _transcribed_flight(out.transcribed)
    x0 = _flight_touchdown(out)
    vc = robot.body_mass * x0[1] + robot.foot_mass * x0[3]
    leg = float(x0[0] - x0[2])
    extra = []
    if not 0.0 <= leg <= robot.s:
        extra.append(f"the transcription's flight ends with the leg at {leg:.9g}, outside "
                     f"the stroke by {max(-leg, leg - robot.s):.1e} (a grid error); clipped")
        leg = min(max(leg, 0.0), robot.s)
    inner = solve_leg_extension(Impact(vc), robot, mode="impact", extension=leg,
                                rate=float(x0[1] - x0[3]), replay=False, two_phase=two)
    notes = out.notes + inner.notes + extra + [
        "the flight's force is not unique (not bang-bang): the flight is the transcription's "
        "piecewise-constant force, propagated exactly; the landing is refined from the "
        "touchdown state it reaches"]
    t_f = sum(a.duration for a in out.flight_arcs)
    return LegExtensionLanding(
        **{**out.__dict__, "depth": inner.depth, "touchdown": inner.touchdown,
           "extension": inner.extension, "rate": inner.rate, "com_velocity": vc,
           "refined": inner.refined, "refined_of": inner.refined_of,
           "arcs": [["transcribed"]] + inner.arcs,
           "switch_times": [[]] + [[t + t_f for t in x] for x in inner.switch_times],
           "phase_times": [0.0] + [t + t_f for t in inner.phase_times], "notes": notes,
           "flight_arcs": out.flight_arcs})


def solve_leg_extension(impact: Impact | float, robot: Robot = PAPER_ROBOT, *,
                        mode: str = "impact", extension: Any = None, rate: Any = None,
                        warm_start: LegExtensionLanding | None = None, replay: bool = True,
                        two_phase: FullLanding | None = None) -> LegExtensionLanding:
    """The minimum-depth landing with the leg's state at touchdown optimised.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity (``mode="drop"``: of the unactuated drop; < 0).
    robot : Robot
        The robot (with a force limit; its ``l0`` is the release leg length in ``drop``).
    mode : {"impact", "drop"}
        Decide the touchdown state directly, or by a flight phase from the drop height.
    extension : float or (float, float), optional
        ``mode="impact"``: the leg length at impact, fixed or bounded (default: the
        stroke, ``(0, s)``; ``s/2`` is the paper's).
    rate : float or (float, float), optional
        ``mode="impact"``: relative velocity ``v_b - v_f`` at impact, fixed or bounded
        (default 0, the paper's).
    warm_start : LegExtensionLanding, optional
        A neighbouring solution (its structure is re-solved directly first).
    replay : bool
        Replay in the exact simulator.
    two_phase : FullLanding, optional
        The two-phase optimum with the paper's initial condition (solved if not given).

    Raises
    ------
    ParameterError
        Bad parameters (e.g. an extension outside the stroke, ``v0 = 0`` for a drop).
    InfeasibleLandingError
        No landing satisfies the constraints.
    """
    impact = Impact.of(impact)
    _validate(robot)
    if mode not in MODES:
        raise ParameterError("mode", f"must be one of {MODES}, got {mode!r}")
    if mode == "drop" and impact.v0 >= 0:
        raise ParameterError("v0", "a drop needs a height: v0 < 0")
    bounds = _bounds(robot, extension, rate) if mode == "impact" else {}
    base = robot.replace(l0=None)
    two = two_phase if two_phase is not None else solve_two_phase(impact, base)
    params = {**_ocp_params(robot, impact), **bounds}
    if mode == "impact":
        params["l0"] = base.rest_length
    notes: list[str] = []
    out = None
    if warm_start is not None and warm_start.refined is not None and warm_start.mode == mode:
        r = structure_resolve(warm_start.refined, params, bound=two.depth)
        if r is not None:
            out = _assemble(robot, impact, mode, bounds, None, r, two.depth, notes,
                            "structure")
    if out is None:
        tr = leg_extension_transcription(mode)
        ws = warm_start.transcribed if warm_start is not None else None
        guess = _guess(two, mode, robot, impact)
        sol = transcribed_solve(tr, params, guess, ws, notes)
        ref = refined_phases(sol, notes)
        if ref is None:
            sol, ref = second_start(leg_extension_transcription_inner(mode),
                                    leg_extension_transcription(mode), params, guess, sol,
                                    notes)
        out = _assemble(robot, impact, mode, bounds, sol, ref, two.depth, notes,
                        "transcription")
        if mode == "drop" and ref is None:
            out = _fixed_flight(out, robot, impact, two)
    if mode == "drop" and not out.flight_arcs and out.refined is not None:
        out.flight_arcs = [a for a in arc_laws(out.refined) if a.phase == 0]
    if replay:
        _replay(out)
    return out


def sweep_leg_extension(v0_values, robot: Robot = PAPER_ROBOT, *, mode: str = "impact",
                        extension: Any = None, rate: Any = None,
                        progress: bool | None = False) -> list[LegExtensionLanding]:
    """Leg extension over impact velocities by continuation (start from the easy end).

    Parameters
    ----------
    v0_values : sequence of float
        Impact velocities.
    robot : Robot
        The robot.
    mode : {"impact", "drop"}
        See :func:`solve_leg_extension`.
    extension, rate : optional
        See :func:`solve_leg_extension`.
    progress : bool, optional
        Progress bar.
    """
    impacts = [Impact.of(v) for v in v0_values]
    out: list[LegExtensionLanding] = []
    prev: LegExtensionLanding | None = None
    prev_two: FullLanding | None = None
    last_sol: Solution | None = None
    for imp in show_progress(impacts, progress, f"leg extension ({mode})", "solve"):
        two = solve_two_phase(imp, robot.replace(l0=None), warm_start=prev_two, replay=False)
        res = solve_leg_extension(imp, robot, mode=mode, extension=extension, rate=rate,
                                  warm_start=prev, two_phase=two)
        out.append(res)
        last_sol = res.transcribed or last_sol
        prev = res if res.transcribed is not None else LegExtensionLanding(
            **{**res.__dict__, "transcribed": last_sol})
        prev_two = two if two.transcribed is not None or prev_two is None else FullLanding(
            **{**two.__dict__, "transcribed": prev_two.transcribed})
    return out


__all__ = ["LegExtensionLanding", "solve_leg_extension", "sweep_leg_extension"]
