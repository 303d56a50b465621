"""``softlanding mpc``: a landing under closed-loop control on a ground the robot does not know.

Every option is checked before the controllers are imported (they load numba's compiled
code and CasADi: a bad option is refused in a fraction of that time).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import Any

from softlanding.cli.ground import ground_text, model_ground
from softlanding.cli.output import (
    EXIT_FAILURE,
    EXIT_OK,
    ground_of_args,
    print_json,
    print_table,
    robot_of,
    savefig,
    target,
)
from softlanding.control.options import DEFAULT_PERIOD, check_noise, check_period
from softlanding.errors import ParameterError, check, check_count
from softlanding.model.robot import Impact

#: The landing's numbers ``--json`` prints (from :meth:`MPCLanding.to_dict`).
REPORTED = ("failure", "stroke_held", "force_held", "rest_proven", "stroke_min", "stroke_max",
            "u_peak", "period", "period_rig_ms", "controller", "uncovered", "deferred",
            "creep_samples", "step_work_max", "noise", "delay", "seed", "margin", "estimator",
            "samples", "steps", "replans", "fallbacks", "step_time_median_ms",
            "step_time_p99_ms", "step_time_max_ms", "step_cpu_median_ms", "step_cpu_p99_ms",
            "step_cpu_max_ms", "prepare_time_s", "setup_ms", "estimate", "ground",
            "model_ground")


@dataclass(frozen=True)
class MPCOptions:
    """``softlanding mpc``'s options, checked.

    Attributes
    ----------
    robot, impact, ground, model : Robot, Impact, ground, ground
        The robot, its impact, the true ground and the controller's model of it.
    plot : Path or None
        The figure's file.
    period, noise : float
        Sample period and the sensor's noise (standard deviation).
    delay, seed : int
        Samples of delay and the noise's seed.
    margin : float
        The compiled controller's margin on the ground estimate (standard deviations).
    """

    robot: Any
    impact: Impact
    ground: Any
    model: Any
    plot: Any
    period: float
    noise: float
    delay: int
    seed: int
    margin: float


def mpc_options(a: argparse.Namespace) -> MPCOptions:
    """The options checked, each refused with its own name (no controller imported yet).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.

    Raises
    ------
    ParameterError
        A bad option.
    """
    period = DEFAULT_PERIOD if a.period is None else check_period("--period", a.period)
    noise = check_noise("--noise-std", a.noise_std)
    delay = check_count("--delay", a.delay, 0, 1000)
    seed = check_count("--seed", a.seed, 0, 2**63 - 1)
    margin = check("--margin", a.margin, (lambda v: v >= 0, "must be >= 0"))
    if a.margin and a.controller != "bangbang":
        raise ParameterError("--margin", "applies to --controller bangbang")
    if a.estimator is not None and not noise:
        raise ParameterError("--estimator", "applies with --noise-std > 0 (exact "
                                            "measurements need no filter)")
    robot, impact, ground, plot = robot_of(a), Impact(a.v0), ground_of_args(a), target(a)
    model = model_ground(a)
    from softlanding.optimal.limits import force_limit

    force_limit(robot)
    if not impact.v0 < 0:
        raise ParameterError("v0", "a landing under control needs v0 < 0")
    return MPCOptions(robot, impact, ground, model, plot, period, noise, delay, seed, margin)


def mpc_command(a: argparse.Namespace) -> int:
    """Run ``softlanding mpc`` (the parsed arguments; the exit code).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    o = mpc_options(a)
    from softlanding.control.mpc import mpc_landing
    from softlanding.optimal.landing import solve_landing
    from softlanding.simulation.simulator import simulate

    m = mpc_landing(o.impact, o.robot, o.ground, model=o.model, period=o.period,
                    estimate=not a.no_estimate, controller=a.controller, noise=o.noise,
                    delay=o.delay, seed=o.seed, margin=o.margin,
                    estimator=a.estimator or "filtered")
    clair = solve_landing(o.impact, o.robot, o.ground)
    ol = simulate(o.robot, o.impact, solve_landing(o.impact, o.robot, o.model).schedule(),
                  o.ground)
    d = m.to_dict()
    out = {"depth": m.depth, "clairvoyant_depth": clair.depth,
           "ratio_to_clairvoyant": m.depth / clair.depth,
           "clairvoyant_verified": not clair.unverified_reasons(),
           "open_loop_depth": ol.depth, "open_loop_feasible": ol.feasible,
           "open_loop_status": ol.status, "feasible": m.feasible,
           **{k: d[k] for k in REPORTED}}
    written = None
    if o.plot:
        from softlanding.plots.control import plot_mpc_landing

        written = savefig(plot_mpc_landing(m, clair.replay, ol), o.plot)
    if a.json:
        print_json(out)
    else:
        print_table(_rows(m, out, clair.depth, ol))
        if written:
            print(f"figure written to {written}")
    if not m.feasible:
        print(f"softlanding: mpc: the landing is not feasible: {m.failure()}", file=sys.stderr)
    return EXIT_OK if m.feasible else EXIT_FAILURE


def _ms(v: float | None) -> str:
    return "none" if v is None else f"{v:.3g}"


def _rows(m: Any, out: dict[str, Any], clair: float, ol: Any) -> list[tuple[str, object]]:
    """The table's rows."""
    e = out["estimate"] or {}
    return [
        ("controller", m.controller),
        ("true ground", ground_text(m.ground)), ("model ground", ground_text(m.model)),
        ("depth (MPC)", m.depth), ("clairvoyant depth", clair),
        ("MPC / clairvoyant", out["ratio_to_clairvoyant"]),
        ("clairvoyant verified", out["clairvoyant_verified"]),
        ("open-loop depth (nominal plan)", ol.depth),
        ("open-loop feasible", ol.feasible), ("feasible (MPC)", m.feasible),
        ("stroke min .. max", f"{m.stroke_min:.6g} .. {m.stroke_max:.6g}"),
        ("peak |u|", m.u_peak),
        ("samples (period)", f"{m.samples} ({m.period:g} = {out['period_rig_ms']:.3g} ms "
                             f"on the paper's rig)"),
        ("re-plans by transcription", m.replans), ("fallbacks", m.fallbacks),
        ("samples not covered (bangbang)", m.uncovered),
        ("samples deferred (bangbang)", m.deferred),
        ("samples under the creep law", m.creep_samples),
        ("noise std, delay (samples)", f"{m.noise:g}, {m.delay}"
                                       + (", filtered estimate" if m.estimator == "filtered"
                                          else "")),
        ("step time median / p99 / max [ms]",
         " / ".join(_ms(out[f"step_time_{q}_ms"]) for q in ("median", "p99", "max"))),
        ("step CPU median / p99 / max [ms]",
         " / ".join(_ms(out[f"step_cpu_{q}_ms"]) for q in ("median", "p99", "max"))),
        ("preparation before impact [s]", f"{m.prepare_time_s:.3g}"),
        ("estimate K, c_d", f"{e.get('stiffness', float('nan')):.6g}, "
                            f"{e.get('c_d', float('nan')):.6g}")]


__all__ = ["MPCOptions", "mpc_command", "mpc_options"]
