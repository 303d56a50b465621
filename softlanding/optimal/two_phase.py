"""The full landing optimised as a hybrid two-phase problem: the body's arrest is optimised
instead of assumed (see :mod:`softlanding.optimal.two_phase_problem` for the formulation).

:func:`solve_two_phase` transcribes the problem (multiple shooting, both phases),
starting from the exact-simulator replay of the paper's single-phase optimum;
refines the switching times of both phases with exact arcs
(:func:`ocp.structure.phase_refinement.refine_phases`); and replays the whole schedule
(yielding arcs, the phase-2 arrest law, then the body's weight) in the exact
simulator. :func:`sweep_two_phase` does this over impact velocities by
continuation, each landing re-solving its neighbour's arc structure directly.

What it finds (r_m = 5, s = 20, u_max = 8.2): the optimal phase-2 force is the
crater's capacity minus the foot's weight, ``u = -x_f(T1) - 1/(1+r_m)``, held
until the body stops at the end of the stroke -- a boundary arc of the mixed
constraint "the crater holds the support force", which is constant because the
foot is pinned. That is the paper's constant ``u_b`` with its arrest condition
active, so the two-phase depth equals the paper's (to rounding).
:func:`two_step_check` asks whether a second yielding step can do better.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ocp import Solution, SolveError, Trajectory
from ocp.structure.phase_refinement import RefinedPhases
from softlanding.errors import InfeasibleLandingError, ParameterError, expect, plain
from softlanding.model.controllers import Rigid
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing import BangBangLanding, solve_landing
from softlanding.optimal.limits import landing_input
from softlanding.optimal.phase_schedule import (
    replay_controller,
    sampled_controller,
    transcribed_controller,
)
from softlanding.optimal.phase_solve import phase_guess, transcribed_solve
from softlanding.optimal.pipeline import (
    PhasedVariant,
    continuation,
    landing_parameters,
    solve_phased,
)
from softlanding.optimal.result import PhasedLanding
from softlanding.optimal.two_phase_problem import OMITTABLE, two_phase_transcription
from softlanding.optimal.verification import at_static_depth, static_depth
from softlanding.simulation.simulator import DEFAULT_MAX_SEGMENTS, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted


@dataclass(kw_only=True)
class TwoPhaseLanding(PhasedLanding):
    """A solved two-phase landing (yielding, then static until the body stops).

    It has the fields of every :class:`~softlanding.optimal.result.PhasedLanding`
    (``paper_depth``: the paper's single-phase optimum, constant-force arrest, for the same
    landing). The replay's ``steps`` may exceed ``steps``: the optimal arrest force equals
    the crater's capacity, so rounding decides whether the resting foot is static or creeps
    (by the replay difference, ~1e-14); the depth is what is checked.

    Attributes
    ----------
    ground : Ground
        The ground model.
    steps : int
        Yielding steps allowed (1: two phases; 2: four).
    T1, T : float
        When the foot stops and when the body stops.
    arrest_force : float
        Mean actuator force of the last (arrest) phase.
    arrest_force_range : (float, float)
        Its smallest and largest value (equal: a constant force).
    """

    VARIANT: ClassVar[str] = "two-phase"
    WORSE_THAN_REFERENCE: ClassVar[str] = (
        "the paper's single-phase optimum by {:.2e}: a local optimum (the paper's constant "
        "arrest is admissible)")

    ground: Ground
    steps: int
    T1: float
    T: float
    arrest_force: float
    arrest_force_range: tuple[float, float]

    LABEL: ClassVar[str] = "two-phase landing"

    def own_rows(self) -> list[tuple[str, object]]:
        """The arrest's rows of the table."""
        return [("yielding steps allowed", self.steps), ("foot stops T1", self.T1),
                ("body stops T", self.T), ("arrest force (phase 2)", self.arrest_force),
                ("arrest force range",
                 "{:.12g} .. {:.12g}".format(*self.arrest_force_range))]

    def own_dict(self) -> dict[str, Any]:
        """The two-phase fields of the JSON."""
        return {"steps": self.steps, "T1": self.T1, "T": self.T,
                "arrest_force": self.arrest_force,
                "arrest_force_range": list(self.arrest_force_range),
                "ground": self.ground.to_dict()}


# ------------------------------------------------------------------- guesses
def _guess(robot: Robot, impact: Impact, ground: Ground, paper: BangBangLanding | None,
           steps: int) -> Any:
    """The paper's optimum (its refined arcs, then the constant-force arrest, exactly), or
    a rigid landing, cut into the phases."""
    if paper is not None and paper.refined is not None:
        tr = paper.refined.trajectory(300)
        T1, xT = paper.T, paper.refined.xT
        L, v = xT[0] - xT[2], xT[1]
        a = v * v / (2 * L) if v < 0 else 0.0
        t2 = np.linspace(0.0, -v / a if a > 0 else 1.0, 200)[1:]
        x2 = np.column_stack([xT[0] + v * t2 + 0.5 * a * t2**2, v + a * t2,
                              np.full_like(t2, xT[2]), np.zeros_like(t2)])
        traj = Trajectory(np.r_[tr.t, T1 + t2], np.vstack([tr.x, x2]),
                          np.r_[tr.u[:, 0], np.full(len(t2), paper.u_b)][:, None],
                          tr.state_names, tr.control_names)
    else:
        res = simulate(robot.without_force_limit(), impact, Rigid(), ground)
        T1 = res.t_first_stop if math.isfinite(res.t_first_stop) else 1.0
        traj = res.trajectory(t_end=T1 + 1.0, n=400)
    if steps == 1:
        return phase_guess(traj, [T1])
    late = traj.t > T1
    shifted = Trajectory(np.where(late, traj.t + 2e-3, traj.t), traj.x, traj.u,
                         traj.state_names, traj.control_names)
    return phase_guess(shifted, [T1, T1 + 1e-3, T1 + 2e-3])


def _explain(err: SolveError, robot: Robot, impact: Impact, ground: Ground, steps: int,
             guess: Any) -> InfeasibleLandingError:
    """Name the condition(s) whose removal makes the request feasible."""
    params = landing_parameters(robot, impact)
    culprits = []
    for name in OMITTABLE:
        try:
            two_phase_transcription(steps, ground=ground, omit=(name,)).solve(params, guess=guess)
            culprits.append(name)
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            continue
    why = (" or ".join(culprits) + " cannot be met together with the other conditions"
           if culprits else "the conditions cannot all be met (dropping the crater or the "
           "stroke condition of the arrest does not help)")
    return InfeasibleLandingError(
        f"no two-phase landing at v0={impact.v0:g}, r_m={robot.r_m:g}, s={robot.s:g}, "
        f"u_max={robot.u_max:g}: {why} (Ipopt: {err.status})")


class TwoPhase(PhasedVariant):
    """The two-phase landing's hooks in the pipeline
    (:func:`~softlanding.optimal.pipeline.solve_phased`).

    Parameters
    ----------
    robot, impact, ground
        The problem.
    steps : {1, 2}
        Yielding steps allowed.
    paper : BangBangLanding or None
        The paper's optimum for the same landing (the guess and the reference).
    """

    def __init__(self, robot: Robot, impact: Impact, ground: Ground, steps: int,
                 paper: BangBangLanding | None) -> None:
        super().__init__(robot, impact)
        self.ground, self.steps, self.paper = ground, steps, paper
        self.paper_depth = paper.depth if paper is not None else math.nan

    def transcription(self) -> Any:
        """The two-phase (or four-phase) transcription on this ground."""
        return two_phase_transcription(self.steps, ground=self.ground)

    def guess(self) -> Any:
        """The paper's optimum cut into the phases (see :func:`_guess`)."""
        return _guess(self.robot, self.impact, self.ground, self.paper, self.steps)

    def accepts(self, neighbour: Any) -> bool:
        """Only a neighbour with as many steps."""
        return getattr(neighbour, "steps", None) == self.steps

    def bound(self) -> float | None:
        """The paper's depth (admissible here)."""
        return self.paper_depth if math.isfinite(self.paper_depth) else None

    def explain(self, err: SolveError, guess: Any) -> Exception:
        """Name the conditions that make the request infeasible (see :func:`_explain`)."""
        return _explain(err, self.robot, self.impact, self.ground, self.steps, guess)

    def assemble(self, sol: Solution | None, ref: RefinedPhases | None, notes: list[str],
                 path: str) -> TwoPhaseLanding:
        """The result from the transcription and/or the refined phases."""
        if ref is not None:
            xT = ref.xT
            times = [float(t) for t in ref.t0] + [ref.T]
            arcs = [[str(k) for k in r.kinds] for r in ref.phases]
            sw = ref.switch_times
            u = ref.phases[-1].trajectory(200).u[:, 0]
        else:
            assert sol is not None
            xT = sol.phases[-1].x[-1]
            times = [float(p.t0) for p in sol.phases] + [float(sol.phases[-1].T)]
            arcs, sw = [], []
            u = sol.phases[-1].u[:, 0]
        src: Any = sol if sol is not None else ref
        return TwoPhaseLanding(
            robot=self.robot, impact=self.impact, ground=self.ground, steps=self.steps,
            depth=float(-xT[2]),
            depth_transcribed=float(-sol.phases[-1].x[-1, 2]) if sol is not None else math.nan,
            paper_depth=self.paper_depth, T1=times[1], T=times[-1], arcs=arcs,
            switch_times=sw, phase_times=times, arrest_force=float(np.mean(u)),
            arrest_force_range=(float(np.min(u)), float(np.max(u))), status=src.status,
            iterations=int(src.iterations), solve_time_s=float(src.solve_time), refined=ref,
            transcribed=sol, notes=notes, path=path)

    def replay(self, result: Any) -> None:
        """Replay the refined (or transcribed) schedule in the exact simulator, in place."""
        tail = result.robot.body_mass
        try:
            if result.refined is not None:
                ctrl, kind = replay_controller(result.refined, tail)
            elif result.smooth is not None:  # a continuous force, finely sampled
                ctrl, kind = sampled_controller(result.transcribed, tail,
                                                u_max=result.force_bound)
            else:
                assert result.transcribed is not None
                ctrl, kind = transcribed_controller(result.transcribed, tail,
                                                    u_max=result.force_bound)
        except NotImplementedError as err:
            result.replay_kind = str(err)
            return
        result.replay_kind = kind
        pieces = len(getattr(ctrl, "times", ()))  # a schedule: one segment or more a piece
        result.replay = simulate(result.robot, result.impact, ctrl, result.ground,
                                 max_segments=max(DEFAULT_MAX_SEGMENTS, 2 * pieces + 100))


def solve_two_phase(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                    ground: Ground = LINEAR_GROUND, *, steps: int = 1, refine: bool = True,
                    warm_start: TwoPhaseLanding | None = None, replay: bool = True,
                    paper: BangBangLanding | None = None) -> TwoPhaseLanding:
    """Solve the full landing as a hybrid multi-phase OCP; refine; replay exactly.

    Parameters
    ----------
    impact, robot, ground
        The landing, as in :func:`~softlanding.optimal.landing.solve_landing`.
    steps : {1, 2}
        Yielding steps allowed (2: yielding, static, yielding, static).
    refine : bool
        Refine the switching times of every phase with exact arcs.
    warm_start : TwoPhaseLanding, optional
        A neighbouring solution: its refined structure is re-solved directly first, then
        its transcription warm-starts the NLP.
    replay : bool
        Replay the whole schedule in the exact simulator.
    paper : BangBangLanding, optional
        The paper's single-phase optimum for this landing (solved if not given): the
        starting guess and the comparison.

    Raises
    ------
    ParameterError
        Bad parameters.
    InfeasibleLandingError
        No landing satisfies the constraints (the message names the condition).
    """
    impact = Impact.of(impact)
    landing_input(robot, ground)
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps not in (1, 2):
        raise ParameterError("steps", f"must be 1 or 2, got {plain(steps)}")
    if warm_start is not None:
        expect("warm_start", warm_start, TwoPhaseLanding, "TwoPhaseLanding (solve_two_phase's)")
    if paper is None:
        try:
            paper = solve_landing(impact, robot, ground)
        except InfeasibleLandingError as err:
            # the same yielding phases are admissible in both problems: the static phase
            # stops a descending body inside the stroke with |u| <= u_max and a support
            # force within the crater's capacity exactly when the paper's arrest force
            # u_b <= min(u_max, capacity - foot weight) exists
            raise InfeasibleLandingError(
                f"no two-phase landing either: {err} (a phase-2 arrest within the force "
                "limit and the crater's capacity exists exactly when the paper's does)"
            ) from None
    try:
        out = solve_phased(TwoPhase(robot, impact, ground, steps, paper), warm_start,
                           refine=refine, replay=replay)
    except SolveError as err:
        bound = static_depth(ground)
        if not at_static_depth(paper.depth, bound):
            raise
        # the static phase has no margin there (the arrest force is the body's weight):
        # say so, not only the scaling of the last iterate
        raise type(err)(err.status, err.iterate, f"{err}; the single-phase landing already "
                        f"stops at the static depth W/K = {bound:.10g}, the least at which "
                        "any landing comes to rest, so no two-phase landing stops shallower "
                        "(its static phase would hold the robot's weight with no margin)"
                        ) from err
    assert isinstance(out, TwoPhaseLanding)
    return out


def solve_two_phase_variant(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                            ground: Ground = LINEAR_GROUND, *, refine: bool = True,
                            warm_start: Any = None, steps: int = 1) -> Any:
    """``--variant two-phase``: :func:`solve_two_phase`, or with ``steps=2``
    :func:`two_step_check` (the variant's solve function, see
    :mod:`softlanding.optimal.builtin_variants`).

    Parameters
    ----------
    impact, robot, ground, refine
        As :func:`solve_two_phase`.
    warm_start : TwoPhaseLanding, optional
        A neighbour (continuation; anything else is not used).
    steps : {1, 2}
        Yielding steps allowed.
    """
    if steps == 2:
        return two_step_check(impact, robot, ground)
    warm = warm_start if isinstance(warm_start, TwoPhaseLanding) and \
        warm_start.steps == 1 else None
    return solve_two_phase(impact, robot, ground, refine=refine, warm_start=warm)


def sweep_two_phase(v0_values, robot: Robot = PAPER_ROBOT, ground: Ground = LINEAR_GROUND, *,
                    progress: bool | None = False,
                    replay: bool = True) -> list[TwoPhaseLanding]:
    """The full landing over impact velocities, by continuation (start from the easy end).

    Each velocity also solves the paper's single-phase problem (continuation too) for the
    comparison ``gain``.

    Parameters
    ----------
    v0_values, robot, ground, progress, replay
        As :func:`~softlanding.optimal.landing.sweep_landing` (``replay``: every schedule
        in the exact simulator).
    """
    impacts = [Impact.of(v) for v in v0_values]
    landing_input(robot, ground)

    last_paper: list[BangBangLanding] = []  # the paper's sweep, alongside

    def one(imp: Impact, prev: TwoPhaseLanding | None) -> TwoPhaseLanding:
        paper = solve_landing(imp, robot, ground,
                              warm_start=last_paper[-1] if last_paper else None)
        last_paper[:] = [paper]
        return solve_two_phase(imp, robot, ground, warm_start=prev, replay=replay, paper=paper)

    return continuation(impacts, one, progress, "two-phase sweep")


__all__ = ["TwoPhase", "TwoPhaseLanding", "solve_two_phase", "solve_two_phase_variant",
           "sweep_two_phase"]


# ------------------------------------------------------------ a second step
@dataclass
class TwoStepCheck:
    """Whether a second yielding step (yielding, static, yielding, static) lowers the depth.

    Attributes
    ----------
    impact : Impact
    one_step : TwoPhaseLanding
        The two-phase optimum.
    depth : float
        Best final depth of the four-phase problem over its starts.
    starts : list of dict
        Per start (``"collapsed"``: the two-phase optimum with short middle phases;
        ``"impedance k_p=.., k_d=.."``: a physical two-step landing): its final depth, the
        phase durations and the depth at the first stop (or the error).
    collapsed : bool
        The best four-phase solution's middle phases (static 1, yielding 2) shrank to
        zero length (< 1e-6) or add no depth: it is the one-step landing.
    """

    impact: Impact
    one_step: TwoPhaseLanding
    depth: float
    starts: list[dict[str, Any]]
    collapsed: bool

    @property
    def gain(self) -> float:
        """``one_step.depth - depth``: what the second step gains (> 0 would be a gain)."""
        return self.one_step.depth - self.depth

    @property
    def notes(self) -> list[str]:
        """The one-step optimum's notes."""
        return self.one_step.notes

    def unverified_reasons(self, certificate: Any = None) -> list[str]:
        """Why the one-step optimum this check compares with is not proven (empty: it is).

        Parameters
        ----------
        certificate : ocp.certificate.phases.PhasesCertificate, optional
            A certificate of the one-step optimum.
        """
        return self.one_step.unverified_reasons(certificate)

    def rows(self) -> list[tuple[str, object]]:
        """The comparison's table rows, one per start."""
        rows: list[tuple[str, object]] = [
            ("one-step depth (refined)", self.one_step.depth),
            ("two-step depth (transcribed, best start)", self.depth),
            ("gain of a second step", self.gain), ("middle phases collapse", self.collapsed)]
        for st in self.starts:
            rows.append((f"start {st['start']}", f"depth {st['depth']:.10g}, phase durations "
                         + ", ".join(f"{d:.4g}" for d in st["durations"]) if "depth" in st
                         else f"failed ({st['error']})"))
        return rows

    def figures(self, certificate: Any = None) -> list[Any]:
        """The one-step optimum's figure (the comparison itself is a table).

        Parameters
        ----------
        certificate : object, optional
            Not drawn.
        """
        return self.one_step.figures()

    def certify(self) -> None:
        """None: the check compares transcribed depths (see :meth:`uncertified_reason`)."""
        return None

    def uncertified_reason(self) -> str:
        """Why there is no certificate."""
        return ("no PMP certificate: the two-step check compares transcribed depths "
                "(certify the one-step optimum with --steps 1 --pmp)")

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict."""
        return json_safe({"v0": self.impact.v0, "depth": self.depth,
                          "one_step_depth": self.one_step.depth,
                          "two_step_depth": self.depth, "gain": self.gain,
                          "collapsed": self.collapsed, "starts": self.starts})


def _two_step_guesses(robot: Robot, impact: Impact, ground: Ground,
                      paper: BangBangLanding | None, tries: int = 12) -> list[tuple[str, Any]]:
    """The collapsed start and the shallowest physical two-step impedance landing within
    the force limit (yielding and static modes only), cut into the four phases."""
    from softlanding.model.controllers import Impedance
    from softlanding.simulation.simulator import simulate_batch

    out = [("collapsed", _guess(robot, impact, ground, paper, 2))]
    g = np.linspace(0.0, 1.0, 41)
    b = simulate_batch(robot, impact.v0, g[:, None], g[None, :], ground)
    ok = (b.steps == 2) & b.strictly_feasible
    order = np.argsort(np.where(ok, b.depth, np.inf), axis=None)[:tries]
    for flat in order:
        i, j = np.unravel_index(flat, ok.shape)
        if not ok[i, j]:
            break
        res = simulate(robot, impact, Impedance(float(g[i]), float(g[j])), ground)
        tr = res.trajectory(n=800)
        assert tr.mode is not None
        runs = np.r_[0, np.cumsum(tr.mode[1:] != tr.mode[:-1])]
        if "flight" in set(tr.mode[runs <= 3]) or runs.max() < 3:
            continue
        last = np.flatnonzero((runs == 3) & (tr.x[:, 1] >= 0))
        if not len(last):
            continue
        keep = np.arange(len(tr.t)) <= last[0]
        edges = [float(tr.t[np.flatnonzero(runs == k)[0]]) for k in (1, 2, 3)]
        cut = Trajectory(tr.t[keep], tr.x[keep], tr.u[keep], tr.state_names, tr.control_names)
        out.append((f"impedance k_p={g[i]:g}, k_d={g[j]:g}", phase_guess(cut, edges)))
        break
    return out


def two_step_check(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                   ground: Ground = LINEAR_GROUND, *,
                   one_step: TwoPhaseLanding | None = None) -> TwoStepCheck:
    """Solve the four-phase landing (two yielding steps) from several starts and compare
    its depth with the two-phase optimum.

    Parameters
    ----------
    impact, robot, ground
        The landing, as in :func:`solve_two_phase`.
    one_step : TwoPhaseLanding, optional
        The two-phase optimum (solved if not given).
    """
    impact = Impact.of(impact)
    one = one_step if one_step is not None else solve_two_phase(impact, robot, ground)
    paper = solve_landing(impact, robot, ground)
    tr = two_phase_transcription(2, ground=ground)
    params = landing_parameters(robot, impact)
    starts: list[dict[str, Any]] = []
    best: tuple[float, list[float]] | None = None
    for name, guess in _two_step_guesses(robot, impact, ground, paper):
        notes: list[str] = []
        try:
            sol = transcribed_solve(tr, params, guess, None, notes)
        except SolveError as err:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            starts.append({"start": name, "error": err.status})
            continue
        # (a collapsed phase can end at -1e-8: Ipopt relaxes bounds by that much; a duration
        # is >= 0, and a printed -9.974e-09 read as a negative time)
        durs = [max(0.0, float(p.T - p.t0)) for p in sol.phases]
        d = float(-sol.phases[-1].x[-1, 2])
        starts.append({"start": name, "depth": d, "durations": durs,
                       "first_stop_depth": float(-sol.phases[0].x[-1, 2]),
                       "verified": bool(sol.verified), "notes": notes})
        if sol.verified and (best is None or d < best[0]):
            best = (d, durs)
    if best is None:
        raise SolveError("no_start_converged", None, "the four-phase landing did not "
                         "converge from any start")
    first = [s["first_stop_depth"] for s in starts if "depth" in s and s["depth"] == best[0]]
    collapsed = (best[1][1] < 1e-6 and best[1][2] < 1e-6) or (
        bool(first) and best[0] - first[0] < 1e-6)
    return TwoStepCheck(impact, one, best[0], starts, collapsed)


__all__ += ["TwoStepCheck", "two_step_check"]
