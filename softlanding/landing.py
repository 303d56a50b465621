"""The paper's soft-landing optimal control problem, posed with :mod:`ocp`.

Minimise the final depth ``-x_f(T)`` over a free final time ``T`` (when the
foot stops), subject to the yielding-stance dynamics (from
:mod:`softlanding.dynamics`), ``|u| <= u_max``, ``0 <= x_b - x_f <= s`` and
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

from ocp import InfeasibleError, MultipleShooting, OptimalControlProblem, Solution, SolveError
from ocp.switching import RefinedSwitching, detect_arcs, refine_switching

from ._progress import progress as show_progress
from .dynamics import STATE_NAMES, stance_dynamics
from .errors import ParameterError
from .scaling import DimensionlessParams
from .simulate import ForceSchedule, LandingResult, Rigid, simulate

T_MAX = 30.0


class InfeasibleLandingError(ValueError):
    """No landing satisfies the constraints; the message names the condition."""


STROKE = "stroke limits 0 <= x_b - x_f <= s"
DESCENDING = "foot descending v_f <= 0"
ARREST = "body arrest -x_f(T) >= 1/(1+r_m) + u_b"
ARREST_FORCE = "arrest force u_b <= u_max"
DIAGNOSABLE = (ARREST_FORCE, ARREST, STROKE, DESCENDING)


def build_landing_problem(omit: tuple[str, ...] = ()) -> OptimalControlProblem:
    """The soft-landing OCP with parameters ``r_m, s, v0, u_max``.

    ``omit`` drops named conditions (used to diagnose infeasible requests).
    """
    p = OptimalControlProblem("soft_landing")
    xb, vb, xf, vf = (p.state(n) for n in STATE_NAMES)
    r_m, s, v0, u_max = (p.parameter(n) for n in ("r_m", "s", "v0", "u_max"))
    u = p.control("u", lower=-u_max, upper=u_max)
    x = ca.vertcat(xb, vb, xf, vf)
    p.set_dynamics(stance_dynamics(x, u, r_m))
    stroke = xb - xf
    if STROKE not in omit:
        p.path_constraint(stroke, 0, s, name=STROKE)
    if DESCENDING not in omit:
        p.path_constraint(vf, -ca.inf, 0, name=DESCENDING)
    p.initial_constraint(xb - s / 2, 0.0, name="x_b(0) = s/2")
    p.initial_constraint(vb - v0, 0.0, name="v_b(0) = v0")
    p.initial_constraint(xf, 0.0, name="x_f(0) = 0")
    p.initial_constraint(vf - v0, 0.0, name="v_f(0) = v0")
    p.terminal_constraint(vf, 0.0, name="foot stopped v_f(T) = 0")
    # stroke * (-x_f - 1/(1+r_m) - u_b) >= 0 and stroke * (u_max - u_b) >= 0
    ub_stroke = arrest_force_times_stroke(x, r_m)
    if ARREST not in omit:
        p.terminal_constraint(stroke * (-xf - 1 / (1 + r_m)) - ub_stroke, 0, ca.inf, name=ARREST)
    if ARREST_FORCE not in omit:
        p.terminal_constraint(stroke * u_max - ub_stroke, 0, ca.inf, name=ARREST_FORCE)
    p.free_final_time(lower=1e-3, upper=T_MAX, guess=1.0)
    p.minimize_terminal(-xf)
    return p


@lru_cache(maxsize=16)
def landing_transcription(nodes: int = 100, substeps: int = 4,
                          omit: tuple[str, ...] = ()) -> MultipleShooting:
    """The transcribed soft-landing NLP, built once per ``(nodes, substeps)`` and reused.

    Expanded to SX: slower to build once, faster at every re-solve of a sweep.
    """
    return MultipleShooting(build_landing_problem(omit), nodes=nodes, integrator="rk4",
                            substeps=substeps, expand=True)


def arrest_force_times_stroke(x, r_m):
    """``u_b (x_b - x_f)``, where ``u_b = r_m/(1+r_m) (1 + v_b^2 / (2 (x_b - x_f)))`` is the
    constant force that stops the body in the remaining stroke (symbolic or numeric)."""
    return r_m / (1 + r_m) * ((x[0] - x[2]) + x[1] ** 2 / 2)


def arrest_force(r_m: float, x_T: np.ndarray) -> float:
    """``u_b``: the constant force that stops the body in the remaining stroke."""
    return float(arrest_force_times_stroke(x_T, r_m) / (x_T[0] - x_T[2]))


@dataclass
class BangBangLanding:
    """A solved soft landing.

    Attributes
    ----------
    depth : float
        ``-x_f(T)``, refined (exact arcs) unless refinement was off or failed.
    depth_transcribed : float
        From the N-node transcription.
    T : float
        Final time (foot stops).
    arcs, switch_times : bang arcs (``"max"``/``"min"``) and the times between them.
    u_b : float
        Body-arrest force at T.
    arrest_active : bool
        Whether ``-x_f(T) = 1/(1+r_m) + u_b`` holds (to 1e-8).
    replay : LandingResult or None
        The refined schedule replayed in the exact simulator.
    """

    params: DimensionlessParams
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
    transcribed: Solution
    replay: LandingResult | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def replay_difference(self) -> float:
        return abs(self.replay.depth - self.depth) if self.replay is not None else math.nan

    def schedule(self) -> ForceSchedule:
        """Open-loop force: the bang arcs, then ``u_b`` until the body stops, then its weight."""
        r_m = self.params.r_m
        if self.refined is not None:
            durs = [d for d in self.refined.durations if d > 1e-14]
            vals = [v for v, d in zip(self.refined.values, self.refined.durations, strict=True)
                    if d > 1e-14]
            xT = self.refined.xT
        else:
            u = self.transcribed.u[:, 0]
            h = self.transcribed.T / self.transcribed.N
            durs, vals = [h] * len(u), list(u)
            xT = self.transcribed.x[-1]
        stroke = xT[0] - xT[2]
        vals = vals + [self.u_b]
        if xT[1] < 0:
            decel = xT[1] ** 2 / (2 * stroke)
            durs = durs + [-xT[1] / decel]
        vals = vals + [r_m / (1 + r_m)]
        return ForceSchedule.from_arcs(durs, vals)

    def to_dict(self) -> dict[str, Any]:
        d = {"depth": self.depth, "depth_transcribed": self.depth_transcribed, "T": self.T,
             "switch_times": self.switch_times, "arcs": self.arcs, "u_b": self.u_b,
             "arrest_active": self.arrest_active, "status": self.status,
             "iterations": self.iterations, "solve_time_s": self.solve_time_s,
             "params": self.params.as_dict(), "notes": self.notes}
        if self.refined is not None:
            d["refined"] = self.refined.to_dict()
        if self.replay is not None:
            d["replay"] = {"depth": self.replay.depth, "difference": self.replay_difference,
                           "feasible": self.replay.feasible, "status": self.replay.status,
                           "stroke_min": self.replay.stroke_min,
                           "stroke_max": self.replay.stroke_max}
        return d


def _validate(v0, r_m, s, u_max) -> DimensionlessParams:
    p = DimensionlessParams(r_m=r_m, s=s, v0=v0, u_max=u_max)
    if u_max is None:
        raise ParameterError("u_max", "the optimal control problem needs a force limit")
    weight = p.r_m / (1 + p.r_m)
    if p.u_max <= weight:
        raise InfeasibleLandingError(
            f"u_max = {u_max:g} does not exceed the body weight r_m/(1+r_m) = {weight:.4g}: "
            "the arrest force u_b <= u_max can never hold")
    return p


def rigid_guess(tr: MultipleShooting, p: DimensionlessParams) -> np.ndarray:
    """Initial guess: the rigid-leg landing up to the foot's first stop (nearly feasible)."""
    res = simulate(p, Rigid())
    T = res.t_first_stop if math.isfinite(res.t_first_stop) else 1.0
    traj = res.trajectory(t_end=T, n=tr.N + 1)
    t = np.linspace(0, T, tr.N + 1)
    X = np.column_stack([np.interp(t, traj.t, traj.x[:, i]) for i in range(4)])
    U = np.clip(np.interp(t[:-1], traj.t, traj.u), -p.u_max, p.u_max)[:, None]
    return tr.initial_guess(T=T, x=X, u=U)


def _explain_infeasible(err: SolveError, p: DimensionlessParams,
                        nodes: int) -> InfeasibleLandingError:
    """Name the condition(s) whose removal makes the request feasible."""
    params = {"r_m": p.r_m, "s": p.s, "v0": p.v0, "u_max": p.u_max}
    culprits = []
    for name in DIAGNOSABLE:
        tr = landing_transcription(nodes, omit=(name,))
        try:
            tr.solve(params, guess=rigid_guess(tr, p))
            culprits.append(name)
        except SolveError:
            continue
    if culprits:
        what = " or ".join(culprits)
        why = f"{what} cannot be met together with the other conditions"
    else:
        why = ("the conditions cannot all be met, and dropping any one of them ("
               + "; ".join(DIAGNOSABLE) + ") does not help either")
    return InfeasibleLandingError(
        f"no landing satisfies the constraints at v0={p.v0:g}, r_m={p.r_m:g}, s={p.s:g}, "
        f"u_max={p.u_max:g}: {why} (Ipopt: {err.status})")


def solve_landing(v0: float, r_m: float = 5.0, s: float = 20.0, u_max: float = 8.2, *,
                  nodes: int = 100, refine: bool = True, extra_arcs: int = 0,
                  warm_start: Solution | None = None, replay: bool = True) -> BangBangLanding:
    """Solve the soft-landing OCP; refine the switching times; replay in the simulator.

    Raises
    ------
    ParameterError
        Non-finite or out-of-range parameters.
    InfeasibleLandingError
        No landing satisfies the constraints (the message names the condition).
    ocp.SolveError
        Ipopt failed otherwise (status attached).
    """
    p = _validate(v0, r_m, s, u_max)
    tr = landing_transcription(nodes)
    params = {"r_m": p.r_m, "s": p.s, "v0": p.v0, "u_max": p.u_max}
    try:
        if warm_start is not None:
            try:
                sol = tr.solve(params, warm_start=warm_start)
            except SolveError:
                sol = tr.solve(params, guess=rigid_guess(tr, p))
        else:
            sol = tr.solve(params, guess=rigid_guess(tr, p))
    except InfeasibleError as err:
        raise _explain_infeasible(err, p, nodes) from None
    notes: list[str] = []
    depth_tr = -sol.x[-1, 2]
    refined = None
    xT = sol.x[-1]
    if refine:
        st = detect_arcs(sol)
        trimmed = st.without_trailing_constrained()
        if trimmed is not st and trimmed.bang_bang:
            notes.append(
                f"dropped the final {st.arcs[-1].duration:.4g}-long arc on which "
                f"{' and '.join(st.arcs[-1].active)} is active: the foot has already stopped "
                "and the force holds the crater's yield load, which is the body-arrest phase")
            st = trimmed
        if st.bang_bang:
            try:
                refined = refine_switching(sol, st, extra_arcs=extra_arcs)
                xT = refined.xT
            except SolveError as err:
                notes.append(f"switching-time refinement failed ({err.status}); "
                             "reporting the transcribed solution")
        else:
            notes.append(f"structure {st.kinds} is not bang-bang; not refined")
    depth = -xT[2]
    u_b = arrest_force(p.r_m, xT)
    gap = depth - 1 / (1 + p.r_m) - u_b
    out = BangBangLanding(
        params=p, depth=float(depth), depth_transcribed=float(depth_tr),
        T=float(refined.T if refined is not None else sol.T),
        arcs=list(refined.kinds if refined is not None else detect_arcs(sol).kinds),
        switch_times=[float(t) for t in (refined.switch_times if refined is not None
                                         else detect_arcs(sol).switch_times)],
        u_b=float(u_b), arrest_active=bool(abs(gap) <= 1e-8 * max(1.0, depth)),
        status=sol.status, iterations=sol.iterations, solve_time_s=sol.solve_time,
        refined=refined, transcribed=sol, notes=notes)
    if replay:
        out.replay = simulate(DimensionlessParams(r_m=p.r_m, s=p.s, v0=p.v0), out.schedule())
    return out


def sweep_landing(v0_values, r_m: float = 5.0, s: float = 20.0, u_max: float = 8.2, *,
                  nodes: int = 100, refine: bool = True, progress: bool = False,
                  replay: bool = False) -> list[BangBangLanding]:
    """Bang-bang depth over impact velocities, by continuation (each solve warm-starts the next).

    The values are solved in the given order; start from the easy end.
    """
    v0_values = list(v0_values)
    for v in v0_values:  # bad input fails before any work (and any progress bar)
        _validate(v, r_m, s, u_max)
    it = show_progress(v0_values, progress, "bang-bang sweep", "solve")
    out: list[BangBangLanding] = []
    prev = None
    for v in it:
        res = solve_landing(v, r_m, s, u_max, nodes=nodes, refine=refine, warm_start=prev,
                            replay=replay)
        out.append(res)
        prev = res.transcribed
    return out


__all__ = ["BangBangLanding", "InfeasibleLandingError", "ParameterError",
           "build_landing_problem", "landing_transcription", "solve_landing", "sweep_landing"]
