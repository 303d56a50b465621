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
  searches the gains;
* :func:`rigid_hop` -- the leg locked until the robot comes to rest on its crater
  (the paper's rigid impactor), then the optimal push-off.

In flight every leg is returned to the apex posture by the same minimum-energy
flight (:func:`softlanding.optimal.hopping_problem.build_hop_problem` from lift-off), so the
three differ only in stance. Every energy reported is evaluated on the **exact
replay** of the control (simulator for stance and flight, power integrated by
quadrature between its sign changes: :mod:`softlanding.simulation.actuator_work`), not on the
transcription's slack; the cycle's energy balance ``E(apex) - E(touchdown) = W_net -
d^2/2`` is checked, and so is the apex posture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from ocp import Solution, SolveError, Trajectory
from softlanding.errors import check_count, expect
from softlanding.model.controllers import ForceSchedule, Rigid
from softlanding.model.dynamics import mechanical_energy
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.hopping_problem import START_PARAMETERS, hop_transcription
from softlanding.optimal.limits import hop_input
from softlanding.optimal.phase_solve import transcribed_solve
from softlanding.optimal.pipeline import landing_parameters
from softlanding.simulation.actuator_work import Work, result_work, state_at
from softlanding.simulation.simulator import LandingResult, joined_trajectory, simulate
from softlanding.util.jsonable import json_safe
from softlanding.util.progress import step
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
        start stretched in time) with the energy each converged to (or its error): the
        cycle is the best of them, and their spread shows whether the optimum found is
        unique (local optima of a non-convex problem).
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
def _params(robot: Robot, impact: Impact, eta: float, start: np.ndarray | None = None
            ) -> dict[str, float]:
    p = {**landing_parameters(robot, impact), "l0": robot.s / 2, "eta": eta}
    if start is not None:
        p.update(zip(START_PARAMETERS, map(float, start), strict=True))
    return p


def _apex_target(robot: Robot, impact: Impact) -> np.ndarray:
    """Centre of mass height and velocity, leg length and rate, at the apex."""
    return np.array([impact.energy + robot.body_mass * robot.s / 2, 0.0, robot.s / 2, 0.0])


def _posture(robot: Robot, x: np.ndarray) -> np.ndarray:
    mb, mf = robot.body_mass, robot.foot_mass
    return np.array([mb * x[0] + mf * x[2], mb * x[1] + mf * x[3], x[0] - x[2], x[1] - x[3]])


def _crater(res: LandingResult, t_end: float) -> float:
    """The crater's depth up to ``t_end`` (deepest foot position at the segment ends)."""
    seg = res.segments
    ends = [float(-seg["z"][k][2]) for k in range(len(seg["t"]) - 1) if seg["t"][k] <= t_end]
    return max([0.0, *ends, float(-state_at(res, t_end)[2])])


def _schedule(sols: list[Solution]) -> tuple[ForceSchedule, float]:
    """The transcriptions' piecewise-constant force, phase after phase, and its length."""
    durs: list[float] = []
    vals: list[float] = []
    for sol in sols:
        for ph in sol.phases:
            h = float(ph.T - ph.t0) / ph.N
            if h > 0:
                durs += [h] * ph.N
                vals += [float(u) for u in ph.u[:, 0]]
    return ForceSchedule.from_arcs(durs, vals + [0.0]), float(np.sum(durs))


def _evaluate(leg: str, robot: Robot, impact: Impact, eta: float, res: LandingResult,
              t_apex: float, pre: Work, E_td: float) -> HopCycle:
    """Energy, depth, CoT and the checks of an exact replay ending at the apex."""
    w = pre + result_work(res, t_apex)
    x_apex = state_at(res, t_apex)
    err = float(np.max(np.abs(_posture(robot, x_apex) - _apex_target(robot, impact))))
    depth = _crater(res, t_apex)
    E_apex = float(mechanical_energy(x_apex, robot.r_m))
    balance = abs(E_apex - E_td - (w.net - depth ** 2 / 2))
    stop = res.t_first_stop
    cot = _landing_cot(robot, impact, res) if leg == "free" else math.nan
    seg = res.segments
    flight = [float(t) for t, m in zip(seg["t"][:-1], seg["mode"], strict=True) if m == 2]
    return HopCycle(leg, robot, impact, eta, w.drawn(eta), w, math.nan, depth, cot, err,
                    balance, times={"touchdown": 0.0, "foot_stop": float(stop),
                                    "lift_off": flight[0] if flight else math.nan,
                                    "apex": t_apex}, replay=res)


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
    why not (:mod:`softlanding.optimal.hop_arcs`)."""
    from softlanding.optimal.hop_arcs import detect_arcs, refine_arcs

    try:
        r = refine_arcs(detect_arcs(c.transcribed[0], robot), robot, impact, eta)
    except ValueError as err:
        c.notes.append(f"exact arcs not refined: {err}")
        return c
    if r.status != "Solve_Succeeded":
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        c.notes.append(f"exact arcs not refined: the refinement NLP stopped ({r.status})")
        return c
    x0 = impact.initial_state(robot.replace(l0=None))
    res = simulate(robot, impact, r.schedule, x0=x0, t_max=r.duration + 1.0)
    out = _evaluate("free", robot, impact, eta, res, r.duration, Work(),
                    float(mechanical_energy(x0, robot.r_m)))
    if out.unverified_reasons() or not out.energy <= c.energy:
        why = "; ".join(out.unverified_reasons()) or (
            f"its energy {out.energy:.9g} is above the grid's {c.energy:.9g}")
        c.notes.append(f"exact arcs not used: the refined schedule's replay fails ({why})")
        return c
    out.energy_transcribed = r.energy
    out.transcribed, out.pieces, out.starts, out.grids = c.transcribed, [
        (res, 0.0, r.duration)], c.starts, c.grids
    # arcs the refinement shrank to nothing (a grid's blips) are left out of the report
    kept = [a for a in r.arcs if sum(a.durations) > 1e-6]
    out.exact_arcs = [{"mode": a.mode, "kind": a.kind, "durations": list(a.durations),
                       "forces": list(a.forces)} for a in kept]
    out.energy_estimate, out.energy_error = c.energy_estimate, c.energy_error
    out.notes = [n for n in c.notes if n != SLACK_NOTE] + [
        f"exact arcs: {len(kept)} arcs ({', '.join(a.mode + ' ' + a.kind for a in kept)}), "
        f"switching times and "
        f"forces refined with every arc flowed exactly; the energy is the exact replay of "
        f"the refined schedule, {c.energy - out.energy:.3g} below the finest grid's"]
    return out


def _grid_row(c: HopCycle) -> dict[str, Any]:
    sol = c.transcribed[0]
    return {"nodes": [int(ph.N) for ph in sol.phases], "energy": c.energy,
            "energy_transcribed": c.energy_transcribed}


def _grid_sequence(base: HopCycle, robot: Robot, impact: Impact, eta: float,
                   doublings: int) -> HopCycle:
    """The base cycle re-solved on ``doublings`` successively doubled grids (each from the
    previous grid's solution); the finest verified one with the sequence and its
    extrapolation (first-order Richardson on the two finest grids, since a grid's excess
    energy is about ``c h``)."""
    grids, cur = [_grid_row(base)], base
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
        grids.append(_grid_row(c))
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
    sol = transcribed_solve(tr, _params(robot, impact, eta), guess, ws, notes)
    sched, t_apex = _schedule([sol])
    x0 = impact.initial_state(robot.replace(l0=None))
    res = simulate(robot, impact, sched, x0=x0, t_max=t_apex + 1.0)
    out = _evaluate("free", robot, impact, eta, res, t_apex, Work(),
                    float(mechanical_energy(x0, robot.r_m)))
    out.energy_transcribed = float(sol.objective)
    out.transcribed, out.pieces = [sol], [(res, 0.0, t_apex)]
    out.notes = [SLACK_NOTE] + [n for n in notes if "slack p" not in n] if notes else []
    return out


# ------------------------------------------------------------- flight alone
def _flight(robot: Robot, impact: Impact, eta: float, start: np.ndarray,
            guess_from: Solution | None = None) -> Solution:
    """The minimum-energy flight from a lift-off state to the apex posture."""
    tr = hop_transcription("lift-off")
    p = _params(robot, impact, eta, start)
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
    target = _apex_target(robot, impact)
    a = t / tf
    com = mb * start[0] + mf * start[2] + vc * t - t**2 / 2
    leg = (start[0] - start[2]) * (1 - a) + target[2] * a
    x = np.column_stack([com + mf * leg, np.gradient(com + mf * leg, t), com - mb * leg,
                         np.gradient(com - mb * leg, t), np.full(len(t), -start[2])])
    g = Trajectory(t, x, np.zeros((len(t), 2)), ("x_b", "v_b", "x_f", "v_f", "crater"),
                   ("u", "p"), phase=np.zeros(len(t), dtype=int))
    return transcribed_solve(tr, p, g, None, notes)


# ------------------------------------------------------------- impedance
@dataclass(frozen=True)
class ThrustImpedance:
    """Impedance ``u = -k_p (l - s/2) - k_d l'`` plus a thrust ``u_t`` while the foot is
    on the ground (yielding or static), none in flight: a per-ground-mode affine law, which
    the exact simulator runs natively. :func:`impedance_hop` switches the thrust on at the
    body's lowest point (a second simulation from that state), so the thrust acts from
    the bottom of the stance until lift-off (Raibert's thrust phase).

    Parameters
    ----------
    k_p, k_d : float
        Stiffness and damping (>= 0).
    u_t : float
        Thrust during ground contact (>= 0).
    """

    k_p: float
    k_d: float
    u_t: float

    def kernel_arrays(self, mats: dict[str, Any],
                      robot: Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The law per ground mode (yielding, static, flight) for the simulator.

        Parameters
        ----------
        mats : dict
            Mode matrices (unused).
        robot : Robot
            The robot (the rest length is ``s/2``).
        """
        g = np.array([-self.k_p, -self.k_d, self.k_p, self.k_d, self.k_p * robot.s / 2])
        Kf = np.tile(g, (3, 1))
        Kf[:2, 4] += self.u_t
        return Kf, np.zeros(0), np.zeros(0)

    def describe(self) -> str:
        """One line."""
        return f"impedance k_p={self.k_p:g}, k_d={self.k_d:g} with thrust u_t={self.u_t:g}"

    def to_dict(self) -> dict[str, Any]:
        """``kind, k_p, k_d, u_t``."""
        return {"kind": "thrust impedance", "k_p": self.k_p, "k_d": self.k_d, "u_t": self.u_t}


@dataclass
class _Stance:
    """An impedance stance: compression (no thrust) to the body's lowest point, then the
    thrust until lift-off; two exact simulations joined at the bottom."""

    apex: float
    first: LandingResult
    t_bottom: float
    second: LandingResult | None = None
    t_lift: float = math.nan
    z_lift: np.ndarray = field(default_factory=lambda: np.zeros(4))

    @property
    def work(self) -> Work:
        """Actuator work from touchdown to lift-off."""
        assert self.second is not None
        return result_work(self.first, self.t_bottom) + result_work(self.second, self.t_lift)


def _bottom(res: LandingResult) -> float:
    """First time the body's velocity crosses zero upwards before any lift-off (NaN if none)."""
    from scipy.optimize import brentq

    seg = res.segments
    for k in range(len(seg["t"]) - 1):
        if seg["mode"][k] == 2:
            return math.nan
        t0, t1 = float(seg["t"][k]), float(seg["t"][k + 1])
        if not math.isfinite(t1):
            t1 = t0 + 100.0
        ts = np.linspace(t0, t1, 41)
        vb = np.array([state_at(res, t)[1] for t in ts])
        up = np.flatnonzero((vb[:-1] < 0) & (vb[1:] >= 0))
        if len(up):
            a, b = ts[up[0]], ts[up[0] + 1]
            return float(brentq(lambda t: state_at(res, t)[1], a, b, xtol=1e-15))
    return math.nan


def _in_stroke(res: LandingResult, t_end: float, s: float, probes: int = 60) -> bool:
    """The leg stays within ``[0, s]`` up to ``t_end`` (sampled on every segment)."""
    seg = res.segments
    for k in range(len(seg["t"]) - 1):
        t0, t1 = float(seg["t"][k]), min(float(seg["t"][k + 1]), t_end)
        if t1 < t0:
            break
        for t in np.linspace(t0, t1, probes):
            x = state_at(res, t)
            if not -1e-12 <= x[0] - x[2] <= s + 1e-12:
                return False
    return True


def _compression(robot: Robot, impact: Impact, k_p: float,
                 k_d: float) -> tuple[LandingResult, float]:
    """The landing without thrust, and the time of the body's lowest point."""
    x0 = impact.initial_state(robot.replace(l0=None))
    first = simulate(robot, impact, ThrustImpedance(k_p, k_d, 0.0), x0=x0,  # type: ignore
                     t_max=200.0)
    return first, _bottom(first)


def _stance(robot: Robot, impact: Impact, k_p: float, k_d: float, u_t: float,
            comp: tuple[LandingResult, float] | None = None, check: bool = False) -> _Stance:
    """The stance and the apex height its lift-off state reaches (-inf when it does not
    lift off, or, with ``check``, leaves the stroke)."""
    first, tb = comp if comp is not None else _compression(robot, impact, k_p, k_d)
    out = _Stance(-math.inf, first, tb)
    if not math.isfinite(tb):
        return out
    zb = state_at(first, tb)
    second = simulate(robot, impact, ThrustImpedance(k_p, k_d, u_t), x0=zb,  # type: ignore
                      t_max=200.0)
    out.second = second
    seg = second.segments
    lift = [k for k, m in enumerate(seg["mode"]) if m == 2]
    if not lift:
        return out
    t_lo = float(seg["t"][lift[0]])
    if check and not (_in_stroke(first, tb, robot.s) and _in_stroke(second, t_lo, robot.s)):
        return out
    z = seg["z"][lift[0]][:4]
    mb, mf = robot.body_mass, robot.foot_mass
    vc = mb * z[1] + mf * z[3]
    out.apex = float(mb * z[0] + mf * z[2] + max(vc, 0.0) * vc / 2)
    out.t_lift, out.z_lift = t_lo, np.asarray(z, dtype=float)
    return out


def _thrust_for(robot: Robot, impact: Impact, k_p: float, k_d: float) -> float | None:
    """The thrust that brings the centre of mass to the apex (bisection to 1e-11), or None
    (no thrust within ``u_max`` does it inside the stroke)."""
    target = _apex_target(robot, impact)[0]
    comp = _compression(robot, impact, k_p, k_d)
    if not math.isfinite(comp[1]):
        return None
    lo, hi = 0.0, float(robot.u_max)  # type: ignore[arg-type]
    if _stance(robot, impact, k_p, k_d, hi, comp).apex < target:
        return None
    if _stance(robot, impact, k_p, k_d, lo, comp).apex >= target:
        hi = lo
    while hi - lo > 1e-11 * max(1.0, hi):
        mid = 0.5 * (lo + hi)
        if _stance(robot, impact, k_p, k_d, mid, comp).apex >= target:
            hi = mid
        else:
            lo = mid
    if _stance(robot, impact, k_p, k_d, hi, comp, check=True).apex < target:
        return None
    return hi


def impedance_hop(impact: Impact | float, k_p: float, k_d: float,
                  robot: Robot = PAPER_ROBOT, eta: float = 0.0, *,
                  flight_guess: Solution | None = None) -> HopCycle | None:
    """The hop of one impedance ``(k_p, k_d)`` (thrust by bisection), or None when no
    thrust within ``u_max`` makes it reach the apex inside the stroke.

    Parameters
    ----------
    impact : Impact or float
        Touchdown velocity.
    k_p, k_d : float
        Gains.
    robot : Robot
        The robot.
    eta : float
        Regenerative efficiency.
    flight_guess : ocp.Solution, optional
        A neighbouring flight's transcription (starting guess).
    """
    robot, impact = hop_input(robot, impact, eta)
    u_t = _thrust_for(robot, impact, k_p, k_d)
    if u_t is None:
        return None
    st = _stance(robot, impact, k_p, k_d, u_t, check=True)
    assert st.second is not None
    try:
        fl = _flight(robot, impact, eta, st.z_lift, flight_guess)
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return None
    sched, t_f = _schedule([fl])
    fres = simulate(robot, impact, sched, x0=st.z_lift, t_max=t_f + 1.0)
    x0 = impact.initial_state(robot.replace(l0=None))
    out = _evaluate("impedance", robot, impact, eta, fres, t_f, st.work,
                    float(mechanical_energy(x0, robot.r_m)))
    depth = _crater(st.second, st.t_lift)
    out.depth, out.cot = depth, _landing_cot(robot, impact, st.first)
    out.balance_error = abs(float(mechanical_energy(state_at(fres, t_f), robot.r_m))
                            - float(mechanical_energy(x0, robot.r_m))
                            - (out.work.net - depth ** 2 / 2))
    t_lo = st.t_bottom + st.t_lift
    out.times.update(foot_stop=st.first.t_first_stop, bottom=st.t_bottom, lift_off=t_lo,
                     apex=t_lo + t_f)
    out.gains, out.transcribed, out.replay = {"k_p": k_p, "k_d": k_d, "u_t": u_t}, [fl], \
        st.second
    out.pieces = [(st.first, 0.0, st.t_bottom), (st.second, st.t_bottom, t_lo),
                  (fres, t_lo, t_lo + t_f)]
    out.grids = [_grid_row(out)]  # the flight's
    return out


def _landing_cot(robot: Robot, impact: Impact, res: LandingResult) -> float:
    x0 = impact.initial_state(robot.replace(l0=None))
    x = state_at(res, res.t_first_stop)
    rel = float(mechanical_energy(x, robot.r_m) - mechanical_energy(x0, robot.r_m))
    return -rel / impact.energy


def best_impedance_hop(impact: Impact | float, robot: Robot = PAPER_ROBOT, eta: float = 0.0,
                       grid: int = 9, top: int = 3, *,
                       flight_guess: Solution | None = None) -> HopCycle | None:
    """The best impedance hop over a ``(k_p, k_d)`` grid in ``[0, 2]^2`` (plus a local
    zoom around the best): the stance of every grid point is simulated, and the best
    ``top`` by stance energy get their flight solved; the lowest total wins.

    Parameters
    ----------
    impact : Impact or float
        Touchdown velocity.
    robot : Robot
        The robot.
    eta : float
        Regenerative efficiency.
    grid : int
        Points per axis.
    top : int
        Candidates whose flight is solved.
    flight_guess : ocp.Solution, optional
        A neighbouring flight's transcription (starting guess).
    """
    robot, impact = hop_input(robot, impact, eta)
    cands = []
    for i, kp in enumerate(np.linspace(0.05, 2.0, grid), 1):
        for kd in np.linspace(0.0, 2.0, grid):
            u_t = _thrust_for(robot, impact, float(kp), float(kd))
            if u_t is None:
                continue
            cands.append((_stance(robot, impact, kp, kd, u_t).work.drawn(eta), float(kp),
                          float(kd)))
        step(f"gain grid, row {i} of {grid}")
    if not cands:
        return None
    best: HopCycle | None = None
    for _, kp, kd in sorted(cands)[:top]:
        h = impedance_hop(impact, kp, kd, robot, eta, flight_guess=flight_guess)
        step("a flight solved")
        if h is not None and (best is None or h.energy < best.energy):
            best = h
        if h is not None:
            flight_guess = h.transcribed[0]
    if best is not None:
        best.notes.append(f"best of a {grid} x {grid} gain grid in [0.05, 2] x [0, 2] "
                          f"({len(cands)} gains hop; the {top} best stances got their flight)")
    return best


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
    p = _params(robot, impact, eta, rest)
    notes: list[str] = []
    sol = transcribed_solve(tr, p, _rest_guess(robot, impact, rest), None, notes)
    sched, t_f = _schedule([sol])
    res = simulate(robot, impact, sched, x0=rest, t_max=t_f + 1.0)
    out = _evaluate("rigid", robot, impact, eta, res, t_f, Work(),
                    float(mechanical_energy(x0, robot.r_m)))
    out.depth = max(land.depth, _crater(res, t_f))
    out.cot = _landing_cot(robot, impact, land)
    out.balance_error = abs(float(mechanical_energy(state_at(res, t_f), robot.r_m))
                            - float(mechanical_energy(x0, robot.r_m))
                            - (out.work.net - out.depth ** 2 / 2))
    out.times.update(foot_stop=t_rest, lift_off=t_rest + out.times["lift_off"],
                     apex=t_rest + t_f)
    out.energy_transcribed, out.transcribed = float(sol.objective), [sol]
    out.pieces = [(land, 0.0, t_rest), (res, t_rest, t_rest + t_f)]
    out.notes = [SLACK_NOTE] + [n for n in notes if "slack p" not in n] if notes else []
    out.grids = [_grid_row(out)]
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
