"""Granular media: ground stiffness from resistive force theory, drag and added-mass presets.

Numbers and where they come from (the first three papers' texts were not at hand; their
coefficients are as transcribed by the sources named, and flagged so):

* **Resistive force theory** (Li, Zhang & Goldman, Science 339, 1408, 2013): the stress on a
  horizontal plate moving straight down at depth ``z`` is ``alpha_z z``, with
  ``alpha_z = A_00 + A_10 + B_11 + B_01 + B_-11`` of the medium's Fourier fit (the generic
  coefficients sum to 1, the scaling factor ``zeta``). Poppy-seed fits, loosely (LP) and
  closely packed (CP), as transcribed in open robotics code (IsaacLab and hector_mpc soft
  contact models): their vertical terms sum to ``alpha_z = 0.254`` (LP) and ``0.464``
  N/cm^3 (CP), and these sums are what is used. A lunar-RFT report quotes ``zeta = 0.488``
  for CP poppy seeds from Li et al.'s supplement, 5 % above the transcribed fit's sum (it
  would give 6477 N/m instead of 6159 N/m for the paper's foot): a measure of how far the
  transcriptions agree, not used. A flat foot of area ``A`` then has ``k_g = alpha_z A``
  (valid to depths of about one foot width, Agarwal et al. 2021).
* **Inertial drag** of a plate, ``F = lambda rho A v^2`` with ``lambda = 1`` and
  ``rho = 638 kg/m^3`` for poppy seeds (Agarwal, Karsai, Goldman & Kamrin, Sci. Adv. 7,
  eabe0631, 2021, eq. 4, read in full).
* **Added mass** (Aguilar & Goldman, Nature Physics 12, 278, 2016): cone parameters
  ``theta = 60 deg``, recruitment rate ``mu = 2``, packing ``phi = 0.57``, grain density
  ``1000 kg/m^3`` as used in Roberts' reference code (KodlabPenn,
  jumping_on_granular_media), with ``c_g = 1`` (that code also carries a "surrounding
  mass scaling" 2.7 whose role it leaves ambiguous: not used here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from softlanding.errors import ParameterError, check
from softlanding.model.ground import AddedMassGround, CustomGround, DragGround
from softlanding.model.robot import G_EARTH, Units

PAPER_FOOT_DIAMETER = 0.130
"""The paper's foot: a 130 mm acrylic cylinder (Section VI), metres."""
PAPER_K_G = 4400.0
"""The paper's measured ground stiffness for that foot in poppy seeds, N/m."""


@dataclass(frozen=True)
class Medium:
    """A granular medium's resistive-force-theory fit and bed density.

    Parameters
    ----------
    name : str
        What it is.
    rft : tuple of 5 float
        ``A_00, A_10, B_11, B_01, B_-11`` in N/cm^3 (the terms that add up to the
        vertical stress of a horizontal plate moving straight down).
    density : float
        Bed (bulk) density, kg/m^3.
    source : str
        Where the numbers come from.
    """

    name: str
    rft: tuple[float, float, float, float, float]
    density: float
    source: str

    @property
    def alpha_z(self) -> float:
        """Vertical stress per unit depth on a horizontal plate moving down, N/m^3."""
        return sum(self.rft) * 1e6  # N/cm^3 -> N/m^3


MEDIA = {
    "poppy-lp": Medium("poppy seeds, loosely packed", (0.051, 0.047, 0.053, 0.083, 0.020),
                       638.0, "Li, Zhang & Goldman 2013 fit, as transcribed in IsaacLab "
                              "soft-contact code; density Agarwal et al. 2021"),
    "poppy-cp": Medium("poppy seeds, closely packed", (0.094, 0.092, 0.092, 0.151, 0.035),
                       638.0, "Li, Zhang & Goldman 2013 fit, as transcribed in IsaacLab "
                              "soft-contact code; density Agarwal et al. 2021"),
}
"""The media with published fits, by the name the CLI takes."""


def medium(name: str) -> Medium:
    """A medium of :data:`MEDIA` by name.

    Parameters
    ----------
    name : str
        ``"poppy-lp"`` or ``"poppy-cp"``.
    """
    try:
        return MEDIA[name]
    except KeyError:
        raise ParameterError("medium", f"must be one of {', '.join(MEDIA)}, "
                                       f"got {name!r}") from None


def foot_area(diameter: float) -> float:
    """Area of a flat circular foot, m^2.

    Parameters
    ----------
    diameter : float
        Foot diameter, m (> 0).
    """
    return math.pi * (0.5 * check("foot_diameter", diameter, _POS)) ** 2


def rft_stiffness(med: Medium, diameter: float = PAPER_FOOT_DIAMETER) -> float:
    """``k_g = alpha_z A`` [N/m]: the one-way spring of a flat foot by resistive force theory.

    Parameters
    ----------
    med : Medium
        The granular medium.
    diameter : float
        Foot diameter, m.
    """
    return med.alpha_z * foot_area(diameter)


def poppy_seed_drag(units: Units, diameter: float = PAPER_FOOT_DIAMETER,
                    lam: float = 1.0) -> DragGround:
    """Inertial drag of a flat foot in poppy seeds, ``b = lambda rho A`` (Agarwal et al. 2021).

    Parameters
    ----------
    units : Units
        The robot's mass and ground stiffness.
    diameter : float
        Foot diameter, m.
    lam : float
        Drag factor ``lambda`` (1 in Agarwal et al.; 1.1 in their plate fits).
    """
    b = lam * MEDIA["poppy-lp"].density * foot_area(diameter)
    return DragGround.from_si(b, units.m_t, units.k_g, units.g)


def poppy_seed_added_mass(units: Units, diameter: float = PAPER_FOOT_DIAMETER, *,
                          theta_deg: float = 60.0, mu: float = 2.0, phi: float = 0.57,
                          grain_density: float = 1000.0, c_g: float = 1.0,
                          c_d: float = 0.0) -> AddedMassGround:
    """The added-mass ground of a flat foot in poppy seeds (see the module notes).

    Parameters
    ----------
    units, diameter
        As :func:`poppy_seed_drag`.
    theta_deg : float
        Shear-band angle of the grain cone, degrees.
    mu : float
        Recruitment rate.
    phi : float
        Packing fraction.
    grain_density : float
        Grain density, kg/m^3.
    c_g : float
        Mass scaling of the cone.
    c_d : float
        Extra dimensionless drag.
    """
    x_s = units.length
    kappa = mu / math.tan(math.radians(theta_deg))
    pi_a = math.pi * c_g * phi * grain_density * mu * x_s**3 / units.m_t
    return AddedMassGround(pi_a=pi_a, radius=0.5 * diameter / x_s, kappa=kappa, c_d=c_d)


@lru_cache(maxsize=32)
def power_law_ground(n: float) -> CustomGround:
    """The power-law ground ``f = d^n`` (stiffening for ``n > 1``), a user law.

    The worked example of a :class:`~softlanding.model.ground.CustomGround`: one CasADi
    expression, from which the simulator (C code generated and compiled once), the OCP
    and the certificate all derive. Cached per ``n`` (one object, one compiled law).

    Parameters
    ----------
    n : float
        Exponent (> 0); ``n = 1`` is the paper's spring.
    """
    import casadi as ca

    n = check("exponent", n)
    return CustomGround(f"power-{n:g}", lambda d, v: ca.fmax(d, 0.0) ** n,
                        parameters={"exponent": n})


def paper_rig_units() -> Units:
    """The paper's rig: ``m_t = 3 kg`` on ``k_g = 4.4 kN/m``."""
    return Units(m_t=3.0, k_g=PAPER_K_G, g=G_EARTH)


_POS = (lambda x: x > 0.0, "must be > 0 (metres)")

__all__ = ["MEDIA", "Medium", "PAPER_FOOT_DIAMETER", "PAPER_K_G", "foot_area", "medium",
           "paper_rig_units", "poppy_seed_added_mass", "poppy_seed_drag", "power_law_ground",
           "rft_stiffness"]
