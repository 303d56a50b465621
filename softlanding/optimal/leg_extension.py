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

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ocp import Solution, Trajectory
from ocp.structure.phase_refinement import RefinedPhases
from softlanding.errors import ParameterError, expect, plain
from softlanding.model.dynamics import mode_matrices
from softlanding.model.ground import LINEAR_GROUND
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal import leg_extension_problem as problem
from softlanding.optimal import pipeline
from softlanding.optimal.limits import force_limit
from softlanding.optimal.phase_schedule import (
    ArcLaw,
    arc_laws,
    propagate,
    replay_controller,
    transcribed_controller,
)
from softlanding.optimal.phase_solve import phase_guess, second_start
from softlanding.optimal.result import PhasedLanding
from softlanding.optimal.two_phase import TwoPhaseLanding, solve_two_phase
from softlanding.simulation.simulator import simulate


@dataclass(kw_only=True)
class LegExtensionLanding(PhasedLanding):
    """A landing whose touchdown leg state was optimised.

    The fields shared by every phased landing are :class:`~softlanding.optimal.result.
    PhasedLanding`'s (``impact.v0``: the centre of mass's impact velocity in
    ``mode="impact"``, the unactuated drop's in ``mode="drop"``; ``paper_depth``: the depth
    with the paper's initial condition, leg ``s/2`` and no relative velocity, i.e. the
    two-phase optimum, equal to the paper's; ``replay``: the landing replayed in the exact
    simulator from the touchdown state).

    Attributes
    ----------
    mode : str
        ``"impact"`` or ``"drop"``.
    bounds : dict
        ``l_min, l_max, w_min, w_max`` (``mode="impact"``).
    extension, rate : float
        Leg length ``x_b - x_f`` and relative velocity ``v_b - v_f`` at touchdown.
    touchdown : ndarray (4,)
        State at touchdown.
    com_velocity : float
        Centre of mass's velocity at touchdown.
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

    VARIANT: ClassVar[str] = "leg-extension"
    REFERENCE: ClassVar[str] = "paper's depth (same v0)"
    WORSE_THAN_REFERENCE: ClassVar[str] = (
        "with the paper's initial condition by {:.2e}: a local optimum (the paper's "
        "touchdown state is admissible)")

    mode: str
    bounds: dict[str, float]
    extension: float
    rate: float
    touchdown: np.ndarray
    com_velocity: float
    flight_check: float = math.nan
    flight_arcs: list[ArcLaw] = field(default_factory=list)
    refined_of: Solution | None = None

    @property
    def certified_transcription(self) -> Solution | None:
        """The transcription ``refined`` was refined from (``refined_of``)."""
        return self.refined_of

    def own_reasons(self) -> list[str]:
        """A drop's flight arcs must reach the touchdown state exactly."""
        if self.mode == "drop" and not self.flight_check <= 1e-9 * max(1.0, abs(
                self.impact.v0) ** 2):
            return [f"the flight arcs propagated exactly miss the touchdown state by "
                    f"{self.flight_check:.2e}"]
        return []

    @property
    def label(self) -> str:
        """``leg extension (mode)``."""
        return f"leg extension ({self.mode})"

    def own_rows(self) -> list[tuple[str, object]]:
        """The touchdown state's rows of the table."""
        return [("mode", self.mode), ("leg length at touchdown", self.extension),
                ("relative velocity at touchdown", self.rate),
                ("centre of mass velocity at touchdown", self.com_velocity),
                ("depth gained", self.gain)]

    def own_dict(self) -> dict[str, Any]:
        """The leg-extension fields of the JSON."""
        return {"mode": self.mode, "bounds": self.bounds, "extension": self.extension,
                "rate": self.rate, "touchdown": self.touchdown.tolist(),
                "com_velocity": self.com_velocity, "flight_check": self.flight_check}


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
        given = f"{plain(lmin)}" if lmin == lmax else f"({plain(lmin)}, {plain(lmax)})"
        raise ParameterError("extension", f"the leg length at impact must lie within the "
                                          f"stroke [0, {robot.s:g}], got {given}")
    wmin, wmax = pair("rate", rate, (0.0, 0.0))
    return {"l_min": lmin, "l_max": lmax, "w_min": wmin, "w_max": wmax}


def _guess(two: TwoPhaseLanding, mode: str, robot: Robot, impact: Impact) -> Trajectory:
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
    """Flight arcs propagated exactly (drop), then the landing in the exact simulator (the
    refined arcs, or the transcription's piecewise-constant force)."""
    if out.refined is None and out.transcribed is None:
        out.replay_kind = "no schedule"
        return
    if out.mode == "drop" and out.refined is None:
        assert out.transcribed is not None
        out.flight_arcs = _transcribed_flight(out.transcribed)
    x0 = out.touchdown
    if out.mode == "drop":
        x0 = _flight_touchdown(out)
        out.flight_check = float(np.max(np.abs(x0 - out.touchdown)))
    try:
        if out.refined is not None:
            first = len(out.refined.phases) - 2  # the yielding phase
            ctrl, kind = replay_controller(out.refined, out.robot.body_mass, first)
        else:
            assert out.transcribed is not None
            ctrl, kind = transcribed_controller(out.transcribed, out.robot.body_mass,
                                                len(out.transcribed.phases) - 2,
                                                u_max=out.force_bound)
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
                  two: TwoPhaseLanding) -> LegExtensionLanding:
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


class LegExtension(pipeline.PhasedVariant):
    """The leg extension's hooks in the pipeline
    (:func:`~softlanding.optimal.pipeline.solve_phased`).

    Parameters
    ----------
    robot, impact
        The problem.
    mode : {"impact", "drop"}
        See :func:`solve_leg_extension`.
    bounds : dict
        ``l_min, l_max, w_min, w_max`` (``mode="impact"``).
    two : TwoPhaseLanding
        The two-phase optimum with the paper's initial condition (guess and reference).
    """

    default_start = True
    """The two-phase guess can mislead Ipopt: seen after another variant's solve in the same
    process, ``v0 = -1`` at an extension of 10 stopped at Restoration_Failed from it (the
    guess 1e-16 apart from one that converges); the default start then converges."""

    def __init__(self, robot: Robot, impact: Impact, mode: str, bounds: dict[str, float],
                 two: TwoPhaseLanding) -> None:
        super().__init__(robot, impact)
        self.mode, self.bounds, self.two = mode, bounds, two
        self.refine = True  # False: a drop's non-unique flight is not re-solved either

    def parameters(self) -> dict[str, float]:
        """The landing's parameters, the touchdown bounds, the paper's leg in ``impact``."""
        params = {**pipeline.landing_parameters(self.robot, self.impact), **self.bounds}
        if self.mode == "impact":
            params["l0"] = self.robot.replace(l0=None).rest_length
        return params

    def transcription(self) -> Any:
        """The leg-extension transcription of this mode (unrefined: the one with the path
        constraints imposed between the nodes too, as the replay of its force checks)."""
        if not self.refine:
            return problem.leg_extension_transcription_inner(self.mode)
        return problem.leg_extension_transcription(self.mode)

    def guess(self) -> Any:
        """The two-phase optimum (after a free fall in ``drop``), see :func:`_guess`."""
        return _guess(self.two, self.mode, self.robot, self.impact)

    def accepts(self, neighbour: Any) -> bool:
        """Only a neighbour of the same mode."""
        return getattr(neighbour, "mode", None) == self.mode

    def bound(self) -> float | None:
        """The two-phase depth (the paper's touchdown state is admissible)."""
        return self.two.depth

    def retry(self, sol: Solution, ref: RefinedPhases | None, guess: Any,
              notes: list[str]) -> tuple[Solution, RefinedPhases | None]:
        """A second start from the inner transcription when the refinement failed."""
        if ref is not None:
            return sol, ref
        return second_start(problem.leg_extension_transcription_inner(self.mode),
                            problem.leg_extension_transcription(self.mode), self.parameters(),
                            guess, sol, notes)

    def assemble(self, sol: Solution | None, ref: RefinedPhases | None, notes: list[str],
                 path: str) -> LegExtensionLanding:
        """The result (see :func:`_assemble`)."""
        out = _assemble(self.robot, self.impact, self.mode, self.bounds, sol, ref,
                        self.two.depth, notes, path)
        if self.mode == "drop" and ref is not None:
            out.flight_arcs = [a for a in arc_laws(ref) if a.phase == 0]
        return out

    def finish(self, result: Any) -> Any:
        """A drop whose flight force is not unique: fix the flight, refine the landing."""
        if self.mode == "drop" and result.refined is None and self.refine:
            return _fixed_flight(result, self.robot, self.impact, self.two)
        return result

    def replay(self, result: Any) -> None:
        """See :func:`_replay`."""
        _replay(result)


def solve_leg_extension(impact: Impact | float, robot: Robot = PAPER_ROBOT, *,
                        mode: str = "impact", extension: Any = None, rate: Any = None,
                        warm_start: LegExtensionLanding | None = None, replay: bool = True,
                        two_phase: TwoPhaseLanding | None = None,
                        refine: bool = True) -> LegExtensionLanding:
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
    two_phase : TwoPhaseLanding, optional
        The two-phase optimum with the paper's initial condition (solved if not given).
    refine : bool
        Refine the switching times of every phase with exact arcs (False: the
        transcription, replayed as its piecewise-constant force).

    Raises
    ------
    ParameterError
        Bad parameters (e.g. an extension outside the stroke, ``v0 = 0`` for a drop).
    InfeasibleLandingError
        No landing satisfies the constraints.
    """
    impact = Impact.of(impact)
    force_limit(robot)
    if warm_start is not None:
        expect("warm_start", warm_start, LegExtensionLanding,
               "LegExtensionLanding (solve_leg_extension's)")
    if mode not in problem.MODES:
        raise ParameterError("mode", f"must be one of {problem.MODES}, got {mode!r}")
    if mode == "drop" and impact.v0 >= 0:
        raise ParameterError("v0", "a drop needs a height: v0 < 0")
    bounds = _bounds(robot, extension, rate) if mode == "impact" else {}
    two = two_phase if two_phase is not None else solve_two_phase(impact, robot.replace(l0=None))
    hooks = LegExtension(robot, impact, mode, bounds, two)
    hooks.refine = refine
    out = pipeline.solve_phased(hooks, warm_start, refine=refine, replay=replay)
    assert isinstance(out, LegExtensionLanding)
    return out


def solve_leg_extension_variant(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                                ground: Any = LINEAR_GROUND, *, refine: bool = True,
                                warm_start: Any = None, mode: str = "impact",
                                extension: Any = "free",
                                rate_max: float | None = 0.0) -> LegExtensionLanding:
    """``--variant leg-extension`` (see :mod:`softlanding.optimal.builtin_variants`):
    :func:`solve_leg_extension` with the command line's options.

    Parameters
    ----------
    impact, robot, refine, mode
        As :func:`solve_leg_extension`.
    ground : Ground
        Only the paper's linear ground.
    warm_start : LegExtensionLanding, optional
        A neighbour of the same mode (continuation; anything else is not used).
    extension : "free" or float
        The leg length at impact, or free within the stroke.
    rate_max : float, optional
        Free the relative velocity at impact within ``+-rate_max`` (0 or None: it is 0,
        the paper's).
    """
    if ground != LINEAR_GROUND:
        raise ParameterError("ground", "leg extension takes only the paper's linear ground")
    warm = warm_start if isinstance(warm_start, LegExtensionLanding) else None
    return solve_leg_extension(
        impact, robot, mode=mode, extension=None if extension == "free" else extension,
        rate=(-rate_max, rate_max) if rate_max else None, warm_start=warm,
        refine=refine)


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
    last_two: list[TwoPhaseLanding] = []  # the two-phase sweep alongside, by continuation

    def one(imp: Impact, prev: LegExtensionLanding | None) -> LegExtensionLanding:
        two = solve_two_phase(imp, robot.replace(l0=None),
                              warm_start=last_two[-1] if last_two else None, replay=False)
        keep = two
        if two.transcribed is None and last_two:
            keep = dataclasses.replace(two, transcribed=last_two[-1].transcribed)
        last_two[:] = [keep]
        return solve_leg_extension(imp, robot, mode=mode, extension=extension, rate=rate,
                                   warm_start=prev, two_phase=two)

    return pipeline.continuation(impacts, one, progress, f"leg extension ({mode})")


__all__ = ["LegExtension", "LegExtensionLanding", "solve_leg_extension",
           "solve_leg_extension_variant", "sweep_leg_extension"]
