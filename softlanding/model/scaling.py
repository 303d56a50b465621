"""A physical robot in SI units, and the paper's experimental rig.

The paper (Lynch, Lynch & Umbanhowar, "The Soft Landing Problem") scales
lengths by ``x_s = m_t g / k_g`` (the depth at which the ground carries the
robot's weight), time by ``tau_s = sqrt(m_t / k_g)`` and force by
``u_s = m_t g``, with ``m_t = m_b + m_f``. The dimensionless model then has
only the mass ratio ``r_m = m_b / m_f``, the stroke ``s = S / x_s``, the force
limit ``u_max = U_max / u_s`` and the impact velocity ``v0 = V0 tau_s / x_s``;
impedance gains scale as ``k_p = K_p / k_g`` and ``k_d = K_d / sqrt(m_t k_g)``.

The conversions themselves live on the value objects (``to_si`` /
``from_si`` of :class:`~softlanding.model.robot.Robot`, :class:`~softlanding.model.robot.Impact`
and the controllers); :class:`PhysicalParams` is the flat SI description a
user types (the ``scale`` command), converted through them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

from softlanding.errors import ParameterError, check_number, check_optional
from softlanding.model.controllers import Controller, Impedance
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import G_EARTH, PAPER_ROBOT, Impact, Robot, Units
from softlanding.model.terrain import paper_rig_units


class Scenario(NamedTuple):
    """A robot, an impact, a controller and a ground: ``simulate(*scenario)`` runs it."""

    robot: Robot
    impact: Impact
    controller: Controller | None = None
    ground: Ground = LINEAR_GROUND


@dataclass(frozen=True)
class PhysicalParams:
    """A physical robot, ground and impact in SI units.

    Parameters
    ----------
    m_b, m_f : float
        Body and foot masses [kg] (> 0).
    k_g : float
        Ground stiffness of the one-way plastic spring [N/m] (> 0).
    stroke : float
        Actuator stroke ``S`` [m] (> 0).
    v0 : float
        Impact velocity ``V0`` [m/s] (<= 0, negative = downward).
    u_max : float or None
        Actuator force limit ``U_max`` [N] (> 0), or None.
    K_p, K_d : float or None
        Rendered leg stiffness [N/m] and damping [N s/m] (>= 0), or None.
    g : float
        Gravity [m/s^2].
    rest_length : float or None
        Leg length at impact [m]; None: half the stroke.
    """

    m_b: float
    m_f: float
    k_g: float
    stroke: float
    v0: float = 0.0
    u_max: float | None = None
    K_p: float | None = None
    K_d: float | None = None
    g: float = G_EARTH
    rest_length: float | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("m_b", "m_f", "k_g", "stroke", "g"):
            set_(self, name, check_number(name, getattr(self, name)))
        set_(self, "v0", check_number("v0", self.v0))
        for name in ("u_max", "K_p", "K_d", "rest_length"):
            set_(self, name, check_optional(name, getattr(self, name)))
        if (self.K_p is None) != (self.K_d is None):
            raise ParameterError("K_d" if self.K_d is None else "K_p",
                                 "give both K_p and K_d, or neither")

    @property
    def m_t(self) -> float:
        """Total mass [kg]."""
        return self.m_b + self.m_f

    @property
    def units(self) -> Units:
        """The paper's scales of this robot."""
        return Units(self.m_t, self.k_g, self.g)

    def to_dimensionless(self) -> Scenario:
        """The robot, impact and (if gains are given) impedance in the paper's units."""
        robot, units = Robot.from_si(self.m_b, self.m_f, self.stroke, self.k_g, U_max=self.u_max,
                                     rest_length=self.rest_length, g=self.g)
        controller = None
        if self.K_p is not None and self.K_d is not None:
            controller = Impedance.from_si(self.K_p, self.K_d, units)
        return Scenario(robot, Impact.from_si(self.v0, units), controller)

    @classmethod
    def from_dimensionless(cls, robot: Robot, impact: Impact, units: Units,
                           controller: Impedance | None = None) -> PhysicalParams:
        """The SI robot of a dimensionless one with total mass and ground stiffness ``units``.

        Parameters
        ----------
        robot : Robot
        impact : Impact
        units : Units
            Total mass, ground stiffness and gravity.
        controller : Impedance, optional
            Its gains are converted too.
        """
        r: dict[str, Any] = robot.to_si(units)
        gains: dict[str, Any] = {}
        if controller is not None:
            si = controller.to_si(units)
            gains = {"K_p": si["K_p"], "K_d": si["K_d"]}
        return cls(m_b=r["m_b"], m_f=r["m_f"], k_g=units.k_g, stroke=r["stroke"],
                   v0=impact.to_si(units)["V0"], u_max=r["U_max"], g=units.g,
                   rest_length=None if robot.l0 is None else r["rest_length"], **gains)

    def to_dict(self) -> dict[str, Any]:
        """All fields."""
        return asdict(self)


def paper_rig(v0: float = -1.2, **overrides: float) -> PhysicalParams:
    """The experimental robot of the paper's Section VI, in SI units.

    Measured in the paper: ``m_b = 2.5 kg``, ``m_f = 0.5 kg`` (so ``r_m = 5``),
    ``k_g = 4.4 kN/m`` (130 mm acrylic foot in poppy seeds), ``g = 9.81``.
    Impact speeds up to 1.2 m/s.

    Left open by the paper, and chosen here from :data:`~softlanding.model.robot.PAPER_ROBOT`:

    * **stroke S** -- the paper uses ``s = 20`` "approximately describing" the
      rig (a LinMot PS01-23x160H, nominally 160 mm of travel). We set
      ``S = 20 x_s = 0.1338 m`` so that the preset reproduces ``s = 20``
      exactly; 160 mm would give ``s = 23.9``.
    * **force limit U_max** -- the paper derives ``u_max = 8.2`` from the
      optimal impedance controller at ``v0 = -10``; we set
      ``U_max = 8.2 m_t g = 241.3 N`` so that the preset reproduces it.
    * **impact velocity** -- the paper says 1.2 m/s is ``v0 = -4.8``; with the
      masses and ``k_g`` above the velocity scale is ``x_s/tau_s = 0.256 m/s``,
      so 1.2 m/s is ``v0 = -4.68`` (``v0 = -4.8`` is 1.23 m/s). We keep the
      physics and report the small discrepancy rather than hide it.

    Parameters
    ----------
    v0 : float
        Impact velocity [m/s], default -1.2 (the rig's fastest drop).
    **overrides
        Any :class:`PhysicalParams` field to replace.
    """
    units = paper_rig_units()
    fields: dict[str, Any] = PhysicalParams.from_dimensionless(
        PAPER_ROBOT, Impact(0.0), units).to_dict()
    fields["v0"] = v0
    unknown = set(overrides) - set(fields)
    if unknown:
        raise ParameterError(sorted(unknown)[0], "is not a PhysicalParams field")
    fields.update(overrides)
    return PhysicalParams(**fields)


EXPERIMENT_V0 = (-1.6, -3.2, -4.8)
"""Impact velocities of the paper's experiments (it gives up to v0 = -4.8, 1.2 m/s; here in
thirds)."""
EXPERIMENT_KP = (0.2, 0.5, 0.9)
"""Stiffness gains of the paper's experiment curves."""

__all__ = ["EXPERIMENT_KP", "EXPERIMENT_V0", "PhysicalParams", "Scenario", "paper_rig"]
