"""The impedance hop: one ``(k_p, k_d)`` with a thrust from the body's lowest point.

In stance ``u = -k_p (l - s/2) - k_d l'``, plus a constant thrust ``u_t`` while the foot
rests on the crater (the simulator's per-mode law, exact), ``u_t`` set by bisection so the
centre of mass reaches the apex (:func:`impedance_hop`); :func:`best_impedance_hop`
searches the gains. The flight is the minimum-energy one every leg shares
(:func:`softlanding.optimal.hop_cycle.flight_to_apex`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp import Solution, SolveError
from softlanding.model.dynamics import mechanical_energy
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.optimal.hop_cycle import (
    HopCycle,
    crater_depth,
    evaluate_replay,
    flight_to_apex,
    force_schedule,
    grid_row,
    landing_cot,
)
from softlanding.optimal.hopping_problem import apex_target
from softlanding.optimal.limits import hop_input
from softlanding.simulation.actuator_work import Work, result_work, state_at
from softlanding.simulation.simulator import LandingResult, simulate
from softlanding.util.progress import step
from softlanding.util.signals import raise_if_interrupted


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
    target = apex_target(robot.body_mass, impact.energy, robot.s)[0]
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
        fl = flight_to_apex(robot, impact, eta, st.z_lift, flight_guess)
    except SolveError:
        raise_if_interrupted()  # CasADi turns Ctrl-C/SIGTERM into a failed solve
        return None
    sched, t_f = force_schedule([fl])
    fres = simulate(robot, impact, sched, x0=st.z_lift, t_max=t_f + 1.0)
    x0 = impact.initial_state(robot.replace(l0=None))
    out = evaluate_replay("impedance", robot, impact, eta, fres, t_f, st.work,
                    float(mechanical_energy(x0, robot.r_m)))
    depth = crater_depth(st.second, st.t_lift)
    out.depth, out.cot = depth, landing_cot(robot, impact, st.first)
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
    out.grids = [grid_row(out)]  # the flight's
    return out


def _rank(h: HopCycle) -> tuple[bool, float]:
    """Verified cycles first, then the lower energy."""
    return bool(h.unverified_reasons()), h.energy


def _gain_grid(robot: Robot, impact: Impact, eta: float,
               grid: int) -> list[tuple[float, float, float]]:
    """``(stance energy, k_p, k_d)`` of every grid gain that hops (no flight solved)."""
    cands = []
    for i, kp in enumerate(np.linspace(0.05, 2.0, grid), 1):
        for kd in np.linspace(0.0, 2.0, grid):
            u_t = _thrust_for(robot, impact, float(kp), float(kd))
            if u_t is None:
                continue
            cands.append((_stance(robot, impact, kp, kd, u_t).work.drawn(eta), float(kp),
                          float(kd)))
        step(f"gain grid, row {i} of {grid}")
    return cands


def _cold_then_best(impact: Impact, robot: Robot, eta: float, gains: list[tuple[float, float]],
                    flight_guess: Solution | None) -> dict[tuple[float, float], list]:
    """Every candidate's flight solved from ``flight_guess`` (None: the default guess),
    then every other candidate's re-solved from the best of those flights: ``(start, hop
    or None)`` per start and candidate, ``2 n - 1`` solves for ``n`` candidates (``n`` if
    none flies). The best first-pass flight is chosen by :func:`_rank`, ties to the
    smaller gains, so each candidate's starts do not depend on the candidates' order."""
    def solved(k: tuple[float, float], guess: Solution | None) -> HopCycle | None:
        h = impedance_hop(impact, *k, robot, eta, flight_guess=guess)
        step("a flight solved")
        return h

    first = "the caller's flight" if flight_guess is not None else "the default guess"
    tries = {k: [(first, solved(k, flight_guess))] for k in sorted(gains)}
    flown = {k: h for k, t in tries.items() if (h := t[0][1]) is not None}
    if flown:
        b = min(flown, key=lambda k: _rank(flown[k]))  # first of equals: sorted gains
        for k in [k for k in tries if k != b]:
            tries[k].append((f"the flight of k_p={b[0]:g}, k_d={b[1]:g}",
                             solved(k, flown[b].transcribed[0])))
    return tries


def best_impedance_hop(impact: Impact | float, robot: Robot = PAPER_ROBOT, eta: float = 0.0,
                       grid: int = 9, top: int = 3, *,
                       flight_guess: Solution | None = None) -> HopCycle | None:
    """The best impedance hop over a ``(k_p, k_d)`` grid in ``[0.05, 2] x [0, 2]``: the
    stance of every grid point is simulated, and the best ``top`` by stance energy get
    their flight solved; the lowest verified total wins.

    The flight NLP has local optima, so the start matters: each candidate's flight is
    solved from ``flight_guess`` (or the default guess), then every other candidate's
    again from the best of those flights, and each candidate keeps its lowest verified
    energy (``2 top - 1`` flight solves). The result does not depend on the candidates'
    order and is never above the best flight from ``flight_guess`` alone; it is the best
    of those starts, a local optimum, not a global one. The winner's ``starts`` lists the
    energy each of its starts reached.

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
        A neighbouring flight's transcription (the first start of every candidate).
    """
    robot, impact = hop_input(robot, impact, eta)
    cands = _gain_grid(robot, impact, eta, grid)
    chosen = [(kp, kd) for _, kp, kd in sorted(cands)[:top]]
    best: HopCycle | None = None
    for runs in _cold_then_best(impact, robot, eta, chosen, flight_guess).values():
        hops = [h for _, h in runs if h is not None]  # candidates in sorted gains
        if not hops:
            continue
        h = min(hops, key=_rank)  # first of equals: the first start
        h.starts = [{"start": s, "energy": x.energy} if x is not None else
                    {"start": s, "error": "no flight"} for s, x in runs]
        if best is None or _rank(h) < _rank(best):
            best = h
    if best is not None:
        best.notes.append(
            f"best of a {grid} x {grid} gain grid in [0.05, 2] x [0, 2] ({len(cands)} gains "
            f"hop; the {len(chosen)} best stances got their flight, solved from "
            f"{best.starts[0]['start']}, "
            "then again from the best of those flights, each candidate's lowest verified "
            "energy kept: the best of those starts, a local optimum, not a global one)")
    return best


__all__ = ["ThrustImpedance", "best_impedance_hop", "impedance_hop"]
