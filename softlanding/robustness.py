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
goes through :class:`~softlanding.scaling.PhysicalParams`, the same one the CLI
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

from dataclasses import replace

import numpy as np
import xarray as xr

from ._kernel import FEAS_TOL
from ._progress import progress as show_progress
from .errors import ParameterError, check_positive
from .scaling import DimensionlessParams
from .simulate import ForceSchedule, Impedance, LandingResult, simulate

PARAMETERS = ("k_g", "r_m", "v0", "switch")
CONTROLLERS = ("bang-bang", "impedance")
_PHYS = {"m_t": 1.0, "k_g": 1.0}  # any nominal robot: the results are scale-free


def true_model(nominal: DimensionlessParams, parameter: str,
               factor: float) -> tuple[DimensionlessParams, float, float]:
    """The perturbed robot in its own dimensionless units, with the nominal's SI gains.

    Parameters
    ----------
    nominal : DimensionlessParams
        The design model; its ``k_p, k_d`` (if given) are held in N/m and N s/m.
    parameter : {"k_g", "r_m", "v0", "switch"}
        What differs; ``"switch"`` leaves the model nominal.
    factor : float
        True value / nominal value (> 0).

    Returns
    -------
    (params, length_ratio, time_ratio)
        The true dimensionless parameters (gains converted), the true length
        unit over the nominal one, and the true time unit over the nominal one.
    """
    check_positive("factor", factor)
    if parameter not in PARAMETERS:
        raise ParameterError("parameter", f"must be one of {PARAMETERS}, got {parameter!r}")
    nom = nominal.to_physical(**_PHYS)
    ph = nom
    if parameter == "k_g":
        ph = replace(nom, k_g=nom.k_g * factor)
    elif parameter == "r_m":
        r = nominal.r_m * factor
        ph = replace(nom, m_b=nom.m_t * r / (1 + r), m_f=nom.m_t / (1 + r))
    elif parameter == "v0":
        ph = replace(nom, v0=nom.v0 * factor)
    return (ph.to_dimensionless(), ph.length_scale / nom.length_scale,
            ph.time_scale / nom.time_scale)


def _shift_switch(times: np.ndarray, factor: float) -> np.ndarray:
    t = times.copy()
    t[0] *= factor
    if len(t) > 1 and t[0] >= t[1]:
        raise ParameterError("factor", "moves the switch past the next switching instant")
    return t


def replay(nominal: DimensionlessParams, policy: Impedance | ForceSchedule, parameter: str,
           factor: float) -> tuple[LandingResult, float]:
    """Replay a nominal controller, unchanged in SI units, on the perturbed model.

    Returns the landing (in the true model's units) and the factor that turns
    its lengths into nominal units.
    """
    if isinstance(policy, Impedance):
        if parameter == "switch":
            raise ParameterError("parameter", "an impedance has no switch to move")
        true, lr, _ = true_model(replace(nominal, k_p=policy.k_p, k_d=policy.k_d),
                                 parameter, factor)
        return simulate(true, Impedance(true.k_p, true.k_d, policy.u_max)), lr
    times = np.asarray(policy.times, float)
    if parameter == "switch":
        times = _shift_switch(times, factor)
        factor = 1.0
    true, lr, tr = true_model(nominal, parameter, factor)
    # the total mass never changes, so forces (units of m_t g) keep their values
    return simulate(true, ForceSchedule(tuple(times / tr), policy.values)), lr


def design(v0: float, r_m: float = 5.0, s: float = 20.0, u_max: float = 8.2, margin: float = 0.0,
           grid: int = 101, controllers: tuple[str, ...] = CONTROLLERS,
           warm_start=None) -> dict[str, tuple[Impedance | ForceSchedule, float, object]]:
    """Depth-optimal controllers designed for the stroke ``(1 - margin) s``.

    The design stroke is centred on the true one (the leg starts at ``s/2`` in
    both), so a margin leaves ``margin * s / 2`` free at each end and the landing
    on the true stroke is the design landing. Returns ``{name: (policy, depth,
    solution)}``; ``solution`` warm-starts the next bang-bang design.
    """
    from .impedance import optimize_impedance
    from .landing import solve_landing

    if not 0.0 <= margin < 1.0:
        raise ParameterError("margin", f"must be in [0, 1), got {margin}")
    s_d = (1.0 - margin) * s
    out = {}
    if "bang-bang" in controllers:
        bb = solve_landing(v0, r_m, s_d, u_max, replay=False, warm_start=warm_start)
        out["bang-bang"] = (bb.schedule(), bb.depth, bb.transcribed)
    if "impedance" in controllers:
        imp = optimize_impedance(v0, r_m, s_d, grid=grid)
        out["impedance"] = (Impedance(imp.kp, imp.kd), imp.depth, None)
    return out


def robustness_study(v0: float = -3.0, r_m: float = 5.0, s: float = 20.0, u_max: float = 8.2,
                     *, spread: float = 0.3, n: int = 13, margins: tuple[float, ...] = (0.0, 0.1),
                     grid: int = 101, progress: bool = False) -> xr.Dataset:
    """Depth penalty and stroke violations of the nominal controllers under model error.

    Each nominal controller is replayed on the perturbed model and compared with
    the controller of the same kind (and margin) designed for that model: the
    *regret* ``depth_ratio = replayed depth / redesigned depth`` is what the
    model error costs, apart from the change that any controller would see (a
    softer ground or a faster impact sinks deeper whatever the control).

    Parameters
    ----------
    v0, r_m, s, u_max : float
        Nominal model (``u_max`` bounds the bang-bang force; the impedance is
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
    progress : bool
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
    if not 0.0 < spread < 1.0:
        raise ParameterError("spread", f"must be in (0, 1), got {spread}")
    if n < 3 or n % 2 == 0:
        raise ParameterError("n", f"must be odd and >= 3 (so 1 is a factor), got {n}")
    nominal = DimensionlessParams(r_m=r_m, s=s, v0=v0)
    factors = np.linspace(1.0 - spread, 1.0 + spread, n)
    factors[n // 2] = 1.0
    shape = (len(CONTROLLERS), len(margins), len(PARAMETERS), n)
    var = {k: np.full(shape, np.nan) for k in ("depth_ratio", "depth_change", "violation")}
    kept = np.zeros(shape, dtype=bool)
    proven = np.zeros(shape, dtype=bool)
    nominal_depth = np.full(shape[:2], np.nan)
    tasks = [(j, m, k, par) for j, m in enumerate(margins) for k, par in enumerate(PARAMETERS)]
    designs = {}
    for j, m, k, par in show_progress(tasks, progress, "robustness", "study"):
        if m not in designs:
            designs[m] = design(v0, r_m, s, u_max, margin=m, grid=grid)
            for i, name in enumerate(CONTROLLERS):
                nominal_depth[i, j] = designs[m][name][1]
        warm = designs[m]["bang-bang"][2]
        for q, f in enumerate(factors):
            if par == "switch":
                oracle = {name: designs[m][name][1] for name in CONTROLLERS}
            else:
                true, _, _ = true_model(nominal, par, float(f))
                redesign = design(true.v0, true.r_m, true.s, u_max, margin=m, grid=grid,
                                  warm_start=warm)
                warm = redesign["bang-bang"][2]
                oracle = {name: redesign[name][1] for name in CONTROLLERS}
            for i, name in enumerate(CONTROLLERS):
                pol = designs[m][name][0]
                if par == "switch" and isinstance(pol, Impedance):
                    continue
                res, lr = replay(nominal, pol, par, float(f))
                s_true = res.params.s
                # an open-loop body that is not stopped drifts for ever: its
                # exact stroke range is unbounded (inf)
                over = max(0.0, -res.stroke_min, res.stroke_max - s_true) / s_true
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
    ds.attrs.update(v0=v0, r_m=r_m, s=s, u_max=u_max, spread=spread,
                    title="nominal controllers replayed on a perturbed model")
    return ds


def robustness_table(ds: xr.Dataset) -> list[dict]:
    """One row per (controller, margin, parameter): regret range and stroke violations."""
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
