"""Ground models: the force yielding ground puts on a foot that digs into it.

A ground model is a small frozen value object. :meth:`yield_force` gives, as a
CasADi expression (or a number), the upward force on a foot moving down at
depth ``d = -x_f`` with velocity ``v_f`` (< 0); :meth:`added_mass` the mass of
grains carried along by the foot (0 for most models). Everything else (the
simulator, the OCP's dynamics, the PMP checks, the energy ledger) is derived
from them through :mod:`softlanding.model.dynamics`; do not write a ground law
anywhere else.

The hybrid logic is the paper's for every model: the ground is plastic (the
crater keeps its deepest depth ``d``), a foot at rest at the crater bottom is
held by any support force up to ``yield_force(d, 0)`` (beyond that it yields
again), the ground cannot pull (below 0 the foot lifts off), and a foot in
flight lands again at the crater bottom.

Units are the paper's: depth in ``x_s = m_t g / k_g``, velocity in ``x_s / tau_s``,
force in ``m_t g``, mass in ``m_t``; the quasi-static spring has stiffness 1.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, ClassVar, Protocol, runtime_checkable

from softlanding.errors import ParameterError, check, check_number


@runtime_checkable
class Ground(Protocol):
    """What the toolkit needs of a ground model."""

    @property
    def name(self) -> str:
        """Short name (``"linear"``, ``"drag"``, ...)."""

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """Upward force on the foot while it yields (moves down) at ``depth`` >= 0.

        Parameters
        ----------
        depth : float or casadi expression
            Foot depth ``-x_f`` (>= 0 while yielding).
        v_f : float or casadi expression
            Foot velocity (<= 0 while yielding).
        """

    def added_mass(self, depth: Any) -> Any:
        """Mass of grains moving with a yielding foot at ``depth`` (units of ``m_t``).

        Parameters
        ----------
        depth : float or casadi expression
            Foot depth ``-x_f``.
        """

    @property
    def is_affine(self) -> bool:
        """True if the yielding dynamics are affine in the state (exact matrix-exponential
        path); otherwise the simulator integrates them
        (see :mod:`softlanding.simulation.simulator`)."""

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output."""

    def __hash__(self) -> int:
        """Ground models are frozen values (mode matrices are cached per model)."""


def _depth_power(depth: Any, n: float) -> Any:
    return depth**n if n != 1.0 else depth


def _stiffness_entry(k: float) -> dict[str, float]:
    """The JSON entry of a stiffness factor: none for the paper's 1 (outputs unchanged)."""
    return {} if k == 1.0 else {"stiffness": k}


class _NoAddedMass:
    """A ground whose grains do not move with the foot (a mixin)."""

    def added_mass(self, depth: Any) -> Any:
        """No grains move with the foot.

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (unused).
        """
        return 0.0


@dataclass(frozen=True)
class LinearGround(_NoAddedMass):
    """The paper's one-way plastic spring: ``f_g = K d`` (``d = -x_f``) while the foot yields.

    In the paper's units the measured stiffness is 1 (lengths are scaled by
    ``x_s = m_t g / k_g``); ``stiffness`` ``K`` is a ground ``K`` times as stiff as the one the
    units are made of (an unknown or mismatched ground: ``K k_g`` in SI). The crater of depth
    ``d`` holds support forces up to ``K d``; the work done on the ground by a foot that dug
    to depth ``d`` is ``K d^2 / 2``.

    Parameters
    ----------
    stiffness : float
        ``K > 0`` (default 1: the paper's ground).
    """

    stiffness: float = 1.0
    name: ClassVar[str] = "linear"

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness", check_number("stiffness", self.stiffness))

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``f_g = K d`` (independent of the foot's velocity).

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (>= 0).
        v_f : float or expression
            The foot's velocity (unused).
        """
        return depth if self.stiffness == 1.0 else self.stiffness * depth

    @property
    def is_affine(self) -> bool:
        return True

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output (``stiffness`` when not 1)."""
        return {"model": self.name, **_stiffness_entry(self.stiffness)}


@dataclass(frozen=True)
class DragGround(_NoAddedMass):
    """The paper's spring plus inertial drag (Katsuragi & Durian, Nature Physics 3, 420, 2007).

    While the foot yields, ``f_g = d + c_d v_f^2``: the granular impact force law
    ``F = k z + b v^2`` (Katsuragi & Durian's "unified force law", depth-linear
    friction plus a velocity-squared inertial drag, ``b = m / d_1``), with its
    depth term the paper's measured spring. The drag opposes the downward motion
    and vanishes at rest, so the static and flight modes are the paper's.

    Parameters
    ----------
    c_d : float
        Dimensionless drag number ``b x_s / m_t = b g / k_g`` for a drag coefficient
        ``b`` in kg/m (>= 0). For a flat plate ``b = lambda rho A`` with
        ``lambda ~ 1`` and ``rho`` the bed density (dynamic resistive force theory,
        Agarwal et al., Sci. Adv. 7, eabe0631, 2021): the paper's 130 mm foot in
        poppy seeds (``rho = 638 kg/m^3``) has ``b ~ 8.5 kg/m``, ``c_d ~ 0.019``
        (see :func:`softlanding.model.terrain.poppy_seed_drag`).
    stiffness : float
        The spring's factor ``K`` (``f_g = K d + c_d v_f^2``; default 1, the paper's; see
        :class:`LinearGround`).
    """

    c_d: float
    stiffness: float = 1.0
    name: ClassVar[str] = "drag"

    def __post_init__(self) -> None:
        object.__setattr__(self, "c_d", check_number("c_d", self.c_d))
        object.__setattr__(self, "stiffness", check_number("stiffness", self.stiffness))

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``f_g = K d + c_d v_f^2``.

        Parameters
        ----------
        depth, v_f : float or expression
            Foot depth ``-x_f`` (>= 0) and velocity (< 0 while yielding).
        """
        spring = depth if self.stiffness == 1.0 else self.stiffness * depth
        return spring + self.c_d * v_f**2 if self.c_d else spring

    @property
    def is_affine(self) -> bool:
        return self.c_d == 0.0

    @classmethod
    def from_si(cls, b: float, m_t: float, k_g: float, g: float = 9.81) -> DragGround:
        """From a drag coefficient ``b`` [kg/m], total mass [kg] and ground stiffness [N/m].

        Parameters
        ----------
        b : float
            Drag coefficient of ``F = b v^2`` [kg/m].
        m_t : float
            Total robot mass [kg].
        k_g : float
            Ground stiffness [N/m].
        g : float
            Gravity [m/s^2].
        """
        return cls(check("b", b) * g / check("k_g", k_g))

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output (``stiffness`` when not 1)."""
        return {"model": self.name, "c_d": self.c_d, **_stiffness_entry(self.stiffness)}


@dataclass(frozen=True)
class AddedMassGround:
    """The paper's spring with an accreted cone of grains (Aguilar & Goldman, Nature Physics
    12, 278, 2016), in the form of Choi et al. (Science Robotics 8, eade2256, 2023, eqs.
    S11-S16) and Roberts' reference code.

    A flat foot of radius ``R`` digging to depth ``d`` accelerates a cone of grains
    whose flat-topped section shrinks as ``A(d) = pi (R - kappa d)^2``, complete at
    the critical depth ``d_c = R / kappa`` (``kappa = mu / tan(theta)``, shear-band
    angle ``theta``, recruitment rate ``mu``). The accreted mass is
    ``m_a(d) = c_g phi rho mu int_0^d A``; the grains take the foot's velocity, so the
    bed pushes back with their momentum flux ``(dm_a/dd) v^2``. Dimensionless, with
    ``r = R / x_s``:

        m_a(d) = Pi_a (r^2 d - r kappa d^2 + kappa^2 d^3 / 3)     (d <= d_c = r / kappa)
        (m_f + m_a) x_f'' = -m_f - u + d + (c_d + m_a'(d)) v_f^2,
        m_a'(d) = Pi_a (r - kappa d)^2,

    and ``m_a`` constant beyond ``d_c``. The quasi-static term is the paper's spring.
    When the foot stops the grains stop with it; a foot that lands again at speed
    hits grains at rest (the simulator makes that collision perfectly inelastic).

    Parameters
    ----------
    pi_a : float
        ``Pi_a = pi c_g phi rho_p mu x_s^3 / m_t`` (>= 0).
    radius : float
        Foot radius ``R / x_s`` (> 0).
    kappa : float
        Cone shape ``mu / tan(theta)`` (> 0).
    c_d : float
        Extra velocity-squared drag (as :class:`DragGround`), default 0.
    """

    pi_a: float
    radius: float
    kappa: float
    c_d: float = 0.0
    name: ClassVar[str] = "added-mass"

    def __post_init__(self) -> None:
        for n in ("pi_a", "radius", "kappa", "c_d"):
            object.__setattr__(self, n, check_number(n, getattr(self, n)))

    @property
    def critical_depth(self) -> float:
        """``d_c = r / kappa``: the cone is complete."""
        return self.radius / self.kappa

    def _clipped(self, depth: Any) -> Any:
        if isinstance(depth, numbers.Real):
            return min(float(depth), self.critical_depth)
        import casadi as ca  # a symbolic depth (float() of one is NaN, not an error)

        return ca.fmin(depth, self.critical_depth)

    def added_mass(self, depth: Any) -> Any:
        """``m_a(min(d, d_c))`` (units of ``m_t``).

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (>= 0).
        """
        dd = self._clipped(depth)
        r, k = self.radius, self.kappa
        return self.pi_a * (r * r * dd - r * k * dd**2 + k * k * dd**3 / 3.0)

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``f_g = d + (c_d + m_a'(d)) v_f^2``: the spring, drag and the grains' momentum flux.

        Parameters
        ----------
        depth, v_f : float or expression
            Foot depth ``-x_f`` (>= 0) and velocity (< 0 while yielding).
        """
        dd = self._clipped(depth)
        flux = self.pi_a * (self.radius - self.kappa * dd) ** 2
        return depth + (self.c_d + flux) * v_f**2

    @property
    def is_affine(self) -> bool:
        return self.pi_a == 0.0 and self.c_d == 0.0

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output."""
        return {"model": self.name, "pi_a": self.pi_a, "radius": self.radius,
                "kappa": self.kappa, "c_d": self.c_d,
                "critical_depth": self.critical_depth}


@dataclass(frozen=True)
class CustomGround:
    """A ground law of your own: the yielding force (and optionally an added mass) as
    functions of the depth and the foot's velocity, written with ``+ - * / **`` and
    CasADi's math (``casadi.sqrt``, ``casadi.fmin``, ...) so the OCP, the certificate and
    the simulator all derive from it.

    Example, a power law ``f = d^n`` (stiffening granular beds have ``n > 1``)::

        import casadi as ca
        ground = CustomGround("power-1.5", lambda d, v: ca.fmax(d, 0) ** 1.5)

    ``force`` is the bed's resistance (quasi-static and rate-dependent); with a ``mass``
    law the grains' momentum flux ``m_a'(d) v_f^2`` (momentum given to grains accreted at
    rest, ``d/dt (m_a v_f)``) is added by :meth:`yield_force`, and the dynamics divide by
    ``m_f + m_a``. The crater's static hold is ``force(d, 0)``. The simulator compiles the
    law to C once (:mod:`softlanding.simulation.groundcode`).

    Parameters
    ----------
    label : str
        Its name in tables and JSON.
    force : callable
        ``force(depth, v_f)``: upward force on a yielding foot.
    mass : callable, optional
        ``mass(depth)``: added mass moving with the foot.
    parameters : dict
        Numbers to record in JSON (the law's own constants).
    """

    label: str
    force: Callable[[Any, Any], Any] = field(compare=False)
    mass: Callable[[Any], Any] | None = field(default=None, compare=False)
    parameters: dict[str, float] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not self.label:
            raise ParameterError("label", "a custom ground needs a name")
        for d, v in ((1.0, -1.0), (0.0, 0.0), (3.0, -2.0)):
            try:
                f = float(self.force(d, v))
                m = 0.0 if self.mass is None else float(self.mass(d))
            except (TypeError, ValueError, ArithmeticError) as err:  # not one number
                raise ParameterError("force", f"the law fails at depth {d:g}, velocity "
                                              f"{v:g}: {type(err).__name__}: {err}") from None
            if not (math.isfinite(f) and math.isfinite(m)) or m < 0:
                raise ParameterError("force", f"the law gives f({d:g}, {v:g}) = {f!r}, "
                                              f"m_a = {m!r}: need finite values, m_a >= 0")

    @property
    def name(self) -> str:
        return self.label

    def __hash__(self) -> int:
        return hash((self.label, id(self.force), id(self.mass)))

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``force(depth, v_f) + m_a'(depth) v_f^2``: the bed's force, plus the grains' momentum
        flux when a mass law is given (as :class:`AddedMassGround`).

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (>= 0).
        v_f : float or expression
            The foot's velocity.
        """
        f = self.force(depth, v_f)
        if self.mass is None:
            return f
        slope = _mass_slope(self.mass)(depth)
        if isinstance(depth, numbers.Real) and isinstance(v_f, numbers.Real):
            return float(f) + float(slope) * float(v_f) ** 2
        return f + slope * v_f**2

    def added_mass(self, depth: Any) -> Any:
        """``mass(depth)`` (0 when not given).

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (>= 0).
        """
        return 0.0 if self.mass is None else self.mass(depth)

    @property
    def is_affine(self) -> bool:
        import casadi as ca

        d, v = ca.SX.sym("d"), ca.SX.sym("v")
        f = ca.SX(self.force(d, v))
        z = ca.vertcat(d, v)
        return self.mass is None and not ca.depends_on(ca.jacobian(f, z), z)

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output."""
        return {"model": self.label, **self.parameters}


@lru_cache(maxsize=64)
def _mass_slope(mass: Callable[[Any], Any]) -> Any:
    """``d -> m_a'(d)`` of a mass law, as a CasADi function (numbers, SX or MX)."""
    import casadi as ca

    d = ca.SX.sym("d")
    return ca.Function("mass_slope", [d], [ca.jacobian(ca.SX(mass(d)), d)])


LINEAR_GROUND = LinearGround()
"""The paper's ground (the default everywhere)."""

_SYMBOLS = {"stiffness": "$K$", "c_d": "$c_d$", "pi_a": r"$\Pi_a$", "radius": "$R$",
            "kappa": r"$\kappa$"}


def ground_label(ground: Ground | dict[str, Any]) -> str:
    """The ground model and its numbers, for a figure title: ``"ground: drag, $c_d$=0.2"``.

    Parameters
    ----------
    ground : Ground or dict
        A ground model, or its :meth:`~Ground.to_dict` (as read back from a dataset by
        :func:`ground_attrs`' inverse).
    """
    d = ground if isinstance(ground, dict) else ground.to_dict()
    params = [f"{_SYMBOLS.get(k, k)}={v:.4g}" for k, v in d.items()  # derived ones left out
              if k not in ("model", "critical_depth") and isinstance(v, (int, float))]
    return "ground: " + ", ".join([str(d["model"])] + params)


def ground_attrs(ground: Ground) -> dict[str, Any]:
    """The ground as netCDF attributes: ``ground`` (its name) and ``ground_<parameter>``.

    Parameters
    ----------
    ground : Ground
        The model.
    """
    d = ground.to_dict()
    return {"ground": str(d.pop("model")),
            **{f"ground_{k}": float(v) for k, v in d.items() if isinstance(v, (int, float))}}


def ground_of_attrs(attrs: dict[str, Any]) -> dict[str, Any]:
    """The inverse of :func:`ground_attrs`: the ground's dict (for :func:`ground_label`).

    Parameters
    ----------
    attrs : dict
        A dataset's attributes.
    """
    return {"model": attrs.get("ground", "linear"),
            **{k[7:]: v for k, v in attrs.items() if k.startswith("ground_")}}


MAX_GROUNDS = 64
"""Most grounds one robust plan is searched over. Every point of the search simulates the
plan on each ground (and a drag ground compiles its law once), so the cost grows with their
number: measured at v0 = -3, 6 grounds (3 linear, 3 drag) take 52 s CPU with a cold law
cache, 200 grounds 27 min; 64 are several minutes. Sample a larger set (the project's
unknown-ground study uses 15)."""


def ground_sequence(grounds: Any, name: str = "grounds") -> tuple[Ground, ...]:
    """A ground, or a non-empty sequence of at most :data:`MAX_GROUNDS` grounds, as a tuple.

    Parameters
    ----------
    grounds : Ground or iterable of Ground
        What was passed.
    name : str
        The argument's name, for messages.

    Raises
    ------
    ParameterError
        Not a ground or a sequence of them, empty, or longer than :data:`MAX_GROUNDS`.
    """
    if isinstance(grounds, Ground):
        return (grounds,)
    if isinstance(grounds, str | bytes) or not hasattr(grounds, "__iter__"):
        raise ParameterError(name, "must be a ground model or a sequence of them, got "
                                   f"{type(grounds).__name__} {grounds!r:.60}")
    out = tuple(grounds)
    if not out:
        raise ParameterError(name, "needs at least one ground")
    if len(out) > MAX_GROUNDS:
        raise ParameterError(name, f"at most {MAX_GROUNDS} grounds, got {len(out)} (sample "
                                   "the set: each ground is simulated at every search point)")
    for g in out:
        if not isinstance(g, Ground):
            raise ParameterError(name, "must be ground models (softlanding.model.ground), "
                                       f"got {type(g).__name__} {g!r:.60}")
    return out


def linear_or_drag(stiffness: float, c_d: float) -> Ground:
    """The ground ``f = K d + c_d v_f^2``: linear when ``c_d = 0`` (the exact path), else drag.

    Parameters
    ----------
    stiffness, c_d : float
        ``K`` and the drag number.
    """
    return LinearGround(stiffness) if c_d == 0 else DragGround(c_d, stiffness)


__all__ = ["AddedMassGround", "CustomGround", "DragGround", "Ground", "LINEAR_GROUND",
           "LinearGround", "MAX_GROUNDS", "ground_attrs", "ground_label", "ground_of_attrs",
           "ground_sequence", "linear_or_drag"]
