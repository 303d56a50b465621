"""Exact-arc refinement of the free hop: its switching times, not a grid.

The hop's optimum (:func:`softlanding.optimal.hopping.solve_hop`) is not bang-bang, but
every arc of it is one of five kinds, each exact in the affine modes of the model
(:func:`softlanding.model.dynamics.mode_matrices`):

* ``"coast"``: ``u = 0`` (no power);
* ``"lock"``: the leg held at constant length, ``u`` the lock force of the ground mode
  (:func:`softlanding.model.controllers.rigid_lock_gains`; no power);
* ``"capacity"``: the foot at rest on its crater, the support force at the crater's
  capacity (``u`` a feedback law in the state: the boundary arc of that constraint), the
  leg absorbing (``P <= 0``);
* ``"+"`` / ``"-"``: arcs where the actuator's power ``P = u (v_b - v_f)`` keeps one sign.
  On them the cost is the arc's work ``int P dt``, which depends on the arc's end states
  only (the robot's mechanical energy, plus the ground's ``K x_f^2 / 2`` while yielding):
  the optimum's control there is not unique (a flat valley, hence the transcription's
  "interior" arcs), and a constant piece of free length reaches the same end states at
  the same cost (:data:`PIECES`).

The arcs are read off a transcription (:func:`detect_arcs`); the unknowns are every
piece's duration (and force, on ``+``/``-`` arcs), the state at every arc's start and
the crater depth; each piece is flowed exactly (the matrix exponential of its affine
mode, by scaling and squaring), path constraints are sampled inside every piece, and the
cost is the sum of the arcs' works (``1`` on ``+`` arcs, ``eta`` on the others, where
``P <= 0``). The result is a :class:`~softlanding.model.controllers.FeedbackSchedule`,
which the exact simulator replays.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ocp.structure.flows import expm_taylor
from ocp.transcriptions.solver_output import solver_output
from softlanding.errors import check_count
from softlanding.model.controllers import FeedbackSchedule, rigid_lock_gains
from softlanding.model.dynamics import mode_matrices
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.hopping_problem import apex_residuals

MODES = ("yielding", "static", "flight")
KINDS = ("coast", "lock", "capacity", "+", "-")
PIECES = 1
"""Constant pieces per ``+``/``-`` arc (their end states are what matters). One: with two,
the second shrank to no length or took the first's force at every optimum measured (13
hops, v0 from -1 to -8, eta from 0 to 0.9), and a piece of no length leaves its force
free, a flat direction that kept Ipopt from converging (it stopped at its iteration cap in
10 of the 13 first runs); with one, the same optima to 1e-11 of the energy."""
SAMPLES = 12
"""Path-constraint samples per piece (besides its ends)."""
SQUARINGS, TERMS = 10, 12
"""The matrix exponential: Taylor terms after scaling by ``2^-SQUARINGS``."""


@dataclass(frozen=True)
class Arc:
    """One arc of the hop: its ground mode, its kind and its pieces.

    Attributes
    ----------
    mode : {"yielding", "static", "flight"}
    kind : {"coast", "lock", "capacity", "+", "-"}
    durations : tuple of float
        Its pieces' lengths (one, or :data:`PIECES` on ``+``/``-`` arcs).
    forces : tuple of float
        The constant force of each piece (``+``/``-`` arcs; empty otherwise).
    """

    mode: str
    kind: str
    durations: tuple[float, ...]
    forces: tuple[float, ...] = ()

    @property
    def free(self) -> bool:
        """Its forces are unknowns (a ``+`` or ``-`` arc)."""
        return self.kind in ("+", "-")


@dataclass
class ArcGuess:
    """The arcs read off a transcription, with the states at their starts and the depth.

    Attributes
    ----------
    arcs : list of Arc
        In order, from touchdown.
    starts : list of array
        The transcription's state at each arc's start.
    depth : float
        The transcription's crater depth.
    """

    arcs: list[Arc]
    starts: list[np.ndarray]
    depth: float

    @property
    def kinds(self) -> list[str]:
        """``mode kind`` per arc."""
        return [f"{a.mode} {a.kind}" for a in self.arcs]


@dataclass
class RefinedHop:
    """The refined arcs and their schedule.

    Attributes
    ----------
    arcs : list of Arc
    schedule : FeedbackSchedule
        The control of the whole cycle (one row per piece), from touchdown.
    duration : float
        Touchdown to apex.
    depth : float
        The crater depth.
    energy : float
        The NLP's energy (the arcs' works); the exact replay's is reported.
    status : str
        Ipopt's return status.
    states : list of array
        The state at every arc's start (the NLP's).
    """

    arcs: list[Arc]
    schedule: FeedbackSchedule
    duration: float
    depth: float
    energy: float
    status: str
    states: list[np.ndarray] = field(default_factory=list)

    @property
    def kinds(self) -> list[str]:
        """``mode kind`` per arc."""
        return [f"{a.mode} {a.kind}" for a in self.arcs]


# ------------------------------------------------------------------ detection
def _phase_mode(name: str) -> str:
    return "flight" if name.startswith("flight") else (
        "static" if name.startswith("static") else "yielding")


def _runs(labels: list[tuple[str, str]]) -> list[list[Any]]:
    """Runs of equal labels: ``[label, first, last]`` (inclusive indices)."""
    out: list[list[Any]] = []
    for i, lab in enumerate(labels):
        if out and out[-1][0] == lab:
            out[-1][2] = i
        else:
            out.append([lab, i, i])
    return out


def _merge_short(runs: list[list[Any]], short: int = 2) -> list[list[Any]]:
    """Blips merged into their neighbours: a run of at most ``short`` intervals between
    two runs of one label (a grid's chattering; a spurious arc left would only shrink to
    zero length in the refinement)."""
    changed = True
    while changed:
        changed = False
        for i in range(1, len(runs) - 1):
            a, b, c = runs[i - 1], runs[i], runs[i + 1]
            if a[0] == c[0] and b[2] - b[1] < short:
                runs[i - 1:i + 2] = [[a[0], a[1], c[2]]]
                changed = True
                break
    return runs


def detect_arcs(sol: Any, robot: Robot, pieces: int = PIECES,
                tol: float = 1e-5, lock_tol: float = 1e-2) -> ArcGuess:
    """The arcs of a transcribed hop (:func:`softlanding.optimal.hopping_problem.
    hop_transcription`), as a start for :func:`refine_arcs`.

    Every interval is labelled (``capacity`` where the foot rests and the support force is
    at the crater's capacity, ``coast`` where ``u = 0``, ``lock`` where the leg's rate is 0
    while yielding, ``+`` where the power slack is positive, else ``-``); runs of labels
    are arcs, blips of a few intervals are merged into their neighbours.

    Parameters
    ----------
    sol : ocp.Solution
        The transcribed hop (phases yielding, static, flight up).
    robot : Robot
        The robot.
    pieces : int
        Constant pieces per ``+``/``-`` arc.
    tol : float
        Force and power tolerance of the labels.
    lock_tol : float
        Largest leg rate at both ends of a ``lock`` interval (a grid's constant force
        holds the leg only to about its step times the force's rate).

    Raises
    ------
    ValueError
        When the transcription is not a touchdown-to-apex hop.
    """
    names = [ph.problem.name for ph in sol.phases]
    if [_phase_mode(n) for n in names] != ["yielding", "static", "flight"]:
        raise ValueError(f"exact arcs need the one-step hop (yielding, static, flight), got "
                         f"phases {names}")
    mf = robot.foot_mass
    depth = float(-np.asarray(sol.phases[0].x)[-1, 2])
    labels: list[tuple[str, str]] = []
    rows: list[tuple[float, float, np.ndarray]] = []  # (h, u, state at the start)
    for ph in sol.phases:
        mode = _phase_mode(ph.problem.name)
        x, u = np.asarray(ph.x, float), np.asarray(ph.u, float)
        h = float(ph.T - ph.t0) / ph.N
        for k in range(ph.N):
            uk, pk = u[k, 0], u[k, 1]
            vl = (x[k, 1] - x[k, 3], x[k + 1, 1] - x[k + 1, 3])
            resting = mode == "static" or max(abs(x[k, 3]), abs(x[k + 1, 3])) < 1e-6
            if mode != "flight" and resting and abs(uk + mf - depth) < tol * 10 and \
                    pk <= tol:
                lab = ("static", "capacity")
            elif abs(uk) < tol:
                lab = (mode, "coast")
            elif mode == "yielding" and max(map(abs, vl)) < lock_tol:
                lab = (mode, "lock")
            else:
                lab = (mode, "+" if pk > tol else "-")
            labels.append(lab)
            rows.append((h, float(uk), x[k, :4].copy()))
    arcs, starts = [], []
    for (mode, kind), i, j in _merge_short(_runs(labels)):
        hs = np.array([r[0] for r in rows[i:j + 1]])
        starts.append(rows[i][2])
        if kind in ("+", "-"):
            us = np.array([r[1] for r in rows[i:j + 1]])
            chunks = [c for c in np.array_split(np.arange(len(hs)), pieces) if len(c)]
            durs = tuple(float(hs[c].sum()) for c in chunks)
            forces = tuple(float(np.average(us[c], weights=hs[c])) for c in chunks)
            arcs.append(Arc(mode, kind, durs, forces))
        else:
            arcs.append(Arc(mode, kind, (float(hs.sum()),)))
    return ArcGuess(arcs, starts, depth)


# ---------------------------------------------------------------- the NLP
@lru_cache(maxsize=1)
def _expm() -> ca.Function:
    """``exp(M)`` of a 5x5 matrix: :func:`ocp.structure.flows.expm_taylor` (degree
    :data:`TERMS`) after scaling by ``2^-SQUARINGS``, then squaring (the piece's length is
    an unknown: its norm is not known when the expression is built)."""
    M = ca.SX.sym("M", 5, 5)
    E = expm_taylor(M / 2.0 ** SQUARINGS, TERMS)
    for _ in range(SQUARINGS):
        E = ca.mtimes(E, E)
    return ca.Function("expm5", [M], [E])


def _rows(robot: Robot) -> dict[str, np.ndarray]:
    """Feedback rows of the law kinds that depend only on the state."""
    mats = mode_matrices(robot.r_m)
    lock = rigid_lock_gains(mats)
    # static capacity: support Fz.z + Fu u = hold (-x_f)
    cap = -np.asarray(mats["Fz"], float).copy()
    cap[2] -= float(mats["hold"])
    cap /= float(mats["Fu"])
    return {"lock yielding": lock[0], "lock static": lock[1], "lock flight": lock[2],
            "capacity": cap}


def _law(arc: Arc, force: Any, rows: dict[str, np.ndarray]) -> Any:
    """The feedback row of one piece of ``arc`` (``force``: that piece's unknown force)."""
    if arc.kind == "coast":
        return ca.DM.zeros(1, 5)
    if arc.kind == "lock":
        return ca.DM(rows[f"lock {arc.mode}"]).T
    if arc.kind == "capacity":
        return ca.DM(rows["capacity"]).T
    return ca.horzcat(0, 0, 0, 0, force)


class _HopNLP:
    """The refinement NLP under construction: the robot's matrices, the unknowns and the
    cost, built arc by arc (:meth:`add_arc`) in the order Ipopt sees them."""

    def __init__(self, guess: ArcGuess, robot: Robot, samples: int) -> None:
        self.mats = mats = mode_matrices(robot.r_m)
        self.Fz, self.Fu = ca.DM(mats["Fz"]).T, float(mats["Fu"])
        self.EQ, self.Ec = ca.DM(mats["EQ"]), ca.DM(mats["Ec"]).T
        self.Wg, self.hold = float(mats["Wg"]), float(mats["hold"])
        self.rows = _rows(robot)
        self.expm = _expm()
        self.u_max, self.s = float(robot.u_max), float(robot.s)  # type: ignore[arg-type]
        self.samples = samples
        self.opti = opti = ca.Opti()
        self.d = opti.variable()
        opti.set_initial(self.d, guess.depth)
        opti.subject_to(self.d >= 0)
        self.zs = []
        for x0 in guess.starts:
            z = opti.variable(4)
            opti.set_initial(z, x0)
            self.zs.append(z)
        self.cost: Any = 0
        self.taus: list[list[Any]] = []
        self.forces: list[list[Any]] = []

    def energy(self, z: Any) -> Any:
        """The robot's mechanical energy at the augmented state ``z``."""
        return 0.5 * ca.mtimes(z.T, ca.mtimes(self.EQ, z)) + ca.mtimes(self.Ec, z)

    def mode_change(self, prev_mode: str, mode: str, z: Any) -> None:
        """The conditions where the ground mode changes from ``prev_mode`` to ``mode``."""
        if mode == prev_mode:
            return
        if (prev_mode, mode) == ("yielding", "static"):
            self.opti.subject_to(z[3] == 0)  # the foot stops
            self.opti.subject_to(self.d == -z[2])
        elif (prev_mode, mode) != ("static", "flight"):
            raise ValueError(f"exact arcs: no {prev_mode} -> {mode} transition")

    def path(self, arc: Arc, K: Any, j: int, zj: Any) -> None:
        """The path constraints at the sample ``zj`` (the ``j``-th of its piece)."""
        opti = self.opti
        u = ca.mtimes(K, zj)
        leg = zj[0] - zj[2]
        opti.subject_to(opti.bounded(0, leg, self.s))
        if arc.kind in ("lock", "capacity"):  # (free forces have bounds)
            opti.subject_to(opti.bounded(-self.u_max, u, self.u_max))
        power = u * (zj[1] - zj[3])
        if arc.kind == "+":
            opti.subject_to(power >= 0)
        elif arc.kind in ("-", "capacity"):
            opti.subject_to(power <= 0)
        if arc.mode == "yielding":
            opti.subject_to(zj[3] <= 0)
        elif arc.mode == "static":
            sup = ca.mtimes(self.Fz, zj) + self.Fu * u
            opti.subject_to(sup >= 0)
            opti.subject_to(sup <= self.hold * self.d)
        elif j > 0:
            opti.subject_to(zj[2] >= -self.d)  # above the crater bottom

    def piece(self, arc: Arc, k: int, dur: float, z: Any, lift_off: bool
              ) -> tuple[Any, Any, Any]:
        """The ``k``-th piece of ``arc`` from ``z``: its duration, its force (or None) and
        its end state, flowed exactly and sampled."""
        opti = self.opti
        tau = opti.variable()
        opti.set_initial(tau, max(dur, 1e-6))
        opti.subject_to(tau >= 0)
        f = None
        if arc.free:
            f = opti.variable()
            opti.set_initial(f, arc.forces[k])
            opti.subject_to(opti.bounded(-self.u_max, f, self.u_max))
        K = _law(arc, f, self.rows)
        m = MODES.index(arc.mode)
        M = ca.DM(self.mats["A"][m]) + ca.mtimes(ca.DM(self.mats["B"][m]), K)
        n = self.samples + 1
        # one exponential per piece, its powers at the samples (exp(M tau j/n) =
        # exp(M tau/n)^j): a 13th of the expression Ipopt's derivatives are built from
        E = self.expm(M * (tau / n))
        pts = [z]
        for _ in range(n):
            pts.append(ca.mtimes(E, pts[-1]))
        for j, zj in enumerate(pts):
            self.path(arc, K, j, zj)
        if lift_off and k == 0:
            u0 = ca.mtimes(K, z)  # lift-off: the ground would have to pull
            opti.subject_to(ca.mtimes(self.Fz, z) + self.Fu * u0 <= 0)
        return tau, f, pts[-1]

    def add_arc(self, i: int, arc: Arc, prev_mode: str, z_end: Any, eta: float) -> Any:
        """Arc ``i`` from the previous arc's end ``z_end``; returns its end state."""
        z = ca.vertcat(self.zs[i], 1)
        if i:
            self.opti.subject_to(self.zs[i] == z_end[:4])
        self.mode_change(prev_mode, arc.mode, z)
        if arc.kind == "lock":
            self.opti.subject_to(z[1] - z[3] == 0)
        t_arc, f_arc = [], []
        z_a = z
        lift_off = arc.mode == "flight" and prev_mode == "static"
        for k, dur in enumerate(arc.durations):
            tau, f, z = self.piece(arc, k, dur, z, lift_off)
            t_arc.append(tau)
            f_arc.append(f)
        work = self.energy(z) - self.energy(z_a)
        if arc.mode == "yielding":
            work = work + self.Wg * (z[2] ** 2 - z_a[2] ** 2)
        if arc.kind == "+":
            self.cost = self.cost + work
        elif arc.kind in ("-", "capacity") and eta:
            self.cost = self.cost + eta * work
        self.taus.append(t_arc)
        self.forces.append(f_arc)
        return z


SETTINGS: tuple[dict[str, Any], ...] = (
    {"bound_push": 1e-8, "bound_frac": 1e-8, "mu_init": 1e-6}, {},
    {"nlp_scaling_method": "none"})
"""Ipopt's settings for :func:`refine_arcs`, to be tried in this order (``setting``). The
first keeps the start (the finest grid's optimum, near the exact one, which Ipopt's default
push off the bounds, 1e-2, and barrier, 0.1, leave); then Ipopt's defaults; then without
scaling. The NLP is not convex and where Ipopt stops depends on them: on 15 hops (v0 from
-1 to -8, eta from 0 to 0.9) each alone missed the lowest energy the three found in 1 to 3
(it stopped short, or at a local optimum up to 5 % above)."""

RESTART = {"warm_start_init_point": "yes", "mu_init": 1e-11, "warm_start_bound_push": 1e-12,
           "warm_start_bound_frac": 1e-12, "warm_start_mult_bound_push": 1e-12,
           "warm_start_slack_bound_push": 1e-12, "warm_start_slack_bound_frac": 1e-12}
"""Ipopt's options for the one restart of :func:`_solve`: from the last iterate, primal and
dual, at a barrier parameter of the tolerance's order."""


def _solve(opti: ca.Opti, ipopt: dict | None) -> tuple[Any, str]:
    """Ipopt on ``opti``: the values (the last iterate if it stopped short) and its
    status.

    Where Ipopt runs out of iterations it is restarted once from its last iterate, primal
    and dual (:data:`RESTART`), and the restart's status is returned. The NLP is
    degenerate (the control on arcs of one-signed power is not unique: a flat valley), and
    Ipopt's adaptive barrier can reach the optimum and then wander along the valley short
    of the tolerance, depending on the last bits of its start: at v0 = -3 a grid optimum
    2.7e-12 away from another stopped after 500 iterations where that one converged in
    271, both at 9.56429510071 (the stopped run met the constraints to 7e-12 and the
    dual conditions to 9e-10 at its 200th iteration); the restart finished in one
    iteration.
    """
    # (a tighter constr_viol_tol sends Ipopt wandering in the flat valley: the replay, not
    # the NLP, is the figure reported, and the two are compared)
    opts = {"tol": 1e-12, "acceptable_tol": 1e-10, "max_iter": 500, "print_level": 0,
            "mu_strategy": "adaptive", **(ipopt or {})}
    val, status = _ipopt(opti, opts)
    if status == "Maximum_Iterations_Exceeded":
        opti.set_initial(opti.x, val(opti.x))
        opti.set_initial(opti.lam_g, val(opti.lam_g))
        val, status = _ipopt(opti, {**opts, **RESTART})
    return val, status


def _ipopt(opti: ca.Opti, opts: dict) -> tuple[Any, str]:
    """One Ipopt run on ``opti`` with ``opts``: its values and status."""
    # the forces' limits as simple bounds, which Ipopt honours exactly on return (a
    # general constraint is met only to 1e-8 of its size: clipped back, the apex moves)
    opti.solver("ipopt", {"print_time": False, "expand": True,
                          "detect_simple_bounds": True}, opts)
    try:
        with solver_output():  # CasADi's messages: logged, not printed
            val = opti.solve().value
    except RuntimeError:  # Ipopt stopped short: its status says how (else a CasADi error)
        if "return_status" not in opti.stats():
            raise
        val = opti.debug.value
    # Ipopt's own word: opti.solve() also returns on Solved_To_Acceptable_Level, which the
    # caller does not take for an optimum
    return val, str(opti.stats()["return_status"])


def _refined(guess: ArcGuess, nlp: _HopNLP, val: Any, status: str) -> RefinedHop:
    """The solved NLP's arcs and their feedback schedule (pieces of no length left out)."""
    durs: list[float] = []
    gains: list[list[float]] = []
    out_arcs: list[Arc] = []
    for arc, t_arc, f_arc in zip(guess.arcs, nlp.taus, nlp.forces, strict=True):
        d_vals = tuple(max(float(val(t)), 0.0) for t in t_arc)
        f_vals = tuple(float(np.clip(val(f), -nlp.u_max, nlp.u_max)) for f in f_arc
                       if f is not None)
        out_arcs.append(Arc(arc.mode, arc.kind, d_vals, f_vals))
        for k, dur in enumerate(d_vals):
            K = _law(arc, f_vals[k] if arc.free else None, nlp.rows)
            durs.append(dur)
            gains.append([float(v) for v in np.asarray(ca.DM(K)).ravel()])
    keep = [k for k, t in enumerate(durs) if t > 0]
    durs = [durs[k] for k in keep]
    gains = [gains[k] for k in keep]
    sched = FeedbackSchedule.from_arcs(durs, gains + [[0.0] * 5])
    cost = nlp.cost
    return RefinedHop(out_arcs, sched, float(np.sum(durs)), float(val(nlp.d)),
                      float(val(cost)) if not isinstance(cost, int) else 0.0, status,
                      [np.asarray(val(z), float).ravel() for z in nlp.zs])


def refine_arcs(guess: ArcGuess, robot: Robot, impact: Impact, eta: float,
                samples: int = SAMPLES, ipopt: dict | None = None, setting: int = 0
                ) -> RefinedHop:
    """The hop on the arcs of ``guess``, their pieces' durations and forces optimised,
    every piece flowed exactly.

    Parameters
    ----------
    guess : ArcGuess
        The arcs and a start (:func:`detect_arcs`).
    robot, impact, eta
        The robot, the touchdown and the regenerative efficiency.
    samples : int
        Path-constraint samples inside every piece.
    ipopt : dict, optional
        Extra Ipopt options.
    setting : int
        Which of :data:`SETTINGS` Ipopt runs with (the NLP is not convex: a caller tries
        the next where one fails).

    Raises
    ------
    ParameterError
        A ``setting`` that is not an index of :data:`SETTINGS`.
    ValueError
        When the arcs' ground modes do not run yielding, static, flight.
    """
    setting = check_count("setting", setting, 0, len(SETTINGS) - 1)
    nlp = _HopNLP(guess, robot, samples)
    opti = nlp.opti
    x_td = impact.initial_state(robot.replace(l0=None))
    opti.subject_to(nlp.zs[0] == ca.DM(x_td[:4]))
    prev_mode = "yielding"
    z_end: Any = None
    for i, arc in enumerate(guess.arcs):
        z_end = nlp.add_arc(i, arc, prev_mode, z_end, eta)
        prev_mode = arc.mode
    if prev_mode != "flight":
        raise ValueError("exact arcs: the cycle does not end in flight")
    for res in apex_residuals(z_end, robot.body_mass, robot.foot_mass, impact.energy, nlp.s):
        opti.subject_to(res == 0)
    opti.minimize(nlp.cost)
    val, status = _solve(opti, {**SETTINGS[setting], **(ipopt or {})})
    return _refined(guess, nlp, val, status)


__all__ = ["KINDS", "MODES", "PIECES", "SETTINGS", "Arc", "ArcGuess", "RefinedHop",
           "detect_arcs", "refine_arcs"]
