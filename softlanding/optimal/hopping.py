"""Minimum-energy hopping on yielding ground: the optimum, the best impedance, a rigid leg.

The cycle and the cost are defined in :mod:`softlanding.optimal.hopping_problem` (touchdown
on fresh ground with the paper's impact state, stance on the crater, lift-off,
flight to the same apex posture; energy drawn ``int (P+ - eta P-) dt``).

* :func:`solve_hop` -- the optimum (free actuator; the transcription of the whole
  cycle);
* :func:`impedance_hop` -- one impedance ``(k_p, k_d)`` with a thrust: in stance
  ``u = -k_p (l - s/2) - k_d l'``, plus a constant thrust ``u_t`` while the foot rests
  on the crater (static mode; the simulator's per-mode law, exact), ``u_t`` set by
  bisection so the centre of mass reaches the apex; :func:`best_impedance_hop`
  searches the gains (both in :mod:`softlanding.optimal.hop_impedance`, imported here);
* :func:`rigid_hop` -- the leg locked until the robot comes to rest on its crater
  (the paper's rigid impactor), then the optimal push-off.

In flight every leg is returned to the apex posture by the same minimum-energy
flight (:func:`softlanding.optimal.hop_cycle.flight_to_apex`), so the
three differ only in stance. Every energy reported is evaluated on the **exact
replay** of the control (simulator for stance and flight, power integrated by
quadrature between its sign changes: :mod:`softlanding.simulation.actuator_work`), not on the
transcription's slack; the cycle's energy balance ``E(apex) - E(touchdown) = W_net -
d^2/2`` is checked, and so is the apex posture.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from ocp import Solution, SolveError, Trajectory
from softlanding.errors import check_count, expect
from softlanding.model.controllers import Rigid
from softlanding.model.dynamics import mechanical_energy
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.hop_cycle import (
    APEX_TOL,
    CONVERGED_RTOL,
    SLACK_NOTE,
    HopCycle,
    crater_depth,
    evaluate_replay,
    force_schedule,
    grid_row,
    hop_parameters,
    landing_cot,
)
from softlanding.optimal.hop_impedance import ThrustImpedance, best_impedance_hop, impedance_hop
from softlanding.optimal.hopping_problem import hop_transcription
from softlanding.optimal.limits import hop_input
from softlanding.optimal.phase_solve import transcribed_solve
from softlanding.simulation.actuator_work import Work, state_at
from softlanding.simulation.simulator import simulate
from softlanding.util.progress import step
from softlanding.util.signals import raise_if_interrupted


# -------------------------------------------------------------- the optimum
@lru_cache(maxsize=8)
def _two_phase_landing(robot: Robot, impact: Impact) -> Any:
    """The two-phase landing every start mirrors (solved once per landing), from empty
    refinement caches: as in a fresh process, whatever was refined before (a neighbour's
    cached NLP gives other last bits, and the hop NLP's flat valley turned those into
    another local optimum)."""
    from ocp.structure import phase_refinement, refinement
    from softlanding.optimal.two_phase import solve_two_phase

    refinement.clear_cache()
    phase_refinement.clear_cache()

    return solve_two_phase(impact, robot.replace(l0=None), replay=False)


#: Time stretches of the push-off and flight of ``solve_hop``'s starts (the first is the
#: plain mirror); deterministic, so the best of them is reproducible.
HOP_STARTS = (1.0, 0.7, 1.4)


def _rounded(a: np.ndarray, bits: int = 30) -> np.ndarray:
    """``a`` with its mantissas rounded to ``bits`` bits (about 9 significant digits)."""
    m, e = np.frexp(a)
    return np.ldexp(np.round(m * 2.0 ** bits) / 2.0 ** bits, e)


def _hop_guess(robot: Robot, impact: Impact, stretch: float = 1.0) -> Trajectory:
    """The landing optimum, its arrest mirrored into a push-off, a flight to the apex; the
    push-off and the flight stretched in time by ``stretch`` (other starts)."""
    two = _two_phase_landing(robot, impact)
    if two.refined is None:  # its exact arcs are the stance of the start
        raise SolveError(two.status, message="no start for the hop: the two-phase landing it "
                         "mirrors was not refined (" + "; ".join(two.notes) + ")")
    tr = two.refined.trajectory(300)
    y, s = tr.phase == 0, tr.phase == 1
    ts, xs, us = tr.t[s], tr.x[s], tr.u[s, 0]
    tm = ts[-1] + stretch * (ts[-1] - ts[::-1])
    xm = xs[::-1].copy()
    xm[:, 1] *= -1 / stretch
    xm[:, 3] /= stretch
    t_st, x_st = np.r_[ts, tm[1:]], np.vstack([xs, xm[1:]])
    u_st = np.r_[us, us[::-1][1:]]
    tf = stretch * (abs(impact.v0) + 1.0)
    t = np.linspace(0.0, tf, 60)
    a = np.sin(np.pi * t / (2 * tf))
    da = np.pi / (2 * tf) * np.cos(np.pi * t / (2 * tf))
    h, l0, x0 = impact.energy, robot.s / 2, xm[-1]
    fl = np.column_stack([x0[0] + (h + l0 - x0[0]) * a, (h + l0 - x0[0]) * da,
                          x0[2] + (h - x0[2]) * a, (h - x0[2]) * da])
    parts = [(tr.t[y], tr.x[y], tr.u[y, 0]), (t_st, x_st, u_st), (tm[-1] + t, fl, 0 * t)]
    crater = -tr.x[y][-1, 2]
    cols = [np.column_stack([x, np.full(len(tt), crater)]) for tt, x, _ in parts]
    us2 = [np.column_stack([u, np.maximum(u * (x[:, 1] - x[:, 3]), 0)]) for _, x, u in parts]
    # rounded to 30 bits: the hop NLP's flat valley turns last-bit differences of the
    # landing it mirrors (which depend on what was solved before in the process) into other
    # local optima; a rounded start gives one answer whatever ran before
    return Trajectory(_rounded(np.concatenate([p[0] for p in parts])),
                      _rounded(np.vstack(cols)), _rounded(np.vstack(us2)),
                      ("x_b", "v_b", "x_f", "v_f", "crater"), ("u", "p"),
                      phase=np.concatenate([np.full(len(p[0]), i)
                                            for i, p in enumerate(parts)]))


def solve_hop(impact: Impact | float, robot: Robot = PAPER_ROBOT, eta: float = 0.0, *,
              warm_start: HopCycle | None = None, doublings: int = 0,
              refine: bool = True) -> HopCycle:
    """The minimum-energy hop cycle (free actuator), replayed exactly.

    The problem is not convex: it is solved from the deterministic starts of
    :data:`HOP_STARTS` (the mirrored landing, its push-off and flight stretched in time)
    and the best verified cycle is returned, with every start's energy in ``starts`` and
    their ``local_optima_spread``. With ``warm_start`` (continuation) only that start.

    The energy is the exact replay of a grid's piecewise-constant control: a real cycle's
    energy, above the continuous optimum by the grid's error (first order in the step:
    the optimum holds the leg at zero power on arcs a constant force cannot follow). With
    ``doublings`` the best cycle is re-solved on grids of twice, four times ... the nodes
    (each from the previous one) and the finest is returned, with the grid sequence, the
    continuous optimum extrapolated from it and an error estimate (``grids``,
    ``energy_estimate``, ``energy_error``).

    With ``refine`` the finest grid's arcs are then refined exactly
    (:mod:`softlanding.optimal.hop_arcs`: switching times and phase durations, every arc
    flowed exactly) and the refined schedule is replayed; it is reported when its replay
    closes and is below the grid's (``exact_arcs``; only when Ipopt says
    ``Solve_Succeeded``), and it is taken as the continuous optimum to
    :data:`CONVERGED_RTOL` when the refined NLP's energy and the exact replay's agree to
    that and it lies within the grids' extrapolation and its error
    (:attr:`HopCycle.converged`): a local optimum on the arc structure read off the grid,
    not certified (the control on arcs of one-signed power is not unique). Otherwise the
    grid's cycle is reported and says "discretised", and by how much.

    Parameters
    ----------
    impact : Impact or float
        Touchdown velocity ``v0 < 0`` (apex ``v0^2/2`` above the surface).
    robot : Robot
        The robot (with a force limit).
    eta : float
        Regenerative efficiency in ``[0, 1)``.
    warm_start : HopCycle, optional
        A neighbouring optimum (its transcription warm-starts this one).
    doublings : int
        Grid doublings after the base grid (0 to 4; 0: one grid, its error not estimated).
    refine : bool
        Refine the finest grid's arcs exactly (above).

    Raises
    ------
    ParameterError
        Bad parameters.
    ocp.SolveError
        When the transcription fails (InfeasibleError: no such hop).
    """
    robot, impact = hop_input(robot, impact, eta)
    doublings = check_count("doublings", doublings, 0, 4)
    if warm_start is not None:
        expect("warm_start", warm_start, HopCycle, "HopCycle (solve_hop's)")
    tr = hop_transcription("touchdown")
    ws = warm_start.transcribed[0] if warm_start is not None and warm_start.transcribed \
        else None
    if ws is not None:  # continuation: the neighbour's optimum is the start
        out = _grid_sequence(_hop_from(tr, robot, impact, eta, None, ws), robot, impact,
                             eta, doublings)
        return _exact_arcs(out, robot, impact, eta) if refine else out
    best: HopCycle | None = None
    starts: list[dict[str, Any]] = []
    last_error: SolveError | None = None
    for stretch in HOP_STARTS:
        try:
            c = _hop_from(tr, robot, impact, eta, _hop_guess(robot, impact, stretch), None)
        except SolveError as err:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            starts.append({"stretch": stretch, "error": err.status})
            last_error = err
            step(f"start {len(starts)} of {len(HOP_STARTS)}")
            continue
        starts.append({"stretch": stretch, "energy": c.energy, "depth": c.depth,
                       "verified": not c.unverified_reasons()})
        step(f"start {len(starts)} of {len(HOP_STARTS)}")
        if best is None or (not c.unverified_reasons(), -c.energy) > (
                not best.unverified_reasons(), -best.energy):
            best = c
    if best is None:
        assert last_error is not None
        raise last_error
    best.starts = starts
    out = _grid_sequence(best, robot, impact, eta, doublings)
    return _exact_arcs(out, robot, impact, eta) if refine else out


def _exact_arcs(c: HopCycle, robot: Robot, impact: Impact, eta: float) -> HopCycle:
    """The grid cycle ``c`` refined on exact arcs and replayed, or ``c`` with a note saying
    why not (:mod:`softlanding.optimal.hop_arcs`).

    The refinement NLP is not convex: it is solved with each of Ipopt's settings of
    :data:`~softlanding.optimal.hop_arcs.SETTINGS` in turn until one's replay is verified,
    below the grid's energy and :attr:`HopCycle.converged` (with one grid, not
    cross-checked: the first verified below the grid's); else the lowest verified one below
    the grid's, else ``c``. The note lists every run."""
    from softlanding.optimal.hop_arcs import SETTINGS, detect_arcs, refine_arcs

    runs: list[str] = []
    best: HopCycle | None = None
    guess = None
    for setting in range(len(SETTINGS)):
        try:
            guess = guess or detect_arcs(c.transcribed[0], robot)
            r = refine_arcs(guess, robot, impact, eta, setting=setting)
        except ValueError as err:  # the arcs' structure: the same for every setting
            c.notes.append(f"exact arcs not refined: {err}")
            return c
        if r.status != "Solve_Succeeded":
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            runs.append(f"stopped: {r.status}")
            continue
        out = _refined_cycle(c, r, robot, impact, eta)
        why = "; ".join(out.unverified_reasons()) or (
            f"its energy {out.energy:.9g} is above the grid's {c.energy:.9g}"
            if not out.energy <= c.energy else "")
        runs.append(f"{r.energy:.10g}" + (f" (the replay fails: {why})" if why else ""))
        if why:
            continue
        if best is None or out.energy < best.energy:
            best = out
        if out.converged or not math.isfinite(c.energy_estimate):
            break
    if best is None:
        c.notes.append(f"exact arcs not used: no refined schedule's replay holds (Ipopt's runs: "
                       f"{'; '.join(runs)})")
        return c
    kept = best.exact_arcs
    best.notes = [n for n in c.notes if n != SLACK_NOTE] + [
        f"exact arcs: {len(kept)} arcs ({', '.join(a['mode'] + ' ' + a['kind'] for a in kept)})"
        f", switching times and forces refined with every arc flowed exactly (Ipopt's runs: "
        f"{'; '.join(runs)}); the energy is the exact replay of the refined schedule, "
        f"{c.energy - best.energy:.3g} below the finest grid's"]
    return best


def _refined_cycle(c: HopCycle, r: Any, robot: Robot, impact: Impact, eta: float
                   ) -> HopCycle:
    """The refined hop ``r`` (:func:`~softlanding.optimal.hop_arcs.refine_arcs`) replayed
    exactly, with the grid cycle ``c``'s transcription, starts and grid sequence."""
    x0 = impact.initial_state(robot.replace(l0=None))
    res = simulate(robot, impact, r.schedule, x0=x0, t_max=r.duration + 1.0)
    out = evaluate_replay("free", robot, impact, eta, res, r.duration, Work(),
                          float(mechanical_energy(x0, robot.r_m)))
    out.energy_transcribed = r.energy
    out.transcribed, out.pieces, out.starts, out.grids = c.transcribed, [
        (res, 0.0, r.duration)], c.starts, c.grids
    # arcs the refinement shrank to nothing (a grid's blips) are left out of the report
    out.exact_arcs = [{"mode": a.mode, "kind": a.kind, "durations": list(a.durations),
                       "forces": list(a.forces)} for a in r.arcs if sum(a.durations) > 1e-6]
    out.energy_estimate, out.energy_error = c.energy_estimate, c.energy_error
    return out


def _grid_sequence(base: HopCycle, robot: Robot, impact: Impact, eta: float,
                   doublings: int) -> HopCycle:
    """The base cycle re-solved on ``doublings`` successively doubled grids (each from the
    previous grid's solution); the finest verified one with the sequence and its
    extrapolation (first-order Richardson on the two finest grids, since a grid's excess
    energy is about ``c h``)."""
    grids, cur = [grid_row(base)], base
    for k in range(1, doublings + 1):
        prev = cur.transcribed[0]
        try:
            c = _hop_from(hop_transcription("touchdown", 1, k), robot, impact, eta, prev, prev)
        except SolveError as err:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            cur.notes.append(f"grid sequence stopped: the {2 ** k}x grid failed ({err.status})")
            break
        if c.unverified_reasons():
            cur.notes.append(f"grid sequence stopped: the {2 ** k}x grid's replay fails its "
                             f"checks ({'; '.join(c.unverified_reasons())})")
            break
        if c.energy > cur.energy:  # the coarse control is on this grid: Ipopt left its basin
            cur.notes.append(f"grid sequence stopped: the {2 ** k}x grid's optimum "
                             f"({c.energy:.9g}) is above the coarser grid's ({cur.energy:.9g}), "
                             "whose control it contains (another local optimum)")
            break
        c.starts = base.starts
        grids.append(grid_row(c))
        cur = c
        step(f"grid {k} of {doublings} doublings")
    cur.grids = grids
    e = [g["energy"] for g in grids]
    if len(e) >= 2:
        cur.energy_estimate = 2 * e[-1] - e[-2]
        cur.energy_error = abs(e[-2] - e[-1]) if len(e) == 2 else \
            abs(cur.energy_estimate - (2 * e[-2] - e[-3]))
    return cur


def _hop_from(tr: Any, robot: Robot, impact: Impact, eta: float,
              guess: Trajectory | Solution | None,
              ws: Solution | None) -> HopCycle:
    """One solve of the free hop from a start, replayed and evaluated."""
    notes: list[str] = []
    sol = transcribed_solve(tr, hop_parameters(robot, impact, eta), guess, ws, notes)
    sched, t_apex = force_schedule([sol])
    x0 = impact.initial_state(robot.replace(l0=None))
    res = simulate(robot, impact, sched, x0=x0, t_max=t_apex + 1.0)
    out = evaluate_replay("free", robot, impact, eta, res, t_apex, Work(),
                    float(mechanical_energy(x0, robot.r_m)))
    out.energy_transcribed = float(sol.objective)
    out.transcribed, out.pieces = [sol], [(res, 0.0, t_apex)]
    out.notes = [SLACK_NOTE] + [n for n in notes if "slack p" not in n] if notes else []
    return out


# ------------------------------------------------------------------ rigid
def rigid_hop(impact: Impact | float, robot: Robot = PAPER_ROBOT, eta: float = 0.0) -> HopCycle:
    """A rigid landing (leg locked, lock force unlimited) until the robot rests on its
    crater, then the optimal push-off and flight; replayed exactly.

    Parameters
    ----------
    impact, robot, eta
        Touchdown velocity, robot and regenerative efficiency, as in :func:`solve_hop`.
    """
    robot, impact = hop_input(robot, impact, eta)
    x0 = impact.initial_state(robot.replace(l0=None))
    land = simulate(robot.without_force_limit(), impact, Rigid(), x0=x0)
    t_rest = land.t_first_stop
    rest = state_at(land, t_rest)
    rest[1] = rest[3] = 0.0
    tr = hop_transcription("rest")
    p = hop_parameters(robot, impact, eta, rest)
    notes: list[str] = []
    sol = transcribed_solve(tr, p, _rest_guess(robot, impact, rest), None, notes)
    sched, t_f = force_schedule([sol])
    res = simulate(robot, impact, sched, x0=rest, t_max=t_f + 1.0)
    out = evaluate_replay("rigid", robot, impact, eta, res, t_f, Work(),
                    float(mechanical_energy(x0, robot.r_m)))
    out.depth = max(land.depth, crater_depth(res, t_f))
    out.cot = landing_cot(robot, impact, land)
    out.balance_error = abs(float(mechanical_energy(state_at(res, t_f), robot.r_m))
                            - float(mechanical_energy(x0, robot.r_m))
                            - (out.work.net - out.depth ** 2 / 2))
    out.times.update(foot_stop=t_rest, lift_off=t_rest + out.times["lift_off"],
                     apex=t_rest + t_f)
    out.energy_transcribed, out.transcribed = float(sol.objective), [sol]
    out.pieces = [(land, 0.0, t_rest), (res, t_rest, t_rest + t_f)]
    out.notes = [SLACK_NOTE] + [n for n in notes if "slack p" not in n] if notes else []
    out.grids = [grid_row(out)]
    return out


def _rest_guess(robot: Robot, impact: Impact, rest: np.ndarray) -> Trajectory:
    """A constant push from rest to the stroke's end, then a flight to the apex."""
    d = -rest[2]
    a = max((1 + robot.r_m) / robot.r_m * min(d - robot.foot_mass, robot.u_max) - 1, 0.1)
    L = robot.s - (rest[0] - rest[2])
    tp = math.sqrt(2 * max(L, 1e-3) / a)
    t = np.linspace(0.0, tp, 40)
    push = np.column_stack([rest[0] + a * t**2 / 2, a * t, np.full_like(t, rest[2]),
                            np.zeros_like(t), np.full_like(t, d)])
    tf = abs(impact.v0) + 1.0
    t2 = np.linspace(0.0, tf, 40)
    s = np.sin(np.pi * t2 / (2 * tf))
    h = impact.energy
    xb = push[-1, 0] + (h + robot.s / 2 - push[-1, 0]) * s
    xf = rest[2] + (h - rest[2]) * s
    fl = np.column_stack([xb, np.gradient(xb, t2), xf, np.gradient(xf, t2), np.full_like(t2, d)])
    u = np.r_[np.full(len(t), robot.r_m / (1 + robot.r_m) * (1 + a)), np.zeros(len(t2))]
    return Trajectory(np.r_[t, tp + t2], np.vstack([push, fl]),
                      np.column_stack([u, np.zeros(len(u))]),
                      ("x_b", "v_b", "x_f", "v_f", "crater"), ("u", "p"),
                      phase=np.r_[np.zeros(len(t), dtype=int), np.ones(len(t2), dtype=int)])


def sweep_hops(v0_values, robot: Robot = PAPER_ROBOT, eta: float = 0.0, *,
               legs: tuple[str, ...] = ("free", "impedance", "rigid"), grid: int = 9,
               progress: bool | None = False) -> dict[str, list[HopCycle | None]]:
    """Hop cycles over touchdown velocities (apex heights ``v0^2/2``), by continuation.

    Parameters
    ----------
    v0_values : sequence of float
        Touchdown velocities (< 0), from the easy end.
    robot : Robot
        The robot.
    eta : float
        Regenerative efficiency.
    legs : tuple of str
        Which of ``"free"``, ``"impedance"``, ``"rigid"``.
    grid : int
        Impedance gain grid per axis.
    progress : bool, optional
        Progress bar.
    """
    from softlanding.util.progress import progress as show_progress

    impacts = [Impact.of(v) for v in v0_values]
    out: dict[str, list[HopCycle | None]] = {leg: [] for leg in legs}
    prev: HopCycle | None = None
    fl: Solution | None = None
    for imp in show_progress(impacts, progress, "hop sweep", "apex"):
        if "free" in legs:
            prev = solve_hop(imp, robot, eta, warm_start=prev)
            out["free"].append(prev)
        if "impedance" in legs:
            h = best_impedance_hop(imp, robot, eta, grid, flight_guess=fl)
            fl = h.transcribed[0] if h is not None else fl
            out["impedance"].append(h)
        if "rigid" in legs:
            out["rigid"].append(rigid_hop(imp, robot, eta))
    return out


__all__ = ["APEX_TOL", "CONVERGED_RTOL", "HopCycle", "ThrustImpedance", "best_impedance_hop",
           "impedance_hop", "rigid_hop", "solve_hop", "sweep_hops"]
