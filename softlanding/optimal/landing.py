"""The paper's soft-landing optimal control problem, posed with :mod:`ocp`.

Minimise the final depth ``-x_f(T)`` over a free final time ``T`` (when the
foot stops), subject to the yielding-stance dynamics (from
:mod:`softlanding.model.dynamics`), ``|u| <= u_max``, ``0 <= x_b - x_f <= s`` and
``v_f <= 0`` on ``[0, T]``, ``v_f(T) = 0`` and the body-arrest condition: the
ground must hold the constant force ``u_b`` that stops the body in the
remaining stroke,

    u_b = r_m/(1+r_m) (1 + v_b(T)^2 / (2 (x_b(T) - x_f(T)))),
    -x_f(T) >= 1/(1+r_m) + u_b,     u_b <= u_max.

(The paper writes the arrest condition as an equality; we pose the inequality
and report whether it is active.) Both terminal conditions are multiplied by
the positive final stroke before they go to Ipopt, so no iterate divides by
zero.

After the transcribed solve, the bang-bang structure is detected and the
switching times refined with exact (matrix-exponential) arcs; the refined
schedule, followed by the arrest force ``u_b`` until the body stops and then
the body's weight, is replayed in the exact hybrid simulator as a check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ocp import MultipleShooting, Solution, SolveError
from ocp.structure.switching import RefinedSwitching, detect_arcs
from ocp.transcriptions.integrators import rk4_function
from softlanding.errors import InfeasibleLandingError, ParameterError, check_count, expect
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.dynamics import stance_dynamics
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.landing_problem import (
    ARREST,
    ARREST_FORCE,
    DESCENDING,
    DIAGNOSABLE,
    MAX_NODES,
    PARAMETERS,
    STROKE,
    T_MAX,
    arrest_force,
    arrest_force_times_stroke,
    build_landing_problem,
    build_landing_problem_of,
    ground_values,
    landing_stance,
    landing_transcription,
)
from softlanding.optimal.landing_schedule import (
    affine_laws,
    arrest_schedule,
    landing_schedule,
    transcribed_schedule,
)
from softlanding.optimal.limits import force_limit, landing_input
from softlanding.optimal.phase_solve import refined_switching, switching_resolve
from softlanding.optimal.pipeline import (
    PhasedVariant,
    continuation,
    landing_parameters,
    solve_phased,
)
from softlanding.optimal.stance_phases import crater_capacity
from softlanding.optimal.verification import (
    certificate_reasons,
    replay_reasons,
    static_depth,
    static_depth_reason,
)
from softlanding.simulation.simulator import LandingResult, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted


@dataclass
class BangBangLanding:
    """A solved soft landing.

    Attributes
    ----------
    robot, impact, ground
        The problem solved.
    depth : float
        ``-x_f(T)``, refined (exact arcs) unless refinement was off or failed.
    depth_transcribed : float
        From the N-node transcription.
    T : float
        Final time (foot stops).
    arcs : list of str
        Bang arcs (``"max"``/``"min"``).
    switch_times : list of float
        The times between them.
    u_b : float
        Body-arrest force at T.
    arrest_active : bool
        Whether ``-x_f(T) = 1/(1+r_m) + u_b`` holds (to 1e-8).
    status : str
        Ipopt's status of the transcribed solve.
    iterations : int
        Ipopt's iterations.
    solve_time_s : float
        Wall time of the transcribed solve.
    refined : RefinedSwitching or None
        The switching-time refinement (exact arcs).
    transcribed : ocp.Solution
        The transcribed solution (a warm start for the next solve).
    replay : LandingResult or None
        The refined schedule replayed in the exact simulator.
    notes : list of str
        What was dropped or failed on the way.
    refine_requested : bool
        Whether the switching times were to be refined.
    path : str
        What produced the result: ``"transcription"`` (transcribed NLP, then the
        switching-time refinement) or ``"structure"`` (the neighbour's arc structure
        re-solved directly, by Newton or a small NLP: no transcription, so
        ``transcribed`` is None and ``depth_transcribed`` NaN).
    """

    robot: Robot
    impact: Impact
    ground: Ground
    depth: float
    depth_transcribed: float
    T: float
    arcs: list[str]
    switch_times: list[float]
    u_b: float
    arrest_active: bool
    status: str
    iterations: int
    solve_time_s: float
    refined: RefinedSwitching | None
    transcribed: Solution | None
    replay: LandingResult | None = None
    notes: list[str] = field(default_factory=list)
    refine_requested: bool = True
    path: str = "transcription"

    def unverified_reasons(self, certificate: Any = None) -> list[str]:
        """Why this result cannot be taken as proven (empty: every check passed).

        The checks: the switching times were refined (when asked), the schedule
        replayed in the exact simulator comes to rest inside the stroke with the
        same depth (1e-9 refined, 1e-6 transcribed), and the PMP certificate, when
        given, certifies it.

        Parameters
        ----------
        certificate : ocp.PMPCertificate, optional
            The certificate of this solution.
        """
        out = []
        if self.refine_requested and self.refined is None:
            out.append("switching times not refined (" + "; ".join(self.notes) + ")")
        if self.refined is None and self.transcribed is not None and not getattr(
                self.transcribed, "verified", True):
            out.append("the transcription violates a path constraint between its nodes")
        if self.replay is not None:
            out += replay_reasons(self.replay, self.depth, self.refined is not None)
        out += certificate_reasons(certificate)
        if out:  # (why, when the landing stops at the least depth a landing can rest at)
            out += static_depth_reason(self.depth, self.static_depth,
                                       float(self.final_state[1]), self.u_b,
                                       self.robot.body_mass, self.replay)
        return out

    @property
    def final_state(self) -> np.ndarray:
        """The state when the foot stops: the refinement's, else the transcription's."""
        if self.refined is not None:
            return np.asarray(self.refined.xT, dtype=float)
        assert self.transcribed is not None  # (one of them, always: see assemble)
        return np.asarray(self.transcribed.x[-1], dtype=float)

    @property
    def static_depth(self) -> float:
        """The static depth ``W / K``, the least depth at which any landing can come to rest
        on this ground (NaN where the crater's hold is not ``K d``): a lower bound of
        :attr:`depth` to the NLP's tolerance."""
        return static_depth(self.ground)

    @property
    def replay_difference(self) -> float:
        """``|replay depth - depth|`` (NaN without a replay)."""
        return abs(self.replay.depth - self.depth) if self.replay is not None else math.nan

    def certify(self) -> Any:
        """The PMP certificate of the transcription and its refinement (None when the
        result came from a structure re-solve, which has no transcription to read)."""
        if self.transcribed is None:
            return None
        from ocp import certify

        return certify(self.transcribed, self.refined)

    def uncertified_reason(self) -> str:
        """One line: why :meth:`certify` gives no certificate (empty when it gives one)."""
        if self.transcribed is None:
            return ("no PMP certificate: the refined structure was re-solved from a "
                    "neighbour's, without a transcription to read costates from")
        return ""

    def rows(self) -> list[tuple[str, object]]:
        """The ``label, value`` rows of the printed table."""
        rows: list[tuple[str, object]] = [
            ("depth -x_f(T)" + (" (refined)" if self.refined is not None else ""), self.depth),
            ("depth, transcribed", self.depth_transcribed), ("final time T", self.T),
            ("arcs", " -> ".join(self.arcs)),
            ("switch times", ", ".join(f"{t:.12g}" for t in self.switch_times)),
            ("arrest force u_b", self.u_b), ("arrest condition active", self.arrest_active),
            ("Ipopt status", self.status), ("Ipopt iterations", self.iterations),
            ("solve time [s]", self.solve_time_s)]
        if self.replay is not None:
            rows += [("simulator replay depth", self.replay.depth),
                     ("replay difference", self.replay_difference),
                     ("replay feasible", self.replay.feasible)]
        return rows

    def figures(self, certificate: Any = None) -> list[Any]:
        """The figures ``--plot`` writes: the landing, then the certificate's (if given).

        Parameters
        ----------
        certificate : PMPCertificate, optional
            Drawn as a second figure.
        """
        from softlanding.plots.paper import plot_bang_bang

        figs = [plot_bang_bang(self)]
        if certificate is not None:
            from ocp import plot_certificate

            figs.append(plot_certificate(certificate))
        return figs

    def schedule(self) -> ForceSchedule | FeedbackSchedule:
        """The whole landing's open-loop control: the arcs, then ``u_b`` until the body stops,
        then its weight (see :func:`landing_schedule`)."""
        if self.refined is not None and (affine_laws(self.refined) or self.transcribed is None):
            return landing_schedule(self.refined, self.robot.r_m)
        assert self.transcribed is not None
        return transcribed_schedule(self.transcribed, self.robot.r_m, force_limit(self.robot),
                                    damped=True)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: the figures, the refined arcs and the replay."""
        d = {"depth": self.depth, "depth_transcribed": self.depth_transcribed, "T": self.T,
             "switch_times": self.switch_times, "arcs": self.arcs, "u_b": self.u_b,
             "arrest_active": self.arrest_active, "status": self.status,
             "iterations": self.iterations, "solve_time_s": self.solve_time_s,
             "path": self.path + ("" if self.refined is None else f" ({self.refined.path})"),
             "robot": self.robot.to_dict(), "impact": self.impact.to_dict(),
             "ground": self.ground.to_dict(), "notes": self.notes}
        if self.refined is not None:
            d["refined"] = self.refined.to_dict()
        if self.replay is not None:
            d["replay"] = {"depth": self.replay.depth, "difference": self.replay_difference,
                           "feasible": self.replay.feasible, "status": self.replay.status,
                           "stroke_min": self.replay.stroke_min,
                           "stroke_max": self.replay.stroke_max}
        return json_safe(d)

def rigid_guess(tr: MultipleShooting, robot: Robot, impact: Impact,
                ground: Ground = LINEAR_GROUND) -> np.ndarray:
    """Initial guess: the rigid-leg landing up to the foot's first stop (nearly feasible).

    The leg is locked by the force that keeps ``v_b' = v_f'`` (no force limit; the guess's
    forces are then clipped to it), integrated from the OCP's own stance dynamics
    (:func:`~softlanding.model.dynamics.stance_dynamics`) by RK4:
    no simulator kernel is loaded, so a process's first landing does not wait for one.
    A foot that does not stop by ``T_MAX`` gives ``T = 1``.

    Parameters
    ----------
    tr : MultipleShooting
        The transcription the guess is for.
    robot, impact, ground
        The problem.
    """
    N = int(tr.N)  # type: ignore[arg-type]  # a one-phase transcription
    x0 = impact.initial_state(robot)
    T = _lock_stop(x0, robot.r_m, ground)
    flow = _lock_flow(ground, N)
    X, lock = (np.asarray(a, float) for a in flow(x0, robot.r_m, T / N))
    X = np.column_stack([x0, X]).T
    u_max = force_limit(robot)
    U = np.clip(np.concatenate([[float(_lock_force(ground)(x0, robot.r_m))], lock[0, :-1]]),
                -u_max, u_max)[:, None]
    return tr.initial_guess(T=T, x=X, u=U)


LOCK_STEP = 1 / 256
"""RK4 step of the rigid-leg guess's search for the foot's stop, divided by ``max(1, |v0|)``
(the landing's time scale is about 1, a drag's ``1 / |v0|``): the guess agrees with the
exact simulator's rigid landing to 1e-11 on the paper's spring, 5e-8 on the drag and
power-law grounds tried (the stop's time to 1e-10), 1e-5 on an added-mass ground at
``v0 = -10`` (the kink of its law at the critical depth)."""
LOCK_SUBSTEPS = 8
"""RK4 steps per transcription interval of the rigid-leg guess."""


@lru_cache(maxsize=16)
def _lock_force(ground: Ground) -> ca.Function:
    """``(x, r_m) -> u``: the force that keeps the leg locked (``v_b' = v_f'``) in the
    yielding stance (the dynamics are affine in ``u``).

    Parameters
    ----------
    ground : Ground
        Ground model.
    """
    x, r = ca.SX.sym("x", 4), ca.SX.sym("r_m")
    f0, f1 = stance_dynamics(x, 0.0, r, ground), stance_dynamics(x, 1.0, r, ground)
    rel0 = f0[1] - f0[3]
    return ca.Function("lock_force", [x, r], [-rel0 / (f1[1] - f1[3] - rel0)])


@lru_cache(maxsize=16)
def _lock_flow(ground: Ground, steps: int) -> ca.Function:
    """``(x, r_m, h) -> (X, U)``: ``steps`` intervals of length ``h`` of the locked leg
    (:data:`LOCK_SUBSTEPS` RK4 steps each): the state at each interval's end and the
    lock force there.

    Parameters
    ----------
    ground : Ground
        Ground model.
    steps : int
        Intervals.
    """
    return _lock_interval(ground).mapaccum("lock_flow", steps, [0], [0])


@lru_cache(maxsize=16)
def _lock_interval(ground: Ground) -> ca.Function:
    """One interval of :func:`_lock_flow`: the transcriptions' RK4 step
    (:func:`ocp.transcriptions.integrators.rk4_function`) on the locked dynamics."""
    x, r, h, none = ca.SX.sym("x", 4), ca.SX.sym("r_m"), ca.SX.sym("h"), ca.SX.sym("u", 0)
    force = _lock_force(ground)
    locked = ca.Function("locked", [x, none, r], [stance_dynamics(x, force(x, r), r, ground)])
    step = rk4_function(locked, ca.Function("L", [x, none, r], [0]), 4, 0, 1, LOCK_SUBSTEPS)
    z = step(x, none, h, r)[0]
    return ca.Function("lock_interval", [x, r, h], [z, force(z, r)])


def _lock_stop(x0: np.ndarray, r_m: float, ground: Ground) -> float:
    """The locked leg's first foot stop (``v_f`` back to 0 after the impact): chunks of
    intervals of :data:`LOCK_STEP` until ``v_f >= 0``, then regula falsi (Illinois) on
    the last interval's length. 1 if the foot does not stop by ``T_MAX``, rises at once,
    or the integration leaves the finite numbers (the guess then says so before a solve).
    """
    chunk = 64
    flow, one = _lock_flow(ground, chunk), _lock_flow(ground, 1)
    h = LOCK_STEP * LOCK_SUBSTEPS / max(1.0, abs(float(x0[3])))
    t, x = 0.0, np.asarray(x0, float)
    while t < T_MAX:
        X = np.asarray(flow(x, r_m, h)[0], float)
        ahead = np.flatnonzero(~(X[3] < 0.0))  # v_f >= 0, or not a number
        if ahead.size:
            j = int(ahead[0])
            if not np.all(np.isfinite(X[:, : j + 1])):
                return 1.0
            start = X[:, j - 1] if j else x
            t += j * h

            def vf(tau: float, start: np.ndarray = start) -> float:
                return float(one(start, r_m, tau)[0][3])

            a, b, fa, fb = 0.0, h, float(start[3]), vf(h)
            c, kept = 0.0, 0  # kept: the end left in place last (-1 a, +1 b)
            for _ in range(100):
                c_old = c
                c = (fa * b - fb * a) / (fa - fb) if fb != fa else 0.5 * (a + b)
                fc = vf(c)
                if fc == 0.0 or abs(c - c_old) <= 4e-16 * max(1.0, t + c):
                    break
                if fc < 0.0:
                    a, fa = c, fc
                    fb = 0.5 * fb if kept == 1 else fb  # b kept twice: halve its value
                    kept = 1
                else:
                    b, fb = c, fc
                    fa = 0.5 * fa if kept == -1 else fa
                    kept = -1
            return t + c if t + c > 0.0 else 1.0
        t += chunk * h
        x = X[:, -1]
    return 1.0


def _explain_infeasible(err: SolveError, robot: Robot, impact: Impact, ground: Ground,
                        nodes: int) -> InfeasibleLandingError:
    """Name the condition(s) whose removal makes the request feasible."""
    params = {**landing_parameters(robot, impact), **ground_values(ground)}
    culprits = []
    for name in DIAGNOSABLE:
        tr = landing_transcription(nodes, omit=(name,), ground=ground, expand=False)
        try:
            tr.solve(params, guess=rigid_guess(tr, robot, impact, ground))
            culprits.append(name)
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            continue
    if culprits:
        what = " or ".join(culprits)
        why = f"{what} cannot be met together with the other conditions"
    else:
        why = ("the conditions cannot all be met, and dropping any one of them ("
               + "; ".join(DIAGNOSABLE) + ") does not help either")
    return InfeasibleLandingError(
        f"no landing satisfies the constraints at v0={impact.v0:g}, r_m={robot.r_m:g}, "
        f"s={robot.s:g}, u_max={robot.u_max:g}: {why} (Ipopt: {err.status})")


class PaperLanding(PhasedVariant[BangBangLanding]):
    """The paper's single-phase landing's hooks in the pipeline
    (:func:`~softlanding.optimal.pipeline.solve_phased`): one phase, refined as one
    switching structure (:func:`~softlanding.optimal.phase_solve.refined_switching`) and
    re-solved from a neighbour's by :func:`~softlanding.optimal.phase_solve.
    switching_resolve`.

    Parameters
    ----------
    robot, impact, ground
        The problem.
    nodes : int
        Shooting intervals.
    extra_arcs : int
        Also try this many more bang arcs (no structure re-solve then).
    """

    def __init__(self, robot: Robot, impact: Impact, ground: Ground, nodes: int,
                 extra_arcs: int) -> None:
        super().__init__(robot, impact)
        self.ground, self.nodes, self.extra_arcs = ground, nodes, extra_arcs
        self.structure: Any = None  # the detected (trimmed) arcs, when refinement was tried

    def parameters(self) -> dict[str, float]:
        """The landing's parameter values and its ground family's (:func:`ground_values`)."""
        return {**super().parameters(), **ground_values(self.ground)}

    def transcription(self) -> MultipleShooting:
        """The (cached) :func:`landing_transcription`."""
        return landing_transcription(self.nodes, ground=self.ground)

    def guess(self) -> np.ndarray:
        """The rigid-leg landing (:func:`rigid_guess`)."""
        return rigid_guess(self.transcription(), self.robot, self.impact, self.ground)

    def accepts(self, neighbour: BangBangLanding) -> bool:
        """A neighbour on the same ground, when no extra arcs are asked for.

        Parameters
        ----------
        neighbour : BangBangLanding
            The warm start.
        """
        return self.extra_arcs == 0 and neighbour.ground == self.ground

    def refinement(self, sol: Solution, notes: list[str]) -> RefinedSwitching | None:
        """One switching structure refined (:func:`~softlanding.optimal.phase_solve.
        refined_switching`).

        Parameters
        ----------
        sol : ocp.Solution
            The transcription.
        notes : list of str
            Receives what was dropped, or why there is no refinement.
        """
        refined, self.structure = refined_switching(sol, notes, self.extra_arcs)
        return refined

    def resolve(self, neighbour: BangBangLanding,
                params: dict[str, float]) -> RefinedSwitching | None:
        """The neighbour's arcs re-solved for this landing (None if they do not hold).

        Parameters
        ----------
        neighbour : BangBangLanding
            The warm start (refined).
        params : dict
            This landing's parameter values.
        """
        assert neighbour.refined is not None
        return switching_resolve(neighbour.refined, build_landing_problem_of(
            self.nodes, self.ground), self.impact.initial_state(self.robot), params)

    def explain(self, err: SolveError, guess: Any) -> Exception:
        """Name the condition(s) whose removal makes the request feasible (``guess``
        unused: each diagnosis starts from its own rigid guess)."""
        return _explain_infeasible(err, self.robot, self.impact, self.ground, self.nodes)

    def assemble(self, sol: Solution | None, ref: RefinedSwitching | None, notes: list[str],
                 path: str) -> BangBangLanding:
        """The result (depth, arrest condition, arcs) from what was solved.

        Parameters
        ----------
        sol : ocp.Solution or None
            The transcription (None on the structure path).
        ref : RefinedSwitching or None
            The refinement.
        notes : list of str
            What the solve noticed.
        path : str
            ``"transcription"`` or ``"structure"``.
        """
        assert ref is not None or sol is not None
        robot, ground = self.robot, self.ground
        xT = ref.xT if ref is not None else sol.x[-1]  # type: ignore[union-attr]
        depth = -xT[2]
        u_b = arrest_force(robot.r_m, xT)
        gap = float(crater_capacity(xT, ground)) - robot.foot_mass - u_b
        if ref is not None:
            src: Any = ref
        elif self.structure is not None:  # the structure refinement was tried on
            src = self.structure
        else:
            assert sol is not None
            src = detect_arcs(sol)
        done = sol if sol is not None else ref
        return BangBangLanding(
            robot=robot, impact=self.impact, ground=ground, depth=float(depth),
            depth_transcribed=float(-sol.x[-1, 2]) if sol is not None else math.nan,
            T=float(ref.T if ref is not None else sol.T),  # type: ignore[union-attr]
            arcs=list(src.kinds), switch_times=[float(t) for t in src.switch_times],
            u_b=float(u_b), arrest_active=bool(abs(gap) <= 1e-8 * max(1.0, depth)),
            status=done.status, iterations=done.iterations,  # type: ignore[union-attr]
            solve_time_s=done.solve_time,  # type: ignore[union-attr]
            refined=ref, transcribed=sol, notes=notes, path=path)

    def replay(self, result: BangBangLanding) -> None:
        """The landing's schedule replayed in the exact simulator.

        Parameters
        ----------
        result : BangBangLanding
            The result (its ``replay`` is set).
        """
        result.replay = simulate(self.robot, self.impact, result.schedule(), self.ground)


def solve_landing(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                  ground: Ground = LINEAR_GROUND, *, nodes: int = 100, refine: bool = True,
                  extra_arcs: int = 0, warm_start: Solution | BangBangLanding | None = None,
                  replay: bool = True) -> BangBangLanding:
    """Solve the soft-landing OCP; refine the switching times; replay in the simulator.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot; its force limit ``u_max`` bounds the control (required).
    ground : Ground
        Ground model.
    nodes : int
        Shooting intervals.
    refine : bool
        Refine the switching times with exact arcs.
    extra_arcs : int
        Also try this many more bang arcs (>= 0).
    warm_start : ocp.Solution or BangBangLanding, optional
        A neighbouring solution (continuation). A refined :class:`BangBangLanding`
        is first tried as a structure: its arcs are re-solved directly for this
        landing (no transcription; ``path == "structure"``), and the transcription
        is solved only if that fails.
    replay : bool
        Replay the schedule in the exact simulator.

    Returns
    -------
    BangBangLanding

    Raises
    ------
    ParameterError
        Non-finite or out-of-range parameters.
    InfeasibleLandingError
        No landing satisfies the constraints (the message names the condition).
    ocp.SolveError
        Ipopt failed otherwise (status attached).
    """
    impact = Impact.of(impact)
    landing_input(robot, ground)
    nodes = check_count("nodes", nodes, 2, MAX_NODES)
    extra_arcs = check_count("extra_arcs", extra_arcs, 0, 20)
    if warm_start is not None:
        expect("warm_start", warm_start, (Solution, BangBangLanding),
               "BangBangLanding or ocp.Solution of this landing problem")
    out = solve_phased(PaperLanding(robot, impact, ground, nodes, extra_arcs), warm_start,
                       refine=refine, replay=replay)
    if replay and out.path == "structure" and out.unverified_reasons():
        # the neighbour's structure does not hold here: solve it properly
        return solve_landing(impact, robot, ground, nodes=nodes, refine=refine,
                             warm_start=out.transcribed, replay=replay)
    return out


def sweep_landing(v0_values, robot: Robot = PAPER_ROBOT, ground: Ground = LINEAR_GROUND, *,
                  nodes: int = 100, refine: bool = True, progress: bool | None = False,
                  replay: bool = False) -> list[BangBangLanding]:
    """Bang-bang depth over impact velocities, by continuation (each solve warm-starts the next).

    The values are solved in the given order; start from the easy end. After the first,
    each landing re-solves its neighbour's arc structure directly (``path ==
    "structure"``) and falls back to the transcription when the structure changes.

    Parameters
    ----------
    v0_values : sequence of float
        Impact velocities.
    robot : Robot
        The robot (with a force limit).
    ground : Ground
        Ground model.
    nodes : int
        Shooting intervals.
    refine : bool
        Refine the switching times.
    progress : bool, optional
        Progress bar.
    replay : bool
        Replay each schedule in the exact simulator.
    """
    impacts = [Impact.of(v) for v in v0_values]  # bad input fails before any work
    landing_input(robot, ground)
    return continuation(impacts, lambda imp, prev: solve_landing(
        imp, robot, ground, nodes=nodes, refine=refine, warm_start=prev, replay=replay),
        progress, "bang-bang sweep")


# the problem (landing_problem) and the schedules (landing_schedule) are imported here too,
# where they were first defined
__all__ = ["ARREST", "ARREST_FORCE", "DESCENDING", "DIAGNOSABLE", "MAX_NODES", "PARAMETERS",
           "STROKE", "T_MAX", "BangBangLanding", "InfeasibleLandingError", "PaperLanding",
           "ParameterError", "affine_laws", "arrest_force", "arrest_force_times_stroke",
           "arrest_schedule", "build_landing_problem", "build_landing_problem_of",
           "landing_schedule", "landing_stance", "landing_transcription", "rigid_guess",
           "solve_landing", "sweep_landing", "transcribed_schedule"]
