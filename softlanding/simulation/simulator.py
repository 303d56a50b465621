"""Event-driven simulation of a landing on yielding ground: exact, or integrated.

The ground has three modes (yielding, static, flight) and crater memory: once the
foot has dug to depth ``d`` the ground holds any support force up to ``f(d, 0)``
(``d`` for the paper's spring) without yielding, and a foot that lifts off lands
again at the crater bottom. On the paper's spring (any affine ground law) every
mode is affine in the state, so each is propagated with the matrix exponential and
each event (foot stops, support force exceeded, lift-off, re-landing, saturation
on/off, schedule switches) is located as a root of the exact solution; see
:mod:`._kernel`.

On a non-affine ground (inertial drag, added mass, a user's law) only the yielding
mode is non-affine: its segments are integrated by an adaptive Dormand-Prince
8(5,3) method (relative and absolute tolerance ``rtol``, default 1e-12) with events
located by Newton on the integrator's own steps, while the static and flight modes,
the rest proof and their events stay exact (:mod:`softlanding.simulation.kernel.nonaffine`).
The energy ledger then also has the drag loss and the grains' loss.

Example
-------
>>> from softlanding import Impact, Impedance, Robot, simulate
>>> res = simulate(Robot(r_m=5, s=20), Impact(-1), Impedance(0.2, 0.18))
>>> res.steps
2
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ocp.definition.trajectory import Trajectory
from softlanding.errors import ParameterError, RestNotProvenError, check, check_count, expect
from softlanding.model.controllers import (
    Controller,
    ForceSchedule,
    Impedance,
    Rigid,
    impedance_gains,
)
from softlanding.model.dynamics import STATE_NAMES, mode_matrices
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import Impact, Robot
from softlanding.simulation import kernel as K
from softlanding.simulation.groundcode import kernel_law, needs_integration, raise_law_errors
from softlanding.util.jsonable import json_safe

O_EDRAG, O_EGRAIN = K.N_OUT, K.N_OUT + 1  # the integrated path's extra columns
N_OUT_NL = K.N_OUT + 2

MODE_NAMES = ("yielding", "static", "flight")
STATUS_NAMES = K.STATUS_NAMES
DEFAULT_T_MAX = 1.0e4
DEFAULT_MAX_SEGMENTS = 500


# ---------------------------------------------------------------------- results
@dataclass
class EnergyLedger:
    """Energies in units of ``m_t g x_s``, potential energy measured from the impact pose.

    ``E0 - ET = ground + drag + grains + actuator`` where ``ground`` is the work done
    on the plastic ground (``int f(d, 0) dd``: ``x_f(T)^2 / 2`` for the paper's spring),
    ``drag`` the work of the bed's rate-dependent force (``int c_d |v_f|^3 dtau`` for
    inertial drag), ``grains`` the loss to the accreted grains (their inelastic
    accretion, ``int m_a'(d) |v_f|^3 / 2 dtau``, and the collisions of a foot landing
    again on them; both 0 on the paper's spring), and
    ``actuator = -int_0^T u (v_b - v_f) dtau`` is the energy taken out of the
    robot by the actuator (the paper writes its magnitude; with ``u > 0``
    pushing the masses apart the balance needs the minus sign). ``E0 = v0^2 / 2``
    is the impact kinetic energy, so ``cot = (E0 - ET) / E0`` is 1 for a
    perfectly inelastic impact and exceeds 1 by the work of gravity during the
    sinking; ``cot_lossless`` counts the ground loss only (actuator rendering
    without loss). Both are NaN at ``v0 = 0``.

    Parameters
    ----------
    E0, ET : float
        Mechanical energy at impact and at the landing's end ``T``, the foot's stop (the
        paper's horizon of the cost of transport; the body may still be moving then).
    ground, actuator : float
        Work done on the ground and taken out by the actuator.
    drag, grains : float
        Drag loss and grain loss (non-affine grounds; 0 otherwise).
    integrated : bool
        The yielding segments were integrated (the ledger then lists drag and grains).
    """

    E0: float
    ET: float
    ground: float
    actuator: float
    drag: float = 0.0
    grains: float = 0.0
    integrated: bool = False

    @property
    def cot(self) -> float:
        """``(E0 - ET) / E0`` (NaN at ``v0 = 0``)."""
        return (self.E0 - self.ET) / self.E0 if self.E0 > 0 else math.nan

    @property
    def cot_lossless(self) -> float:
        """Losses to the terrain over ``E0``: ``(ground + drag + grains) / E0`` (NaN at
        ``v0 = 0``)."""
        return (self.ground + self.drag + self.grains) / self.E0 if self.E0 > 0 else math.nan

    @property
    def residual(self) -> float:
        """``(E0 - ET) - (ground + drag + grains + actuator)``: zero up to rounding (and the
        integrator's tolerance on a non-affine ground)."""
        return (self.E0 - self.ET) - (self.ground + self.drag + self.grains + self.actuator)

    def to_dict(self) -> dict[str, float]:
        """Every figure, the two CoTs included."""
        d = {"E0": self.E0, "ET": self.ET, "ground": self.ground, "actuator": self.actuator}
        if self.integrated:
            d.update(drag=self.drag, grains=self.grains)
        d.update(cot=self.cot, cot_lossless=self.cot_lossless)
        return d


def stroke(traj: Trajectory) -> np.ndarray:
    """Leg length ``x_b - x_f`` along a trajectory of the landing model.

    Parameters
    ----------
    traj : Trajectory
        With states ``x_b`` and ``x_f``.
    """
    return traj.state("x_b") - traj.state("x_f")


@dataclass
class LandingResult:
    """Outcome of one simulated landing (dimensionless units).

    Attributes
    ----------
    depth : float
        Final penetration depth ``-x_f`` at rest (positive); without a proven rest, the
        depth reached, or the limit of a proven creep or of undamped hops shrinking toward
        the lift-off threshold (see ``status`` and :mod:`softlanding.simulation.kernel.hops`).
    steps : int
        Number of intrusion (yielding) phases (those simulated, if rest is not proven).
    feasible : bool
        Rest proven and ``0 <= x_b - x_f <= s`` throughout (to 1e-9 s): the landing is
        proven to succeed. Its two halves apart: :attr:`stroke_held`, :attr:`rest_proven`.
    u_peak : float
        ``max |u|`` over the whole run, including after the foot stops.
    stroke_min, stroke_max : float
        Exact extrema of ``x_b - x_f`` over the whole run (infinite if the
        body drifts without bound after the foot has stopped).
    t_first_stop : float
        First time the foot stops (NaN if it never does).
    T : float
        Time the foot comes to rest for good (start of the final static phase).
    status : str
        ``"rest proven"`` or why not.
    energy : EnergyLedger
    n_segments : int
        Hybrid segments simulated.
    robot, impact, controller, ground
        What was simulated.
    depth_limit : float
        The depth as t -> inf: the rest depth when the foot rests, the limit a
        never-resting creep approaches (then ``depth`` is that limit too, a supremum the
        foot never reaches), the limit of undamped hops shrinking toward the lift-off
        threshold (by energy balance; if the hops ever ended, the foot would rest at
        least this deep), NaN when unknown.
    foot_rest : bool
        The foot's rest is proven, whatever the body does (a body that passes through
        its foot is not a rest of the robot: ``status`` says so).
    """

    depth: float
    steps: int
    feasible: bool
    u_peak: float
    stroke_min: float
    stroke_max: float
    t_first_stop: float
    T: float
    status: str
    energy: EnergyLedger
    n_segments: int
    robot: Robot
    impact: Impact
    controller: Controller
    ground: Ground = LINEAR_GROUND
    depth_limit: float = math.nan
    foot_rest: bool = False
    _segments: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def segments(self) -> Mapping[str, np.ndarray]:
        """The simulated segments (the kernel's arrays by name: ``t``, the state at each
        segment's start, its mode and law), read-only: what the samplers and energy
        integrals of other modules read."""
        return MappingProxyType(self._segments)

    @property
    def stroke_held(self) -> bool:
        """``0 <= x_b - x_f <= s`` held over the run simulated (to the kernel's tolerance),
        whether or not rest was proven: ``feasible`` is this and :attr:`rest_proven`."""
        tol = K.FEAS_TOL * max(1.0, self.robot.s)
        return bool(self.stroke_min >= -tol and self.stroke_max <= self.robot.s + tol)

    @property
    def rest_proven(self) -> bool:
        """The foot's final rest is proven (no further event can happen)."""
        return self.status == STATUS_NAMES[K.REST_PROVEN]

    @property
    def depth_kind(self) -> str:
        """What ``depth`` is: ``"final"`` (the foot's rest is proven), ``"limit"`` (the
        limit of a proven creep or of shrinking undamped hops) or ``"reached"`` (where the
        simulation gave up)."""
        if self.foot_rest:
            return "final"
        return "limit" if math.isfinite(self.depth_limit) else "reached"

    def trajectory(self, t_end: float | None = None, n: int = 2000) -> Trajectory:
        """Sample the exact solution on ``n`` points of ``[0, t_end]`` plus every event time.

        The samples use the simulator's own propagator, so they are exact to rounding
        (a pinned foot has exactly zero velocity); on a non-affine ground the yielding
        segments are integrated again from their starts at the simulation's tolerance.

        Parameters
        ----------
        t_end : float, optional
            End of the samples; defaults to 1.3 T (showing the body settle after
            the foot stops), or to the end of the simulation when rest is not proven.
        n : int
            Number of evenly spaced samples (event times are added).

        Returns
        -------
        Trajectory
            States ``x_b, v_b, x_f, v_f``, control ``u`` and the ground mode of each sample.

        Raises
        ------
        RestNotProvenError
            If ``t_end`` lies beyond the simulated time of a landing whose rest is not
            proven (nothing is known there).
        """
        seg = self._segments
        ts = seg["t"]
        if len(ts) < 2:
            raise RestNotProvenError(f"nothing was simulated ({self.status})")
        if not self.rest_proven:
            if t_end is not None and t_end > ts[-1]:
                raise RestNotProvenError(
                    f"the landing was simulated up to t = {ts[-1]:.6g} without proving rest "
                    f"({self.status}); there are no samples up to {t_end:g}")
            t_end = ts[-1] if t_end is None else t_end
        elif t_end is None:
            t_end = max(1.3 * self.T, self.T + 2.0, ts[-1])
        grid = np.union1d(np.linspace(0.0, t_end, n), ts[(ts >= 0) & (ts <= t_end)])
        sampler = K.sample_segments_nl if "law" in seg else K.sample_segments
        z, u, mode = sampler(seg, grid)
        x = z[:, :4]
        return Trajectory(grid, x, u[:, None], STATE_NAMES, ("u",),
                          mode=np.array(MODE_NAMES)[mode])

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """Plain JSON-able dict (non-finite numbers become None).

        Parameters
        ----------
        trajectory : bool
            Include the sampled trajectory.
        """
        d = {
            "depth": self.depth, "steps": self.steps, "feasible": self.feasible,
            "stroke_held": self.stroke_held,
            "u_peak": self.u_peak, "stroke_min": self.stroke_min,
            "stroke_max": self.stroke_max, "t_first_stop": self.t_first_stop,
            "T": self.T, "status": self.status, "rest_proven": self.rest_proven,
            "n_segments": self.n_segments, "depth_limit": self.depth_limit,
            "depth_kind": self.depth_kind,
            "foot_rest": self.foot_rest, "energy": self.energy.to_dict(),
            "robot": self.robot.to_dict(), "impact": self.impact.to_dict(),
            "ground": self.ground.to_dict(), "controller": self.controller.to_dict(),
        }
        if trajectory:
            d["trajectory"] = self.trajectory().to_dict()
        return json_safe(d)


# ----------------------------------------------------------------------- single
@contextlib.contextmanager
def _signal_as_itself() -> Iterator[None]:
    """A signal handler's exception (Ctrl-C, SIGTERM, an alarm's) raised as a compiled landing
    returns comes out as itself, not inside numba's SystemError ("returned a result with an
    exception set"), which the CLI would call a bug."""
    try:
        yield
    except SystemError as exc:
        if exc.__cause__ is None:
            raise
        raise exc.__cause__ from None


def simulate(
    robot: Robot,
    impact: Impact | float,
    controller: Controller | None = None,
    ground: Ground = LINEAR_GROUND,
    *,
    x0: np.ndarray | None = None,
    energy: bool = True,
    t_max: float = DEFAULT_T_MAX,
    max_segments: int = DEFAULT_MAX_SEGMENTS,
    method: str = "auto",
    rtol: float = K.DEFAULT_RTOL,
) -> LandingResult:
    """Simulate one landing (exactly on an affine ground).

    Parameters
    ----------
    robot : Robot
        Mass ratio, stroke, force limit (saturates every controller) and rest length.
    impact : Impact or float
        Impact velocity (a bare number is read as ``Impact(v0)``).
    controller : Rigid, Impedance or ForceSchedule, optional
        Default: the rigid leg.
    ground : Ground
        Ground model. Affine laws are simulated exactly; others have their yielding
        segments integrated (see the module notes).
    x0 : array of 4, optional
        Initial state; defaults to the impact state ``[l0, v0, 0, v0]``.
    energy : bool
        Compute the energy ledger (exact Gramian quadrature; ~2x cost).
    t_max : float
        Give up proving rest after this time.
    max_segments : int
        Give up proving rest after this many hybrid segments.
    method : str
        ``"auto"`` (exact if the ground allows it), ``"exact"`` (refuses a non-affine
        ground) or ``"integrate"`` (the DOP853 path even for an affine ground: a check).
    rtol : float
        Relative and absolute tolerance of the integrated yielding segments.

    Returns
    -------
    LandingResult
    """
    impact = Impact.of(impact)
    expect("robot", robot, Robot)
    controller = Rigid() if controller is None else controller
    if isinstance(controller, type):
        raise ParameterError("controller", f"must be a controller, got the class "
                                           f"{controller.__name__} (make one: "
                                           f"{controller.__name__}(...))")
    if not hasattr(controller, "kernel_arrays"):  # duck-typed: variants bring their own laws
        raise ParameterError("controller", f"must be a controller (Rigid, Impedance, "
                                           f"ForceSchedule, ...), got {controller!r:.60}")
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    integrate = integrated(ground, method)
    mats = mode_matrices(robot.r_m, LINEAR_GROUND if integrate else ground)
    Kf, st, su = controller.kernel_arrays(mats, robot)
    umax = math.inf if robot.u_max is None else robot.u_max
    z0 = impact.initial_state(robot) if x0 is None else np.asarray(x0, float)
    if z0.shape != (4,) or not np.all(np.isfinite(z0)):
        raise ParameterError("x0", "must be 4 finite numbers")
    max_seg = check_count("max_segments", max_segments, 1, 10**6)
    if integrate:
        law = kernel_law(ground, robot.r_m, lock=isinstance(controller, Rigid), u_max=umax)
        with _signal_as_itself():
            out, segments = K.run_landing_nl(mats, law, Kf, umax, st, su, z0, robot.s,
                                             check("t_max", t_max), max_seg, bool(energy),
                                             check("rtol", rtol))
        raise_law_errors()  # a law evaluated in Python (no C compiler) cannot raise in the kernel
    else:
        with _signal_as_itself():
            out, segments = K.run_landing(mats, Kf, umax, st, su, z0, robot.s,
                                          check("t_max", t_max), max_seg, bool(energy))
    return LandingResult(
        depth=float(out[K.O_DEPTH]), steps=int(out[K.O_STEPS]), feasible=bool(out[K.O_FEAS]),
        u_peak=float(out[K.O_UPEAK]), stroke_min=float(out[K.O_SMIN]),
        stroke_max=float(out[K.O_SMAX]), t_first_stop=float(out[K.O_TSTOP]),
        T=float(out[K.O_T]), status=STATUS_NAMES[int(out[K.O_STATUS])],
        energy=_ledger(out, integrate),
        n_segments=int(out[K.O_NSEG]), robot=robot, impact=impact, controller=controller,
        depth_limit=float(out[K.O_DLIM]), foot_rest=bool(out[K.O_FOOT_REST]),
        ground=ground, _segments=segments)


def integrated(ground: Ground, method: str = "auto") -> bool:
    """Whether landings on ``ground`` are integrated (True) or exact (False).

    Parameters
    ----------
    ground : Ground
        The ground model.
    method : str
        ``"auto"``, ``"exact"`` or ``"integrate"``.

    Raises
    ------
    ParameterError
        An unknown method, or ``"exact"`` for a ground that has no exact path.
    """
    if method not in ("auto", "exact", "integrate"):
        raise ParameterError("method", f"must be auto, exact or integrate, got {method!r}")
    need = needs_integration(ground)
    if method == "exact" and need:
        raise ParameterError("method", f"the {ground.name} ground is not affine (or its "
                                       "crater holds other than f(d, 0) = K d): no exact path")
    return need or method == "integrate"


def _ledger(out: np.ndarray, integrate: bool) -> EnergyLedger:
    if not integrate:
        return EnergyLedger(float(out[K.O_E0]), float(out[K.O_ET]), float(out[K.O_EGND]),
                            float(out[K.O_EACT]))
    return EnergyLedger(float(out[K.O_E0]), float(out[K.O_ET]), float(out[K.O_EGND]),
                        float(out[K.O_EACT]), float(out[O_EDRAG]), float(out[O_EGRAIN]),
                        integrated=True)


# ------------------------------------------------------------------------ batch
BYTES_PER_LANDING = 8 * (K.N_OUT + 15 + 4 + 3) + 64
"""Memory a batched landing takes: its output row, feedback, start state, inputs, labels."""
SECONDS_PER_LANDING = 60e-6
"""Typical CPU time per landing (paper grid, measured), for the estimate in messages."""


def available_memory() -> int:
    """Bytes the kernel can give a new allocation: free memory plus reclaimable page cache.

    ``MemAvailable`` of ``/proc/meminfo`` where there is one; bare free pages would refuse a
    batch on a machine whose memory is mostly cache (a busy CI runner), falsely.
    """
    import os

    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return 8 * 2**30


def check_batch_size(n: int, option: str = "grid") -> None:
    """Refuse a batch that would not fit in memory, before anything is allocated.

    Parameters
    ----------
    n : int
        Number of landings.
    option : str
        The user's option that set the size (named in the message).

    Raises
    ------
    ParameterError
        With the estimated memory and time.
    """
    need = n * BYTES_PER_LANDING
    avail = available_memory()
    if need > 0.5 * avail:
        raise ParameterError(option, f"{n:,} landings need about {need / 2**30:.1f} GiB of "
                                     f"memory ({avail / 2**30:.1f} GiB available) and about "
                                     f"{n * SECONDS_PER_LANDING / 3600:.1f} CPU hours; "
                                     "ask for fewer")


_FIELD_COL = {
    "depth": K.O_DEPTH, "steps": K.O_STEPS, "t_first_stop": K.O_TSTOP, "T": K.O_T,
    "u_peak": K.O_UPEAK, "stroke_min": K.O_SMIN, "stroke_max": K.O_SMAX, "feasible": K.O_FEAS,
    "status": K.O_STATUS, "E0": K.O_E0, "ET": K.O_ET, "ground": K.O_EGND, "actuator": K.O_EACT,
    "depth_limit": K.O_DLIM, "foot_rest": K.O_FOOT_REST,
}
BATCH_FIELDS = tuple(_FIELD_COL)


@dataclass
class BatchResult:
    """Arrays of per-landing figures, all of the broadcast input shape.

    Fields are those of :data:`BATCH_FIELDS` (read as attributes); ``feasible``
    is boolean, ``steps`` and ``status`` are integers (0 = rest proven).
    ``cot`` and ``cot_lossless`` are derived (NaN where energy was not computed).

    Parameters
    ----------
    robot : Robot
    ground : Ground
    inputs : dict
        ``v0``, ``k_p``, ``k_d`` broadcast to the output shape.
    data : dict
        One array per field.
    """

    robot: Robot
    ground: Ground
    inputs: dict[str, np.ndarray]
    data: dict[str, np.ndarray]

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["data"][name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def cot(self) -> np.ndarray:
        """``(E0 - ET) / E0`` per landing."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.data["E0"] > 0,
                            (self.data["E0"] - self.data["ET"]) / self.data["E0"], np.nan)

    @property
    def cot_lossless(self) -> np.ndarray:
        """Losses to the terrain over ``E0`` (``(ground + drag + grains) / E0``) per landing."""
        with np.errstate(divide="ignore", invalid="ignore"):
            loss = self.data["ground"] + self.data.get("drag", 0.0) + self.data.get("grains", 0.0)
            return np.where(self.data["E0"] > 0, loss / self.data["E0"], np.nan)

    @property
    def stroke_margin(self) -> np.ndarray:
        """Distance to the nearer stroke limit (negative when a limit is crossed)."""
        return np.minimum(self.data["stroke_min"], self.robot.s - self.data["stroke_max"])

    @property
    def strictly_feasible(self) -> np.ndarray:
        """Rest proven and the stroke limits kept exactly (``feasible`` allows 1e-9 s of
        rounding at a limit; an optimiser would exploit that)."""
        return (self.data["status"] == K.REST_PROVEN) & (self.stroke_margin >= 0.0)


def _broadcast(v0, k_p, k_d) -> tuple[np.ndarray, ...]:
    try:
        return tuple(np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (v0, k_p, k_d))))
    except ValueError:
        shapes = ", ".join(f"{n} {np.shape(a)}" for n, a in (("v0", v0), ("k_p", k_p),
                                                              ("k_d", k_d)))
        raise ParameterError("k_p", f"v0, k_p and k_d must broadcast together: {shapes}") \
            from None


def simulate_batch(
    robot: Robot,
    v0,
    k_p,
    k_d,
    ground: Ground = LINEAR_GROUND,
    *,
    energy: bool = False,
    progress: bool | None = None,
    chunk_size: int = 8192,
    t_max: float = DEFAULT_T_MAX,
    max_segments: int = DEFAULT_MAX_SEGMENTS,
    method: str = "auto",
    rtol: float = K.DEFAULT_RTOL,
) -> BatchResult:
    """Simulate many impedance-controlled landings of one robot in parallel (all cores).

    Parameters
    ----------
    robot : Robot
        The robot (its force limit saturates every landing; its rest length is
        the impact leg length and the springs' rest length).
    v0, k_p, k_d : array_like
        Impact velocities and gains, broadcast against each other.
    ground : Ground
        Ground model (a non-affine one is integrated, see :func:`simulate`; the result
        then also has the fields ``drag`` and ``grains``).
    energy : bool
        Also compute the energy ledger.
    progress : bool or None
        Show a tqdm progress bar; None shows one for more than 50,000 landings.
    chunk_size : int
        Landings per parallel call (the progress bar's granularity).
    t_max : float
        Give up proving rest after this time.
    max_segments : int
        Give up proving rest after this many hybrid segments.
    method : str
        As :func:`simulate`.
    rtol : float
        Tolerance of the integrated yielding segments.

    Returns
    -------
    BatchResult
    """
    expect("robot", robot, Robot)
    expect("ground", ground, Ground, "ground model (softlanding.model.ground)")
    arrays = _broadcast(v0, k_p, k_d)
    shape = arrays[0].shape
    v, kp, kd = (check(name, np.array(a.ravel(), dtype=float))
                 for name, a in zip(("v0", "k_p", "k_d"), arrays, strict=True))
    n = kp.size
    check_batch_size(n)
    integrate = integrated(ground, method)
    mats = mode_matrices(robot.r_m, LINEAR_GROUND if integrate else ground)
    law = kernel_law(ground, robot.r_m) if integrate else None
    l0 = robot.rest_length
    Kf = np.empty((n, 3, 5))
    Kf[:] = impedance_gains(kp, kd, np.full(n, l0)).T[:, None, :]  # the one impedance law
    x0 = np.stack([np.full(n, l0), v, np.zeros(n), v], axis=1)
    um = np.full(n, math.inf if robot.u_max is None else robot.u_max)
    ss = np.full(n, robot.s)
    out = np.zeros((n, N_OUT_NL if integrate else K.N_OUT))
    ridx = np.zeros(n, dtype=np.int64)
    from softlanding.util.progress import progress_bar

    with progress_bar(n if progress or (progress is None and n > 50_000) else 0,
                      "simulating", "landing") as bar:
        for a in range(0, n, chunk_size):
            b = min(n, a + chunk_size)
            if law is not None:
                K.run_batch_nl([mats], ridx[a:b], law, Kf[a:b], um[a:b], x0[a:b], ss[a:b],
                               check("t_max", t_max), max_segments, energy, out[a:b],
                               check("rtol", rtol))
                raise_law_errors()
            else:
                K.run_batch([mats], ridx[a:b], Kf[a:b], um[a:b], x0[a:b], ss[a:b],
                            check("t_max", t_max), max_segments, energy, out[a:b])
            bar.update(b - a)
    inputs = {"v0": arrays[0], "k_p": arrays[1], "k_d": arrays[2]}
    return BatchResult(robot, ground, inputs, _batch_data(out, shape, integrate))


def _batch_data(out: np.ndarray, shape: tuple, integrate: bool) -> dict[str, np.ndarray]:
    """The output rows as one array per field (drag and grains on an integrated ground)."""
    data = {}
    cols = dict(_FIELD_COL, drag=O_EDRAG, grains=O_EGRAIN) if integrate else _FIELD_COL
    for name, col in cols.items():
        v_ = out[:, col].reshape(shape)
        if name in ("feasible", "foot_rest"):
            v_ = v_.astype(bool)
        elif name in ("steps", "status"):
            v_ = v_.astype(np.int64)
        data[name] = v_
    return data


def joined_trajectory(pieces: Sequence[tuple[LandingResult, float, float]],
                      n: int = 1500) -> Trajectory:
    """One trajectory from simulations that continue each other: ``(result, a, b)`` covers
    times ``[a, b]`` of the whole with the result's own times ``[0, b - a]``.

    Parameters
    ----------
    pieces : sequence of (LandingResult, float, float)
        The simulations and the spans they cover, in order.
    n : int
        About how many samples in all (at least 20 a piece).
    """
    total = max(sum(b - a for _, a, b in pieces), 1e-300)
    parts = [(r.trajectory(t_end=b - a, n=max(20, int(n * (b - a) / total))), a)
             for r, a, b in pieces]
    return Trajectory(np.concatenate([tr.t + a for tr, a in parts]),
                      np.vstack([tr.x for tr, _ in parts]),
                      np.vstack([tr.u for tr, _ in parts]), parts[0][0].state_names,
                      parts[0][0].control_names,
                      mode=np.concatenate([tr.mode for tr, _ in parts]))


__all__ = ["BATCH_FIELDS", "BatchResult", "EnergyLedger", "ForceSchedule", "Impedance",
           "LandingResult", "MODE_NAMES", "Rigid", "STATUS_NAMES", "joined_trajectory",
           "simulate", "simulate_batch", "stroke"]
