"""One hop cycle, replayed exactly: its record and the checks of its replay.

:class:`HopCycle` (energy, depth, the checks, the transcriptions and the replay) and what
every leg of :mod:`softlanding.optimal.hopping` and :mod:`softlanding.optimal.hop_impedance`
shares: the problem's parameters, the transcribed force as a schedule, the evaluation of a
replay that ends at the apex (:func:`evaluate_replay`) and the minimum-energy flight from a
lift-off state (:func:`flight_to_apex`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp import Solution, SolveError, Trajectory
from softlanding.model.controllers import ForceSchedule
from softlanding.model.dynamics import mechanical_energy
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.hopping_problem import (
    START_PARAMETERS,
    apex_residuals,
    apex_target,
    hop_transcription,
)
from softlanding.optimal.phase_solve import transcribed_solve
from softlanding.optimal.pipeline import landing_parameters
from softlanding.simulation.actuator_work import Work, result_work, state_at
from softlanding.simulation.simulator import LandingResult, joined_trajectory
from softlanding.util.jsonable import json_safe
from softlanding.util.signals import raise_if_interrupted

SLACK_NOTE = ("the transcription meets its power slack p >= u (v_b - v_f) at its nodes and "
              "RK4 steps only (p is piecewise constant), so its own energy figure is "
              "approximate; the energy reported is the exact replay's")
"""Why a hop transcription's slack figure differs from the exact energy."""

APEX_TOL = 1e-5
"""Largest apex posture error (relative) accepted from a transcription's replay."""

CONVERGED_RTOL = 1e-6
"""A cycle's energy is taken as the continuous optimum (a local one: the hop is not convex)
when, refined on exact arcs, the refined NLP's energy and the exact replay's agree to this
(relative) and the energy lies within the grid sequence's extrapolation and its error; or,
a grid's, when that extrapolation and its error agree with it to this."""


@dataclass
class HopCycle:
    """One hop cycle and its energy (evaluated on the exact replay).

    Attributes
    ----------
    leg : str
        ``"free"`` (the optimum), ``"impedance"`` or ``"rigid"``.
    robot, impact : Robot, Impact
        The robot and the hop (``v0``: the touchdown velocity; apex ``v0^2/2`` above).
    eta : float
        Regenerative efficiency.
    energy : float
        Energy drawn per cycle, ``work.drawn(eta)``, on the exact replay.
    work : Work
        Positive and negative actuator work over the cycle.
    energy_transcribed : float
        The optimiser's own figure: the refined NLP's (the arcs' works) with
        ``exact_arcs``, else its slack on a grid (NaN where none).
    depth : float
        Crater depth.
    cot : float
        The paper's CoT of the cycle's landing: ``(E(0) - E(T)) / E(0)``, ``E(0) = v0^2/2``
        at touchdown, ``E(T)`` when the foot stops (potential energy from the impact pose).
    apex_error : float
        Largest error of the replay's apex posture (centre of mass height and velocity,
        leg length and rate).
    balance_error : float
        ``|E(apex) - E(touchdown) - (W_net - d^2/2)|``: the energy balance on the replay.
    gains : dict
        ``k_p, k_d, u_t`` (impedance), else empty.
    times : dict
        ``touchdown``, ``foot_stop``, ``lift_off``, ``apex``.
    replay : LandingResult or None
        The exact simulation of the cycle (stance and flight).
    transcribed : list of ocp.Solution
        The transcriptions solved.
    pieces : list of (LandingResult, float, float)
        The exact simulations the cycle is made of, with the cycle times each covers
        (each simulation starts at its own time 0).
    notes : list of str
    starts : list of dict
        ``solve_hop``'s deterministic starts (``stretch``: the push-off and flight of the
        start stretched in time), or the impedance hop's flight starts (``start``: the
        default guess or the caller's flight, then the best candidate's), with the energy
        each converged to (or its error): the cycle is the best of them, and their spread
        shows whether the optimum found is unique (local optima of a non-convex problem).
    grids : list of dict
        The grid sequence (``nodes`` per phase, replayed ``energy``), coarse to fine; the
        cycle reported is the finest grid's. Its controls are piecewise constant and the
        power slack ``p >= P`` holds at nodes and RK4 steps only, so a grid's optimum is
        above the continuous one by about ``c/N`` (first order, measured).
    energy_estimate : float
        The continuous optimum estimated from ``grids`` (Richardson, first order, on the
        two finest); NaN with one grid.
    energy_error : float
        The estimate's error estimate: how far the previous pair's extrapolation is from
        it (three grids or more), else the extrapolation's own correction; NaN with one
        grid. With ``exact_arcs`` the same (the grids behind the refinement), which the
        refined energy must lie within to be :attr:`converged`.
    exact_arcs : list of dict
        The arcs of the exact-arc refinement (:mod:`softlanding.optimal.hop_arcs`:
        ``mode``, ``kind``, ``durations``, ``forces``) when the cycle reported is its
        replay; empty when it is a grid's.
    """

    leg: str
    robot: Robot
    impact: Impact
    eta: float
    energy: float
    work: Work
    energy_transcribed: float
    depth: float
    cot: float
    apex_error: float
    balance_error: float
    gains: dict[str, float] = field(default_factory=dict)
    times: dict[str, float] = field(default_factory=dict)
    replay: LandingResult | None = None
    transcribed: list[Solution] = field(default_factory=list)
    pieces: list[tuple[LandingResult, float, float]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    starts: list[dict[str, Any]] = field(default_factory=list)
    grids: list[dict[str, Any]] = field(default_factory=list)
    energy_estimate: float = math.nan
    energy_error: float = math.nan
    exact_arcs: list[dict[str, Any]] = field(default_factory=list)

    @property
    def refined_gap(self) -> float:
        """With ``exact_arcs``: how far the refined NLP's energy is from the exact replay's
        (relative; a second computation of the same schedule's cost), else NaN."""
        if not self.exact_arcs:
            return math.nan
        return abs(self.energy - self.energy_transcribed) / max(abs(self.energy), 1e-300)

    @property
    def converged(self) -> bool:
        """The energy reported is the continuous optimum (a local one) to
        :data:`CONVERGED_RTOL`. Refined on exact arcs: the refined NLP's energy and the
        replay's agree to it, and the energy lies within the grid sequence's extrapolation
        and its error (an independent, coarser estimate; none with one grid: not
        converged). A grid's: the extrapolation agrees with it, and its error is below
        that."""
        if self.exact_arcs:
            return bool(self.refined_gap <= CONVERGED_RTOL
                        and abs(self.energy - self.energy_estimate) <= self.energy_error)
        gap = abs(self.energy - self.energy_estimate) + self.energy_error
        return bool(gap <= CONVERGED_RTOL * max(abs(self.energy_estimate), 1e-300))

    def unconverged_reason(self) -> str:
        """Why the energy is not the continuous optimum ("" when it is :attr:`converged`)."""
        if self.converged:
            return ""
        if self.exact_arcs and not self.refined_gap <= CONVERGED_RTOL:
            return (f"refined on exact arcs, but the refined NLP's energy "
                    f"({self.energy_transcribed:.10g}) and its exact replay's "
                    f"({self.energy:.10g}) differ by {self.refined_gap:.2g} (relative)")
        if self.exact_arcs and not math.isfinite(self.energy_estimate):
            return ("refined on exact arcs, not cross-checked: one grid, no extrapolation "
                    "to compare with (doublings >= 1)")
        if self.exact_arcs:
            return (f"refined on exact arcs, but outside the grid sequence's extrapolation "
                    f"{self.energy_estimate:.7g} +- {self.energy_error:.2g}: another optimum "
                    f"than the grids'")
        nodes = "/".join(map(str, self.grids[-1]["nodes"])) if self.grids else "?"
        if not math.isfinite(self.energy_estimate):
            return (f"discretised: the energy is the exact replay of a {nodes}-node grid's "
                    f"control, above the continuous optimum by an error not estimated (one "
                    f"grid)")
        return (f"discretised: the energy is the exact replay of a {nodes}-node grid's "
                f"control; the continuous optimum is estimated at {self.energy_estimate:.7g} "
                f"+- {self.energy_error:.2g} from {len(self.grids)} grids (the energy is "
                f"{self.energy - self.energy_estimate:.2g} above it)")

    @property
    def local_optima_spread(self) -> float:
        """Largest minus smallest replayed energy over the converged starts (0: one
        optimum found from every start; NaN: fewer than two converged)."""
        e = [s["energy"] for s in self.starts if "energy" in s]
        return max(e) - min(e) if len(e) > 1 else math.nan

    def trajectory(self, n: int = 1500) -> Trajectory:
        """The whole cycle from its exact simulations (``mode`` = ground mode).

        Parameters
        ----------
        n : int
            About how many samples.
        """
        return joined_trajectory(self.pieces, n)

    @property
    def apex_height(self) -> float:
        """``v0^2 / 2``: the foot's apex height above the surface."""
        return self.impact.energy

    @property
    def specific_energy(self) -> float:
        """Energy per cycle over the apex height (``m_t g h``)."""
        return self.energy / self.apex_height

    def uncertified_reason(self) -> str:
        """Why the cycle gets no PMP certificate, in one line (``hop --pmp``).

        ``ocp``'s certificate checks Pontryagin's conditions on refined, exact arcs; the
        free and rigid legs' transcriptions are read for their arc structure, and the one
        that is not bang-bang is named (the optimum holds the leg at zero power on arcs
        whose force follows the ground's, which the detection reads as interior arcs)."""
        if not self.transcribed:
            return ("no PMP certificate: an impedance leg is a feedback law with a thrust, "
                    "not an optimal control")
        if self.exact_arcs:
            return ("no PMP certificate: the cycle is refined on exact arcs ("
                    + ", ".join(f"{a['mode']} {a['kind']}" for a in self.exact_arcs)
                    + "), but on its arcs of one-signed power (+/-) the control is not "
                    "unique (their cost is the work between their end states), which ocp's "
                    "certificate does not cover; the energy is the exact replay of the "
                    "refined schedule")
        from ocp.structure.phase_refinement import detect_phase_structures

        sol = self.transcribed[0]
        for ph, st in zip(sol.phases, detect_phase_structures(sol), strict=True):
            if not st.refinable:
                kinds = "; ".join(f"{c.control}: {', '.join(c.kinds)}" for c in st.per_control
                                  if not c.refinable)
                return (f"no PMP certificate: the transcribed optimum is not bang-bang (phase "
                        f"{ph.problem.name!r}, arcs {kinds}), so there are no exact arcs to "
                        "check Pontryagin's conditions on; its energy is the exact replay of "
                        "the grid's control")
        return ("no PMP certificate: the hop's arcs are not refined (its transcription is "
                "replayed as a grid's control), and the certificate needs refined arcs")

    def unverified_reasons(self) -> list[str]:
        """Why this cycle cannot be taken as exact (empty: every check passed)."""
        out = []
        scale = max(1.0, self.apex_height)
        if not self.apex_error <= APEX_TOL * scale:
            out.append(f"the replay misses the apex posture by {self.apex_error:.2e}")
        if not self.balance_error <= 1e-8 * scale:
            out.append(f"the replay's energy balance is off by {self.balance_error:.2e}")
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (``unverified_reasons``: the replay's checks and, for a cycle
        whose energy is not the continuous optimum, why; empty exactly when verified)."""
        reasons = self.unverified_reasons() + [r for r in [self.unconverged_reason()] if r]
        return json_safe({
            "leg": self.leg, "v0": self.impact.v0, "apex_height": self.apex_height,
            "eta": self.eta, "energy": self.energy, "energy_per_apex_height":
                self.specific_energy, "positive_work": self.work.positive,
            "negative_work": self.work.negative, "net_work": self.work.net,
            "ground_loss": self.depth ** 2 / 2, "energy_transcribed": self.energy_transcribed,
            "depth": self.depth, "cot": self.cot, "apex_error": self.apex_error,
            "balance_error": self.balance_error, "gains": self.gains, "times": self.times,
            "verified": not reasons, "replay_verified": not self.unverified_reasons(),
            "unverified_reasons": reasons, "converged": self.converged,
            "optimum": "converged" if self.converged else "discretised",
            "method": "exact arcs" if self.exact_arcs else "grid",
            "exact_arcs": self.exact_arcs,
            "unconverged_reason": self.unconverged_reason(),
            "energy_estimate": self.energy_estimate, "energy_error": self.energy_error,
            "refined_gap": self.refined_gap,
            "grids": self.grids, "notes": self.notes,
            "starts": self.starts, "local_optima_spread": self.local_optima_spread,
            "robot": self.robot.to_dict()})


# ---------------------------------------------------------------- helpers
def hop_parameters(robot: Robot, impact: Impact, eta: float,
                   start: np.ndarray | None = None) -> dict[str, float]:
    """The hop problem's parameter values.

    Parameters
    ----------
    robot, impact, eta
        The robot, the touchdown and the regenerative efficiency.
    start : array, optional
        A given first state (the flight's lift-off, the push-off's rest).
    """
    p = {**landing_parameters(robot, impact), "l0": robot.s / 2, "eta": eta}
    if start is not None:
        p.update(zip(START_PARAMETERS, map(float, start), strict=True))
    return p


def crater_depth(res: LandingResult, t_end: float) -> float:
    """The crater's depth up to ``t_end`` (deepest foot position at the segment ends).

    Parameters
    ----------
    res : LandingResult
        An exact replay.
    t_end : float
        Up to this time.
    """
    seg = res.segments
    ends = [float(-seg["z"][k][2]) for k in range(len(seg["t"]) - 1) if seg["t"][k] <= t_end]
    return max([0.0, *ends, float(-state_at(res, t_end)[2])])


def force_schedule(sols: list[Solution]) -> tuple[ForceSchedule, float]:
    """The transcriptions' piecewise-constant force, phase after phase, and its length.

    Parameters
    ----------
    sols : list of ocp.Solution
        Transcriptions, in the order they are flown.
    """
    durs: list[float] = []
    vals: list[float] = []
    for sol in sols:
        for ph in sol.phases:
            h = float(ph.T - ph.t0) / ph.N
            if h > 0:
                durs += [h] * ph.N
                vals += [float(u) for u in ph.u[:, 0]]
    return ForceSchedule.from_arcs(durs, vals + [0.0]), float(np.sum(durs))


def evaluate_replay(leg: str, robot: Robot, impact: Impact, eta: float, res: LandingResult,
                    t_apex: float, pre: Work, E_td: float) -> HopCycle:
    """Energy, depth, CoT and the checks of an exact replay ending at the apex.

    Parameters
    ----------
    leg : str
        Which leg (``"free"`` also gets its landing's CoT).
    robot, impact, eta
        The robot, the touchdown and the regenerative efficiency.
    res : LandingResult
        The replay.
    t_apex : float
        Its apex time.
    pre : Work
        The actuator's work before the replay starts.
    E_td : float
        The mechanical energy at touchdown.
    """
    w = pre + result_work(res, t_apex)
    x_apex = state_at(res, t_apex)
    err = float(np.max(np.abs(apex_residuals(x_apex, robot.body_mass, robot.foot_mass,
                                             impact.energy, robot.s))))
    depth = crater_depth(res, t_apex)
    E_apex = float(mechanical_energy(x_apex, robot.r_m))
    balance = abs(E_apex - E_td - (w.net - depth ** 2 / 2))
    stop = res.t_first_stop
    cot = landing_cot(robot, impact, res) if leg == "free" else math.nan
    seg = res.segments
    flight = [float(t) for t, m in zip(seg["t"][:-1], seg["mode"], strict=True) if m == 2]
    return HopCycle(leg, robot, impact, eta, w.drawn(eta), w, math.nan, depth, cot, err,
                    balance, times={"touchdown": 0.0, "foot_stop": float(stop),
                                    "lift_off": flight[0] if flight else math.nan,
                                    "apex": t_apex}, replay=res)


def landing_cot(robot: Robot, impact: Impact, res: LandingResult) -> float:
    """The landing's cost of transport: the mechanical energy lost from touchdown to the
    foot's first stop, over the impact energy.

    Parameters
    ----------
    robot, impact
        The robot and the touchdown.
    res : LandingResult
        The landing's replay.
    """
    x0 = impact.initial_state(robot.replace(l0=None))
    x = state_at(res, res.t_first_stop)
    rel = float(mechanical_energy(x, robot.r_m) - mechanical_energy(x0, robot.r_m))
    return -rel / impact.energy


def grid_row(c: HopCycle) -> dict[str, Any]:
    """One grid of a cycle's grid sequence: its nodes per phase and energies.

    Parameters
    ----------
    c : HopCycle
        The cycle solved on that grid.
    """
    sol = c.transcribed[0]
    return {"nodes": [int(ph.N) for ph in sol.phases], "energy": c.energy,
            "energy_transcribed": c.energy_transcribed}


# ------------------------------------------------------------- flight alone
def flight_to_apex(robot: Robot, impact: Impact, eta: float, start: np.ndarray,
                   guess_from: Solution | None = None) -> Solution:
    """The minimum-energy flight from a lift-off state to the apex posture.

    Parameters
    ----------
    robot, impact, eta
        The robot, the touchdown and the regenerative efficiency.
    start : array
        The lift-off state.
    guess_from : ocp.Solution, optional
        A neighbouring flight (its start; a cold guess when it fails).
    """
    tr = hop_transcription("lift-off")
    p = hop_parameters(robot, impact, eta, start)
    notes: list[str] = []
    if guess_from is not None:
        try:
            return transcribed_solve(tr, p, guess_from, None, notes)
        except SolveError:
            raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
            pass
    mb, mf = robot.body_mass, robot.foot_mass
    vc = mb * start[1] + mf * start[3]
    tf = max(vc, 0.1)
    t = np.linspace(0.0, tf, 60)
    target = apex_target(mb, impact.energy, robot.s)
    a = t / tf
    com = mb * start[0] + mf * start[2] + vc * t - t**2 / 2
    leg = (start[0] - start[2]) * (1 - a) + target[2] * a
    x = np.column_stack([com + mf * leg, np.gradient(com + mf * leg, t), com - mb * leg,
                         np.gradient(com - mb * leg, t), np.full(len(t), -start[2])])
    g = Trajectory(t, x, np.zeros((len(t), 2)), ("x_b", "v_b", "x_f", "v_f", "crater"),
                   ("u", "p"), phase=np.zeros(len(t), dtype=int))
    return transcribed_solve(tr, p, g, None, notes)


__all__ = ["APEX_TOL", "CONVERGED_RTOL", "SLACK_NOTE", "HopCycle", "crater_depth",
           "evaluate_replay", "flight_to_apex", "force_schedule", "grid_row",
           "hop_parameters", "landing_cot"]
