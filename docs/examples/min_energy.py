"""
A smooth landing variant in one module: the least actuator energy within a depth budget
========================================================================================

The paper minimises the depth. A robot on batteries may rather spend as little actuator
effort as it can, ``J = ∫u² dt`` until the body rests, as long as the foot sinks no deeper
than a budget ``D``. The problem is the two-phase landing (yielding, then static stance
until the body rests; :mod:`softlanding.optimal.stance_phases`) with that cost and one
terminal condition; optionally the leg keeps a margin ``m`` from both ends of its stroke.

The optimal force is continuous (interior arcs, ``H_u = 2u + ... = 0``): there are no
switching times to refine, so the pipeline (:func:`softlanding.optimal.solve_phased`)
converges it on a refined collocation mesh, certifies every arc (stationarity,
Legendre–Clebsch, ``H`` constant and zero) and replays the force in the exact simulator.

**Closed form.** The body obeys ``v_b' = -1 + (1 + r_m)/r_m u`` in every ground mode, and
must go from ``v0`` to rest. By Cauchy–Schwarz ``J >= (|v0| + T)² r_m² / ((1 + r_m)² T)``,
least at ``T = |v0|``: ``J >= 4 |v0| r_m² / (1 + r_m)²`` (25/3 at ``v0 = -3``, ``r_m =
5``), met by the constant force ``u = 2 r_m / (1 + r_m)`` when the landing it gives fits
the budget. A tighter budget binds: the depth is ``D`` and the energy is larger.

Run it from the command line (``PYTHONPATH=docs/examples``)::

    softlanding solve --variant min_energy:VARIANT --v0 -3 --depth-max 3 --pmp
    softlanding solve --variant min_energy:VARIANT --v0 -3 --config budget.toml

where ``budget.toml`` holds ``depth_max = 3`` (and optionally ``stroke_margin = 8.6``).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting
from softlanding.errors import ParameterError
from softlanding.model import LINEAR_GROUND, PAPER_ROBOT, Ground, Impact, Robot
from softlanding.optimal import Option, TwoPhase, TwoPhaseLanding, Variant, solve_phased
from softlanding.optimal.stance_phases import (
    ARREST_MAX,
    T_MAX,
    add_static,
    add_yielding,
    arrest_to_rest,
    impact_state,
    parameters,
)


def energy_bound(v0: float, r_m: float) -> float:
    """The least energy of any landing from ``v0``: ``4 |v0| r_m² / (1 + r_m)²``."""
    return 4.0 * abs(v0) * (r_m / (1.0 + r_m)) ** 2


@lru_cache(maxsize=4)
def min_energy_transcription(ground: Ground = LINEAR_GROUND,
                             margin: bool = False) -> MultipleShooting:
    """Yielding, then static until the body rests; minimise ``∫u² dt``, the final depth at
    most the parameter ``depth_max`` (and, with ``margin``, the leg within ``[m, s - m]``,
    ``m`` the parameter ``stroke_margin``)."""
    mp = MultiPhaseProblem("min_energy")
    par = parameters(mp)
    depth_max = mp.parameter("depth_max")
    m = mp.parameter("stroke_margin")
    yielding = add_yielding(mp, "yielding", par, ground)
    yielding.free_final_time(1e-3, T_MAX, guess=0.5)
    static = add_static(mp, "static", par, ground)
    static.free_duration(1e-6, ARREST_MAX, guess=2.0)
    impact_state(yielding, par)
    arrest_to_rest(static, par, ground)
    mp.link(yielding, static)
    static.terminal_constraint(-static.x[2] - depth_max, -ca.inf, 0.0, name="depth budget")
    for ph in (yielding, static):
        ph.minimize_integral(ph.u[0] ** 2)
        if margin:
            ph.path_constraint(ph.x[0] - ph.x[2] - m, 0.0, par["s"] - 2 * m, name="margin")
    return MultipleShooting(mp, nodes=[40, 20], integrator="rk4", substeps=4, expand=True)


@dataclass(kw_only=True)
class MinEnergyLanding(TwoPhaseLanding):
    """The least-energy landing; ``paper_depth`` holds the budget, so ``gain`` is the margin
    left under it (>= 0).

    Attributes
    ----------
    energy : float
        ``∫u² dt`` until the body rests (its error: ``smooth.objective_error``).
    depth_max, stroke_margin : float
        The budget and the margin asked for.
    """

    VARIANT: ClassVar[str] = "min-energy"
    LABEL: ClassVar[str] = "least actuator energy"
    REFERENCE: ClassVar[str] = "depth budget D"
    WORSE_THAN_REFERENCE: ClassVar[str] = "the depth budget, exceeded by {:.2e}"

    energy: float
    depth_max: float
    stroke_margin: float

    @property
    def budget_active(self) -> bool:
        """The depth reaches the budget (to 1e-6)."""
        return self.depth_max - self.depth <= 1e-6 * max(1.0, self.depth_max)

    def own_rows(self) -> list[tuple[str, object]]:
        """The energy and its closed-form bound first, then the two-phase rows."""
        bound = energy_bound(self.impact.v0, self.robot.r_m)
        return [("energy ∫u² dt", self.energy), ("energy bound 4|v0| r_m²/(1+r_m)²", bound),
                ("depth budget", "active" if self.budget_active else "slack"),
                ("stroke margin", self.stroke_margin), *super().own_rows()]

    def own_reasons(self) -> list[str]:
        """An energy below the closed-form bound is impossible."""
        bound = energy_bound(self.impact.v0, self.robot.r_m)
        return [] if self.energy >= bound * (1 - 1e-8) else [
            f"the energy {self.energy:.12g} is below the bound {bound:.12g}"]

    def own_dict(self) -> dict[str, Any]:
        """The two-phase fields, the energy and the budget."""
        return {**super().own_dict(), "energy": self.energy, "depth_max": self.depth_max,
                "stroke_margin": self.stroke_margin, "budget_active": self.budget_active,
                "energy_bound": energy_bound(self.impact.v0, self.robot.r_m)}


class MinEnergy(TwoPhase):
    """The hooks: the two-phase landing's result and replay, with this problem."""

    def __init__(self, robot: Robot, impact: Impact, ground: Ground, depth_max: float,
                 stroke_margin: float) -> None:
        super().__init__(robot, impact, ground, 1, None)
        self.depth_max, self.stroke_margin = depth_max, stroke_margin
        self.paper_depth = depth_max

    def parameters(self) -> dict[str, float]:
        """The landing's parameters, the budget and the margin."""
        return {**super().parameters(), "depth_max": self.depth_max,
                "stroke_margin": self.stroke_margin}

    def transcription(self) -> MultipleShooting:
        """This variant's problem."""
        return min_energy_transcription(self.ground, self.stroke_margin > 0)

    def guess(self) -> Any:
        """Ipopt's default start (the problem is convex in the force)."""
        return None

    def accepts(self, neighbour: Any) -> bool:
        """Only a neighbour of this variant."""
        return isinstance(neighbour, MinEnergyLanding)

    def bound(self) -> float | None:
        """No depth bound (the budget is a constraint)."""
        return None

    def explain(self, err: Any, guess: Any) -> Exception:
        """Ipopt's verdict as it is."""
        return err

    def assemble(self, sol: Any, ref: Any, notes: list[str], path: str) -> MinEnergyLanding:
        """The two-phase result, with the energy (the objective) and the budget."""
        two = super().assemble(sol, ref, notes, path)
        src = ref if ref is not None else sol
        return MinEnergyLanding(**two.__dict__, energy=float(src.objective),
                                depth_max=self.depth_max, stroke_margin=self.stroke_margin)


def read_config(path: str) -> dict[str, float]:
    """``depth_max`` (and ``stroke_margin``) from a TOML file.

    Parameters
    ----------
    path : str
        The file, e.g. holding ``depth_max = 3.0``.

    Raises
    ------
    ParameterError
        An unreadable file, no ``depth_max``, or another key.
    """
    try:
        with open(path, "rb") as f:
            d = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ParameterError("--config", f"cannot read {path}: {err}") from None
    unknown = set(d) - {"depth_max", "stroke_margin"}
    if unknown or "depth_max" not in d:
        raise ParameterError("--config", f"{path} must hold depth_max (and may hold "
                             f"stroke_margin), got {sorted(d)}")
    return {k: float(v) for k, v in d.items()}


def solve_min_energy(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                     ground: Ground = LINEAR_GROUND, *, depth_max: float | None = None,
                     config: str | None = None, stroke_margin: float = 0.0,
                     refine: bool = True, warm_start: Any = None) -> MinEnergyLanding:
    """The landing of least ``∫u² dt`` with the final depth at most ``depth_max`` (given, or
    read from the TOML file ``config``), the leg ``stroke_margin`` inside its stroke.

    Parameters
    ----------
    impact, robot, ground
        The landing.
    depth_max : float, optional
        The depth budget (or give ``config``).
    config : str, optional
        A TOML file holding ``depth_max`` (and optionally ``stroke_margin``).
    stroke_margin : float
        The leg stays within ``[m, s - m]`` (0: the stroke itself).
    refine, warm_start
        As every variant's (a smooth optimum has no switching times to refine).

    Raises
    ------
    ParameterError
        Neither or both of ``depth_max`` and ``config``; a budget <= 0; a margin outside
        ``[0, s/2)``.
    """
    if (depth_max is None) == (config is None):
        raise ParameterError("--depth-max", "give the budget or a --config file holding "
                             "it" + (", not both" if config is not None else ""))
    if config is not None:
        read = read_config(config)
        depth_max, stroke_margin = read["depth_max"], read.get("stroke_margin", stroke_margin)
    assert depth_max is not None
    if not (math.isfinite(depth_max) and depth_max > 0):
        raise ParameterError("--depth-max", f"must be a depth > 0, got {depth_max:g}")
    if not 0 <= stroke_margin < robot.s / 2:
        raise ParameterError("--stroke-margin", f"must be in [0, s/2), got {stroke_margin:g}")
    warm = warm_start if isinstance(warm_start, MinEnergyLanding) else None
    variant = MinEnergy(robot, Impact.of(impact), ground, float(depth_max), float(stroke_margin))
    out = solve_phased(variant, warm, refine=refine)
    assert isinstance(out, MinEnergyLanding)
    return out


VARIANT = Variant(
    "min-energy", "the least actuator energy ∫u² dt landing within a depth budget",
    solve_min_energy, ground=True, objective=("energy", "energy ∫u² dt"),
    options=(Option("depth_max", float, help="the depth budget D", metavar="D"),
             Option("config", str, help="a TOML file with depth_max (and stroke_margin)",
                    metavar="FILE"),
             Option("stroke_margin", float, 0.0, help="the leg keeps this far from both "
                    "ends of its stroke", metavar="M")))
"""``softlanding solve --variant min_energy:VARIANT --depth-max D``."""

if __name__ == "__main__":
    bound = energy_bound(-3.0, PAPER_ROBOT.r_m)
    for d in (5.0, 3.5, 3.0):
        r = solve_min_energy(-3.0, depth_max=d)
        assert r.smooth is not None
        print(f"D = {d}: energy {r.energy:.12f} (bound 25/3 = {bound:.12f}, "
              f"{r.smooth.convergence}), depth {r.depth:.9f}, "
              f"{r.smooth.certificate.verdict}, verified: {not r.unverified_reasons()}")
