"""Robustness of the nominal controllers to model error (numbers for the paper's claim).

The paper argues that open-loop bang-bang force control is brittle and impedance
control robust, without numbers. Here both nominal controllers are designed for
the nominal model and then replayed, unchanged *in physical units*, on a robot
and ground that differ from the nominal:

* ``k_g`` -- the true ground stiffness is ``factor * k_g``;
* ``r_m`` -- the true mass ratio is ``factor * r_m`` at the same total mass;
* ``v0``  -- the true impact velocity is ``factor * v0``;
* ``switch`` -- (bang-bang only) the first switch comes ``factor`` times its
  nominal instant (late for ``factor > 1``), later instants unchanged.

"Unchanged in physical units" matters: the controller holds its newtons,
seconds, N/m and N s/m, while the dimensionless numbers (which are scaled by
``k_g`` and the masses) change. A stiffer ground makes the same schedule last
longer in ground time units and the same leg relatively softer. The conversion
goes through the value objects' ``to_si`` / ``from_si``, the same ones the CLI
uses, so there is one definition of the scaling.

The bang-bang schedule is replayed whole, as the optimiser defines it: the bang
arcs, the arrest force until the body would stop, then the body's nominal
weight. With an error in ``r_m``, ``v0`` or the switch the body is not stopped
when the hold starts, so it drifts into a stroke limit for ever: that is what
"open loop" means (the simulator proves the foot's rest and finds the stroke
range unbounded). The ground stiffness does not change the body's motion, so
there the body still stops. Depths are compared in physical units with the
same kind of controller designed for the true model (the *regret*).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from softlanding.errors import ParameterError, check, check_count
from softlanding.model.controllers import Controller, ForceSchedule, Impedance
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot, Units
from softlanding.simulation.kernel import FEAS_TOL
from softlanding.simulation.simulator import LandingResult, simulate
from softlanding.util.progress import progress as show_progress

PARAMETERS = ("k_g", "r_m", "v0", "switch")
CONTROLLERS = ("bang-bang", "impedance")
NOMINAL_UNITS = Units(m_t=1.0, k_g=1.0)
"""Any nominal robot will do: the results are scale-free."""


def true_model(robot: Robot, impact: Impact, parameter: str,
               factor: float) -> tuple[Robot, Impact, Units]:
    """The perturbed robot and impact in their own dimensionless units.

    Parameters
    ----------
    robot, impact : Robot, Impact
        The design model, in :data:`NOMINAL_UNITS`.
    parameter : {"k_g", "r_m", "v0", "switch"}
        What differs; ``"switch"`` leaves the model nominal.
    factor : float
        True value / nominal value (> 0).

    Returns
    -------
    (robot, impact, units)
        The true model and its units (the nominal robot's SI numbers, with the
        one perturbed, converted back).
    """
    factor = check("factor", factor)
    if parameter not in PARAMETERS:
        raise ParameterError("parameter", f"must be one of {', '.join(PARAMETERS)}, "
                                          f"got {parameter!r}")
    si = robot.to_si(NOMINAL_UNITS)
    m_t, k_g, V0 = NOMINAL_UNITS.m_t, NOMINAL_UNITS.k_g, impact.to_si(NOMINAL_UNITS)["V0"]
    m_b, m_f = si["m_b"], si["m_f"]
    if parameter == "k_g":
        k_g *= factor
    elif parameter == "r_m":
        r = robot.r_m * factor
        m_b, m_f = m_t * r / (1 + r), m_t / (1 + r)
    elif parameter == "v0":
        V0 *= factor
    true, units = Robot.from_si(m_b, m_f, si["stroke"], k_g, U_max=si["U_max"],  # type: ignore[arg-type]
                                rest_length=si["rest_length"], g=NOMINAL_UNITS.g)
    return true, Impact.from_si(V0, units), units


def transfer(controller: Controller, units: Units, true_units: Units) -> Controller:
    """The same controller, unchanged in SI units, in the true model's units.

    Parameters
    ----------
    controller : Impedance or ForceSchedule
        Designed in ``units``.
    units, true_units : Units
        The design model's and the true model's scales.
    """
    if isinstance(controller, Impedance):
        si = controller.to_si(units)
        return Impedance.from_si(si["K_p"], si["K_d"], true_units, si["rest_length"])
    if isinstance(controller, ForceSchedule):
        si = controller.to_si(units)
        return ForceSchedule.from_si(si["times_s"], si["forces_N"], true_units)
    return controller


def _shift_switch(schedule: ForceSchedule, factor: float) -> ForceSchedule:
    t = list(schedule.times)
    t[0] *= factor
    if len(t) > 1 and t[0] >= t[1]:
        raise ParameterError("factor", "moves the switch past the next switching instant")
    return ForceSchedule(tuple(t), schedule.values)


def replay(robot: Robot, impact: Impact, controller: Impedance | ForceSchedule,
           parameter: str, factor: float) -> tuple[LandingResult, float]:
    """Replay a nominal controller, unchanged in SI units, on the perturbed model.

    Parameters
    ----------
    robot, impact : Robot, Impact
        The nominal model.
    controller : Impedance or ForceSchedule
        The nominal controller.
    parameter : {"k_g", "r_m", "v0", "switch"}
        What differs.
    factor : float
        True value / nominal value.

    Returns
    -------
    (LandingResult, float)
        The landing (in the true model's units) and the factor that turns its
        lengths into nominal units.
    """
    if parameter == "switch":
        if not isinstance(controller, ForceSchedule):
            raise ParameterError("parameter", "an impedance has no switch to move")
        return simulate(robot, impact, _shift_switch(controller, factor)), 1.0
    true, true_impact, units = true_model(robot, impact, parameter, factor)
    res = simulate(true, true_impact, transfer(controller, NOMINAL_UNITS, units))
    return res, units.length / NOMINAL_UNITS.length


def design(impact: Impact | float, robot: Robot = PAPER_ROBOT, margin: float = 0.0,
           grid: int = 101, controllers: tuple[str, ...] = CONTROLLERS,
           warm_start: Any = None) -> dict[str, tuple[Controller, float, Any]]:
    """Depth-optimal controllers designed for the stroke ``(1 - margin) s``.

    The design stroke is centred on the true one (the leg starts at the middle
    in both), so a margin leaves ``margin * s / 2`` free at each end and the
    landing on the true stroke is the design landing.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot (its force limit bounds the bang-bang force; the impedance is
        unsaturated, as in the paper's comparison).
    margin : float
        Stroke safety margin, in [0, 1).
    grid : int
        Starting grid of the impedance optimisation.
    controllers : tuple of str
        Which to design.
    warm_start : ocp.Solution, optional
        Warm start of the bang-bang design.

    Returns
    -------
    dict
        ``{name: (controller, depth, solution)}``; ``solution`` warm-starts the
        next bang-bang design.
    """
    from softlanding.optimal.landing import solve_landing
    from softlanding.studies.impedance import optimize_impedance

    if not 0.0 <= margin < 1.0:
        raise ParameterError("margin", f"must be in [0, 1), got {margin}")
    designed = robot.replace(s=(1.0 - margin) * robot.s, l0=None)
    out: dict[str, tuple[Controller, float, Any]] = {}
    if "bang-bang" in controllers:
        bb = solve_landing(impact, designed, replay=False, warm_start=warm_start)
        out["bang-bang"] = (bb.schedule(), bb.depth, bb.transcribed)
    if "impedance" in controllers:
        imp = optimize_impedance(impact, designed.without_force_limit(), grid=grid)
        out["impedance"] = (Impedance(imp.k_p, imp.k_d), imp.depth, None)
    return out


def robustness_study(impact: Impact | float = -3.0, robot: Robot = PAPER_ROBOT, *,
                     spread: float = 0.3, n: int = 13, margins: tuple[float, ...] = (0.0, 0.1),
                     grid: int = 101, progress: bool | None = False) -> xr.Dataset:
    """Depth penalty and stroke violations of the nominal controllers under model error.

    Each nominal controller is replayed on the perturbed model and compared with the
    controller of the same kind (and margin) designed for that model: the *regret*
    ``depth_ratio = replayed depth / redesigned depth`` is what the model error costs.

    Parameters
    ----------
    impact : Impact or float
        Nominal impact velocity.
    robot : Robot
        Nominal robot (its ``u_max`` bounds the bang-bang force; the impedance is
        unsaturated, as in the paper's comparison).
    spread : float
        Largest relative error: factors run over ``1 +- spread``.
    n : int
        Number of factors (odd, so that 1 is one of them).
    margins : tuple of float
        Stroke safety margins the controllers are designed with (the paper's
        remedy for optima that sit on the stroke limit).
    grid : int
        Starting grid of the impedance optimisation.
    progress : bool, optional
        Show a progress bar.

    Returns
    -------
    xarray.Dataset
        Dims ``(controller, margin, parameter, factor)``; variables
        ``depth_ratio`` (regret, see above), ``depth_change`` (replayed depth /
        nominal depth, in physical units), ``violation`` (largest excursion
        beyond a stroke limit as a fraction of the stroke: 0 when kept, inf
        when the body never stops relative to the foot), ``stroke_kept``,
        ``rest_proven`` (the foot's rest is proven), and
        ``nominal_depth`` (dims ``controller, margin``, units of ``x_s``).
        Entries that do not apply (moving an impedance's switch) are NaN.
    """
    impact = Impact.of(impact)
    factors = _factors(spread, n)
    n = factors.size
    shape = (len(CONTROLLERS), len(margins), len(PARAMETERS), n)
    var = {k: np.full(shape, np.nan) for k in ("depth_ratio", "depth_change", "violation")}
    kept = np.zeros(shape, dtype=bool)
    proven = np.zeros(shape, dtype=bool)
    nominal_depth = np.full(shape[:2], np.nan)
    tasks = [(j, m, k, par) for j, m in enumerate(margins) for k, par in enumerate(PARAMETERS)]
    designs: dict[float, dict] = {}
    for j, m, k, par in show_progress(tasks, progress, "robustness", "study"):
        if m not in designs:
            designs[m] = design(impact, robot, margin=m, grid=grid)
            for i, name in enumerate(CONTROLLERS):
                nominal_depth[i, j] = designs[m][name][1]
        warm = designs[m]["bang-bang"][2]
        for q, f in enumerate(factors):
            oracle, warm = _redesigned(robot, impact, par, float(f), m, grid, designs[m], warm)
            for i, name in enumerate(CONTROLLERS):
                cell = _replayed(robot, impact, designs[m][name][0], name, par, float(f))
                if cell is None:
                    continue
                res, lr, over = cell
                var["depth_ratio"][i, j, k, q] = res.depth / oracle[name]
                var["depth_change"][i, j, k, q] = res.depth * lr / nominal_depth[i, j]
                var["violation"][i, j, k, q] = over
                kept[i, j, k, q] = over <= FEAS_TOL
                proven[i, j, k, q] = res.rest_proven
    dims = ("controller", "margin", "parameter", "factor")
    ds = xr.Dataset(
        {**{k: (dims, v) for k, v in var.items()},
         "stroke_kept": (dims, kept), "rest_proven": (dims, proven),
         "nominal_depth": (dims[:2], nominal_depth)},
        coords={"controller": list(CONTROLLERS), "margin": np.asarray(margins, float),
                "parameter": list(PARAMETERS), "factor": factors})
    ds.attrs.update(v0=impact.v0, r_m=robot.r_m, s=robot.s,
                    u_max=-1.0 if robot.u_max is None else robot.u_max, spread=spread,
                    title="nominal controllers replayed on a perturbed model")
    return ds


def _factors(spread: float, n: int) -> np.ndarray:
    """``n`` factors over ``1 +- spread``, 1 exactly in the middle."""
    if not 0.0 < spread < 1.0:
        raise ParameterError("spread", f"must be in (0, 1), got {spread}")
    n = check_count("n", n, 3, 1001)
    if n % 2 == 0:
        raise ParameterError("n", f"must be odd (so 1 is a factor), got {n}")
    factors = np.linspace(1.0 - spread, 1.0 + spread, n)
    factors[n // 2] = 1.0
    return factors


def _redesigned(robot: Robot, impact: Impact, par: str, f: float, margin: float, grid: int,
                nominal: dict, warm: Any) -> tuple[dict[str, float], Any]:
    """Depth of each kind of controller designed for the true model (the regret's oracle)."""
    if par == "switch":
        return {name: nominal[name][1] for name in CONTROLLERS}, warm
    true, true_impact, _ = true_model(robot, impact, par, f)
    redesign = design(true_impact, true, margin=margin, grid=grid, warm_start=warm)
    return {name: redesign[name][1] for name in CONTROLLERS}, redesign["bang-bang"][2]


def _replayed(robot: Robot, impact: Impact, controller: Controller, name: str, par: str,
              f: float) -> tuple[LandingResult, float, float] | None:
    """The nominal controller on the true model: landing, length ratio, stroke excursion."""
    if par == "switch" and isinstance(controller, Impedance):
        return None
    # the impedance is unsaturated, as designed (the paper's comparison)
    rob = robot if name == "bang-bang" else robot.without_force_limit()
    res, lr = replay(rob, impact, controller, par, f)  # type: ignore[arg-type]
    s_true = res.robot.s
    # an open-loop body that is not stopped drifts for ever: its exact stroke range is
    # unbounded (inf)
    over = max(0.0, -res.stroke_min, res.stroke_max - s_true) / s_true
    return res, lr, over


def robustness_table(ds: xr.Dataset) -> list[dict]:
    """One row per (controller, margin, parameter): regret range and stroke violations.

    Parameters
    ----------
    ds : xarray.Dataset
        From :func:`robustness_study`.
    """
    rows = []
    for c in ds.controller.values:
        for m in ds.margin.values:
            for p in ds.parameter.values:
                d = ds.sel(controller=c, margin=m, parameter=p)
                ok = np.isfinite(d.depth_ratio.values)
                if not ok.any():
                    continue
                viol = ok & ~d.stroke_kept.values
                drift = ok & np.isinf(d.violation.values)
                finite = d.violation.values[ok & np.isfinite(d.violation.values)]
                rows.append({
                    "controller": str(c), "margin": float(m), "parameter": str(p),
                    "nominal_depth": float(ds.nominal_depth.sel(controller=c, margin=m)),
                    "worst_depth_ratio": float(np.nanmax(d.depth_ratio)),
                    "cases": int(ok.sum()), "violations": int(viol.sum()),
                    "body_never_stops": int(drift.sum()),
                    "largest_violation": float(finite.max()) if finite.size else 0.0,
                    "violating_factors": [round(float(x), 6) for x in d.factor.values[viol]],
                })
    return rows


__all__ = ["CONTROLLERS", "PARAMETERS", "design", "replay", "robustness_study",
           "robustness_table", "transfer", "true_model"]
