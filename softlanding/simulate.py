"""Exact event-driven simulation of a landing on yielding ground.

The ground is the paper's one-way plastic spring with three modes (yielding,
static, flight) and crater memory: once the foot has dug to depth ``d`` the
ground holds any support force up to ``d`` without yielding, and a foot that
lifts off lands again at the crater bottom. Every mode is affine in the state,
so each is propagated with the matrix exponential and each event (foot stops,
support force exceeded, lift-off, re-landing, saturation on/off, schedule
switches) is located as a root of the exact solution; see :mod:`._kernel`.

Example
-------
>>> from softlanding import DimensionlessParams, Impedance, simulate
>>> res = simulate(DimensionlessParams(r_m=5, s=20, v0=-1), Impedance(0.2, 0.18))
>>> res.steps
2
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import scipy.linalg

from . import _kernel as K
from ._jsonutil import json_safe
from .dynamics import VB, VF, mode_matrices
from .errors import (
    ParameterError,
    check_finite,
    check_impact_velocity,
    check_nonnegative,
    check_positive,
)
from .scaling import DimensionlessParams, PhysicalParams

MODE_NAMES = ("yielding", "static", "flight")
STATUS_NAMES = K.STATUS_NAMES
DEFAULT_T_MAX = 1.0e4
DEFAULT_MAX_SEGMENTS = 500


# --------------------------------------------------------------------- policies
@dataclass(frozen=True)
class Rigid:
    """Body and foot locked together: the actuator supplies whatever force keeps
    the stroke constant (derived per ground mode from the dynamics)."""

    def describe(self) -> str:
        return "rigid leg"


@dataclass(frozen=True)
class Impedance:
    """Rendered spring-damper ``u = -k_p (x_b - x_f - l0) - k_d (v_b - v_f)``.

    Parameters
    ----------
    k_p, k_d : float
        Dimensionless stiffness and damping (>= 0).
    u_max : float or None
        Saturate the force at ``+-u_max`` (None: unlimited).
    l0 : float or None
        Rest length; None means the paper's ``s / 2``.
    """

    k_p: float
    k_d: float
    u_max: float | None = None
    l0: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_p", check_nonnegative("k_p", self.k_p))
        object.__setattr__(self, "k_d", check_nonnegative("k_d", self.k_d))
        if self.u_max is not None:
            object.__setattr__(self, "u_max", check_positive("u_max", self.u_max))
        if self.l0 is not None:
            object.__setattr__(self, "l0", check_finite("l0", self.l0))

    def describe(self) -> str:
        sat = "" if self.u_max is None else f", |u| <= {self.u_max:g}"
        return f"impedance k_p={self.k_p:g}, k_d={self.k_d:g}{sat}"


@dataclass(frozen=True)
class ForceSchedule:
    """Open-loop piecewise-constant force: ``u = values[i]`` on ``[times[i-1], times[i])``.

    ``times`` are the switching instants (strictly increasing, > 0); ``values``
    has one more entry than ``times`` and its last value is held forever.
    """

    times: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        t = tuple(check_finite("times", v) for v in self.times)
        u = tuple(check_finite("values", v) for v in self.values)
        if len(u) != len(t) + 1:
            raise ParameterError("values", "needs exactly one more entry than times")
        if any(b <= a for a, b in zip((0.0,) + t, t, strict=False)):
            raise ParameterError("times", "must be strictly increasing and > 0")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", u)

    @classmethod
    def from_arcs(cls, durations, values) -> ForceSchedule:
        """Schedule from arc durations and the force on each arc (and after)."""
        d = [check_positive("durations", v) for v in durations]
        return cls(tuple(np.cumsum(d)), tuple(values))

    def describe(self) -> str:
        return f"open-loop schedule with {len(self.times)} switches"


Policy = Rigid | Impedance | ForceSchedule


def impedance_gain_vector(k_p: float, k_d: float, l0: float) -> np.ndarray:
    """``u = K . [x_b, v_b, x_f, v_f, 1]`` for the impedance law."""
    return np.array([-k_p, -k_d, k_p, k_d, k_p * l0])


def rigid_lock_gains(mats: dict[str, np.ndarray]) -> np.ndarray:
    """Per-mode feedback that keeps ``v_b' = v_f'`` (the locked leg), from the mode matrices."""
    R = np.zeros(5)
    R[VB], R[VF] = 1.0, -1.0
    Kf = np.empty((3, 5))
    for m in range(3):
        Kf[m] = -(R @ mats["A"][m]) / (R @ mats["B"][m])
    return Kf


# ---------------------------------------------------------------------- results
@dataclass
class EnergyLedger:
    """Energies in units of ``m_t g x_s``, potential energy measured from the impact pose.

    ``E0 - ET = ground + actuator`` where ``ground = x_f(T)^2 / 2`` is the work
    done on the plastic ground and ``actuator = -int_0^T u (v_b - v_f) dtau`` is the
    energy taken out of the robot by the actuator (the paper writes its
    magnitude; with ``u > 0`` pushing the masses apart the balance needs the
    minus sign). ``E0 = v0^2 / 2`` is the impact kinetic energy, so
    ``cot = (E0 - ET) / E0`` is 1 for a perfectly inelastic impact and exceeds
    1 by the work of gravity during the sinking; ``cot_lossless`` counts the
    ground loss only (actuator rendering without loss). Both are NaN at ``v0 = 0``.
    """

    E0: float
    ET: float
    ground: float
    actuator: float

    @property
    def cot(self) -> float:
        return (self.E0 - self.ET) / self.E0 if self.E0 > 0 else math.nan

    @property
    def cot_lossless(self) -> float:
        return self.ground / self.E0 if self.E0 > 0 else math.nan

    @property
    def residual(self) -> float:
        """``(E0 - ET) - (ground + actuator)``: zero up to rounding."""
        return (self.E0 - self.ET) - (self.ground + self.actuator)

    def as_dict(self) -> dict[str, float]:
        return {"E0": self.E0, "ET": self.ET, "ground": self.ground,
                "actuator": self.actuator, "cot": self.cot, "cot_lossless": self.cot_lossless}


@dataclass
class Trajectory:
    """Dense samples of an exact trajectory: ``t`` (n,), ``x`` (n, 4), ``u`` (n,), ``mode`` (n,)."""

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    mode: np.ndarray

    @property
    def stroke(self) -> np.ndarray:
        return self.x[:, 0] - self.x[:, 2]

    def as_dict(self) -> dict[str, list]:
        return {"t": self.t.tolist(), "x_b": self.x[:, 0].tolist(), "v_b": self.x[:, 1].tolist(),
                "x_f": self.x[:, 2].tolist(), "v_f": self.x[:, 3].tolist(),
                "u": self.u.tolist(), "mode": [MODE_NAMES[m] for m in self.mode]}


@dataclass
class LandingResult:
    """Outcome of one simulated landing (dimensionless units).

    Attributes
    ----------
    depth : float
        Final penetration depth ``-x_f`` at rest (positive).
    steps : int
        Number of intrusion (yielding) phases.
    feasible : bool
        Rest proven and ``0 <= x_b - x_f <= s`` throughout (to 1e-9 s).
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
    params: DimensionlessParams
    policy: Any
    _segments: dict[str, np.ndarray] = field(default=None, repr=False)

    @property
    def rest_proven(self) -> bool:
        return self.status == STATUS_NAMES[K.REST_PROVEN]

    def trajectory(self, t_end: float | None = None, n: int = 2000) -> Trajectory:
        """Sample the exact solution on ``n`` points of ``[0, t_end]`` plus every event time.

        ``t_end`` defaults to 1.3 T (showing the body settle after the foot stops).
        """
        seg = self._segments
        ts = seg["t"]
        nseg = len(ts) - 1
        if t_end is None:
            T = self.T if math.isfinite(self.T) else ts[-1]
            t_end = max(1.3 * T, T + 2.0, ts[-1])
        grid = np.union1d(np.linspace(0.0, t_end, n), ts[(ts >= 0) & (ts <= t_end)])
        x = np.empty((len(grid), 4))
        u = np.empty(len(grid))
        mode = np.empty(len(grid), dtype=int)
        idx = np.clip(np.searchsorted(ts[:nseg], grid, side="right") - 1, 0, nseg - 1)
        for i, (tt, k) in enumerate(zip(grid, idx, strict=True)):
            zk = scipy.linalg.expm(seg["A"][k] * (tt - ts[k])) @ seg["z"][k]
            x[i] = zk[:4]
            u[i] = seg["cu"][k] @ zk
            mode[i] = seg["mode"][k]
        return Trajectory(grid, x, u, mode)

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """Plain JSON-able dict (non-finite numbers become None)."""
        d = {
            "depth": self.depth, "steps": self.steps, "feasible": self.feasible,
            "u_peak": self.u_peak, "stroke_min": self.stroke_min,
            "stroke_max": self.stroke_max, "t_first_stop": self.t_first_stop,
            "T": self.T, "status": self.status, "rest_proven": self.rest_proven,
            "n_segments": self.n_segments, "energy": self.energy.as_dict(),
            "params": self.params.as_dict(), "policy": policy_as_dict(self.policy),
        }
        if trajectory:
            d["trajectory"] = self.trajectory().as_dict()
        return json_safe(d)


def policy_as_dict(policy) -> dict[str, Any]:
    """``{"kind": ..., **fields}`` for JSON output."""
    kind = {Rigid: "rigid", Impedance: "impedance", ForceSchedule: "schedule"}[type(policy)]
    return {"kind": kind, **asdict(policy)}


# ----------------------------------------------------------------------- single
def _as_dimensionless(params) -> DimensionlessParams:
    if isinstance(params, PhysicalParams):
        return params.to_dimensionless()
    if isinstance(params, DimensionlessParams):
        return params
    raise TypeError("params must be DimensionlessParams or PhysicalParams")


def default_policy(p: DimensionlessParams) -> Policy:
    """Impedance from the parameters' gains when both are given, else the rigid leg."""
    if p.k_p is not None and p.k_d is not None:
        return Impedance(p.k_p, p.k_d, p.u_max)
    if (p.k_p is None) != (p.k_d is None):
        raise ParameterError("k_d" if p.k_d is None else "k_p", "give both k_p and k_d, or neither")
    return Rigid()


def _policy_arrays(policy: Policy, p: DimensionlessParams, mats):
    empty = np.zeros(0)
    if isinstance(policy, Rigid):
        return rigid_lock_gains(mats), np.inf, empty, empty
    if isinstance(policy, Impedance):
        l0 = p.l0 if policy.l0 is None else policy.l0
        Kf = np.empty((3, 5))
        Kf[:] = impedance_gain_vector(policy.k_p, policy.k_d, l0)
        umax = np.inf if policy.u_max is None else policy.u_max
        return Kf, umax, empty, empty
    if isinstance(policy, ForceSchedule):
        return (np.zeros((3, 5)), np.inf, np.asarray(policy.times, float),
                np.asarray(policy.values, float))
    raise TypeError(f"unknown policy {policy!r}")


def initial_state(p: DimensionlessParams) -> np.ndarray:
    """The paper's impact state ``[l0, v0, 0, v0]``."""
    return np.array([p.l0, p.v0, 0.0, p.v0])


def simulate(
    params: DimensionlessParams | PhysicalParams,
    policy: Policy | None = None,
    *,
    x0: np.ndarray | None = None,
    energy: bool = True,
    t_max: float = DEFAULT_T_MAX,
    max_segments: int = DEFAULT_MAX_SEGMENTS,
) -> LandingResult:
    """Simulate one landing exactly.

    Parameters
    ----------
    params : DimensionlessParams or PhysicalParams
        Robot, ground and impact velocity (SI parameters are scaled first).
    policy : Rigid, Impedance or ForceSchedule, optional
        Defaults to :func:`default_policy`.
    x0 : array of 4, optional
        Initial state; defaults to the paper's ``[s/2, v0, 0, v0]``.
    energy : bool
        Compute the energy ledger (exact Gramian quadrature; ~2x cost).
    t_max, max_segments : float, int
        Give up proving rest after this time or this many hybrid segments.

    Returns
    -------
    LandingResult
    """
    p = _as_dimensionless(params)
    policy = default_policy(p) if policy is None else policy
    mats = mode_matrices(p.r_m)
    Kf, umax, st, su = _policy_arrays(policy, p, mats)
    z0 = initial_state(p) if x0 is None else np.asarray(x0, float)
    if z0.shape != (4,) or not np.all(np.isfinite(z0)):
        raise ParameterError("x0", "must be 4 finite numbers")
    out, segments = K.run_landing(mats, Kf, umax, st, su, z0, p.s, float(t_max),
                                  int(max_segments), bool(energy))
    return _result_from_row(out, p, policy, segments)


def _result_from_row(out, p, policy, segments=None) -> LandingResult:
    return LandingResult(
        depth=float(out[K.O_DEPTH]),
        steps=int(out[K.O_STEPS]),
        feasible=bool(out[K.O_FEAS]),
        u_peak=float(out[K.O_UPEAK]),
        stroke_min=float(out[K.O_SMIN]),
        stroke_max=float(out[K.O_SMAX]),
        t_first_stop=float(out[K.O_TSTOP]),
        T=float(out[K.O_T]),
        status=STATUS_NAMES[int(out[K.O_STATUS])],
        energy=EnergyLedger(float(out[K.O_E0]), float(out[K.O_ET]),
                            float(out[K.O_EGND]), float(out[K.O_EACT])),
        n_segments=int(out[K.O_NSEG]),
        params=p,
        policy=policy,
        _segments=segments,
    )


# ------------------------------------------------------------------------ batch
_FIELD_COL = {
    "depth": K.O_DEPTH, "steps": K.O_STEPS, "t_first_stop": K.O_TSTOP, "T": K.O_T,
    "u_peak": K.O_UPEAK, "stroke_min": K.O_SMIN, "stroke_max": K.O_SMAX, "feasible": K.O_FEAS,
    "status": K.O_STATUS, "E0": K.O_E0, "ET": K.O_ET, "ground": K.O_EGND, "actuator": K.O_EACT,
}
BATCH_FIELDS = tuple(_FIELD_COL)


@dataclass
class BatchResult:
    """Arrays of per-landing figures, all of the broadcast input shape.

    Fields are those of :data:`BATCH_FIELDS`; ``feasible`` is boolean, ``steps``
    and ``status`` are integers (0 = rest proven). ``cot`` and
    ``cot_lossless`` are derived (NaN where energy was not computed).
    """

    inputs: dict[str, np.ndarray]
    data: dict[str, np.ndarray]

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["data"][name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def cot(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.data["E0"] > 0,
                            (self.data["E0"] - self.data["ET"]) / self.data["E0"], np.nan)

    @property
    def cot_lossless(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.data["E0"] > 0, self.data["ground"] / self.data["E0"], np.nan)


def _check_array(name, flat, check) -> None:
    bad = ~np.isfinite(flat)
    if bad.any():
        raise ParameterError(name, f"must be finite, got {float(flat[bad][0])!r}")
    if flat.size:
        check(name, float(flat.min()))
        check(name, float(flat.max()))


def simulate_batch(
    k_p,
    k_d,
    v0,
    r_m=5.0,
    s=20.0,
    u_max=None,
    *,
    energy: bool = False,
    progress: bool | None = None,
    chunk_size: int = 8192,
    t_max: float = DEFAULT_T_MAX,
    max_segments: int = DEFAULT_MAX_SEGMENTS,
) -> BatchResult:
    """Simulate many impedance-controlled landings in parallel (all cores).

    Parameters
    ----------
    k_p, k_d, v0, r_m, s : array_like
        Broadcast against each other; ``l0 = s/2`` and the paper's initial state.
    u_max : array_like or None
        Force saturation (None: unlimited).
    energy : bool
        Also compute the energy ledger.
    progress : bool or None
        Show a tqdm progress bar; None shows one for more than 50,000 landings.
    chunk_size : int
        Landings per parallel call (the progress bar's granularity).

    Returns
    -------
    BatchResult
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                   (k_p, k_d, v0, r_m, s, np.inf if u_max is None else u_max)))
    shape = arrays[0].shape
    kp, kd, v, rm, ss, um = (np.array(a.ravel(), dtype=float) for a in arrays)
    _check_array("k_p", kp, check_nonnegative)
    _check_array("k_d", kd, check_nonnegative)
    _check_array("v0", v, check_impact_velocity)
    _check_array("r_m", rm, check_positive)
    _check_array("s", ss, check_positive)
    if u_max is not None:
        _check_array("u_max", um, check_positive)
    n = kp.size
    uniq, ridx = np.unique(rm, return_inverse=True)
    mats = [mode_matrices(float(r)) for r in uniq]
    l0 = 0.5 * ss
    Kf = np.empty((n, 3, 5))
    Kf[:, :, 0], Kf[:, :, 1] = -kp[:, None], -kd[:, None]
    Kf[:, :, 2], Kf[:, :, 3] = kp[:, None], kd[:, None]
    Kf[:, :, 4] = (kp * l0)[:, None]
    x0 = np.stack([l0, v, np.zeros(n), v], axis=1)
    out = np.zeros((n, K.N_OUT))
    if progress is None:
        progress = n > 50_000
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n, unit="landing", desc="simulating")
    for a in range(0, n, chunk_size):
        b = min(n, a + chunk_size)
        K.run_batch(mats, ridx[a:b], Kf[a:b], um[a:b], x0[a:b], ss[a:b], t_max, max_segments,
                    energy, out[a:b])
        if bar is not None:
            bar.update(b - a)
    if bar is not None:
        bar.close()
    data = {}
    for name, col in _FIELD_COL.items():
        v_ = out[:, col].reshape(shape)
        if name == "feasible":
            v_ = v_.astype(bool)
        elif name in ("steps", "status"):
            v_ = v_.astype(np.int64)
        data[name] = v_
    inputs = {"k_p": arrays[0], "k_d": arrays[1], "v0": arrays[2], "r_m": arrays[3],
              "s": arrays[4], "u_max": arrays[5]}
    return BatchResult(inputs, data)
