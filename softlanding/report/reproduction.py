"""Reproduce the paper end to end: every figure, the headline numbers, a robustness study.

:func:`reproduce` writes, into one folder, each figure of the paper as PNG and
PDF, ``summary.json`` (every headline number, machine-readable), ``summary.md``
(the same as tables, with the paper's values beside ours where it gives them)
and the computed datasets as netCDF under ``data/``. ``quick=True`` uses
coarser grids and fewer impact velocities (about a minute on 2 cores); the
numbers it reports are still exact for the grids it uses, and each of them is
what the public API returns for the same arguments (the test suite checks).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Impact
from softlanding.report.summary import summary_markdown
from softlanding.util.files import atomic_folder
from softlanding.util.jsonable import json_safe

BANG_BANG_V0 = -3.0
"""Impact velocity of the paper's bang-bang example figure."""

#: Impact velocities of the paper's experiments: up to v0 = -4.8 (1.2 m/s), here in thirds.
EXPERIMENT_V0 = (-1.6, -3.2, -4.8)
EXPERIMENT_KP = (0.2, 0.5, 0.9)
STEP_MAP_V0 = (-0.5, -1.0, -2.0, -4.0, -6.0, -10.0)
DEPTH_MAP_V0 = (-1.0, -3.0, -5.0, -10.0)
FAMILIES = ((2.0, 5.0, 10.0), (10.0, 20.0, 40.0))


@dataclass(frozen=True)
class Settings:
    """Grid sizes of one reproduction run.

    Parameters
    ----------
    quick : bool
        The quick run.
    map_n, optimizer_grid : int
        Points per axis of the depth maps and of the optimiser's starting grid.
    curve_v0, compare_v0, cot_v0 : tuple of float
        Impact velocities of the optimal-gain curves, the comparison and the CoT study.
    experiment_kd_n : int
        Damping values of the experiment curves.
    robustness_n : int
        Factors of the robustness study.
    """

    quick: bool
    map_n: int
    optimizer_grid: int
    curve_v0: tuple[float, ...]
    compare_v0: tuple[float, ...]
    cot_v0: tuple[float, ...]
    experiment_kd_n: int
    robustness_n: int

    @classmethod
    def make(cls, quick: bool) -> Settings:
        if quick:
            return cls(True, 41, 41, _grid(0.0, -10.0, 6), _grid(0.0, -10.0, 6),
                       _grid(-1.0, -10.0, 5), 51, 5)
        return cls(False, 101, 101, _grid(0.0, -10.0, 41), _grid(0.0, -10.0, 21),
                   _grid(-0.5, -10.0, 20), 251, 13)


def _grid(a: float, b: float, n: int) -> tuple[float, ...]:
    return tuple(float(x) for x in np.round(np.linspace(a, b, n), 12))


def _save(fig, out: Path, stem: str, files: list[str]) -> None:
    import matplotlib.pyplot as plt

    for ext in ("png", "pdf"):
        path = out / f"{stem}.{ext}"
        fig.savefig(path, dpi=130, bbox_inches="tight")
        files.append(path.name)
    plt.close(fig)


# ------------------------------------------------------------------ sections
def bang_bang_example(out: Path, files: list[str]) -> dict:
    """[fig:ex_bb_traj] the optimal landing at v0 = -3, with its PMP certificate."""
    from ocp import certify
    from softlanding.optimal.landing import solve_landing
    from softlanding.plots.paper import plot_bang_bang

    res = solve_landing(BANG_BANG_V0, PAPER_ROBOT)
    assert res.transcribed is not None  # a cold solve always transcribes
    cert = certify(res.transcribed, res.refined)
    _save(plot_bang_bang(res), out, "fig_bang_bang_trajectory", files)
    return {"v0": BANG_BANG_V0, **PAPER_ROBOT.to_dict(), "depth": res.depth,
            "T": res.T, "body_stops_at": res.schedule().times[-1], "arcs": res.arcs,
            "switch_times": res.switch_times, "u_b": res.u_b,
            "arrest_active": res.arrest_active, "replay_difference": res.replay_difference,
            "pmp_verdict": cert.verdict, "pmp_H_max_abs": cert.H_max_abs,
            "pmp_switch_sigma_gap": cert.switch_sigma_gap}


def _maps(v0s, st: Settings, cache: dict) -> list:
    """Depth maps of the paper's robot, each v0 simulated once per run."""
    from softlanding.studies.sweeps import depth_map

    for v in v0s:
        if v not in cache:
            cache[v] = depth_map(v, PAPER_IMPEDANCE_ROBOT, n=st.map_n, energy=False)
    return [cache[v] for v in v0s]


def stepped_intrusions(out: Path, files: list[str], st: Settings, cache: dict) -> dict:
    """[fig:multi_intrusion_regions] three stepped trajectories and step-count maps."""
    from softlanding.model.controllers import Impedance
    from softlanding.plots.paper import plot_stepped_intrusion_figure
    from softlanding.simulation.simulator import simulate

    runs = [simulate(PAPER_IMPEDANCE_ROBOT, Impact(-1.0), Impedance(0.2, kd))
            for kd in (0.4, 0.18, 0.0)]
    maps = _maps(STEP_MAP_V0, st, cache)
    _save(plot_stepped_intrusion_figure(runs, maps), out, "fig_stepped_intrusions", files)
    regions = []
    for ds in maps:
        steps = ds.steps.values
        feas = ds.strictly_feasible.values
        rest = ds.status.values == 0
        regions.append({"v0": float(ds.v0), "multi_step_fraction": float((steps > 1).mean()),
                        "multi_step_feasible_fraction": float(((steps > 1) & feas).mean()),
                        "max_steps_rest_proven": int(steps[rest].max()),
                        "rest_unproven_fraction": float((~rest).mean())})
    return {"trajectories": [{"k_p": 0.2, "k_d": r.controller.to_dict()["k_d"], "v0": -1.0,
                              "steps": r.steps,
                              "depth": r.depth} for r in runs],
            "paper_steps": [1, 2, 3], "regions": regions}


def depth_maps(out: Path, files: list[str], st: Settings, cache: dict) -> list[dict]:
    """[fig:Kp_Kd_grid] normalised depth maps with the optimum starred."""
    from softlanding.plots.paper import plot_depth_maps
    from softlanding.studies.impedance import optimize_impedance

    maps = _maps(DEPTH_MAP_V0, st, cache)
    optima = [optimize_impedance(v, PAPER_IMPEDANCE_ROBOT, grid=st.optimizer_grid)
              for v in DEPTH_MAP_V0]
    _save(plot_depth_maps(maps, optima), out, "fig_depth_maps", files)
    return [{"v0": o.v0, "k_p": o.k_p, "k_d": o.k_d, "depth": o.depth, "steps": o.steps,
             "on_stroke_boundary": o.on_stroke_boundary, "active_constraint": o.active_constraint,
             "grid_best": o.grid_best} for o in optima]


def optimal_gains(out: Path, files: list[str], st: Settings,
                  progress: bool) -> tuple[dict, Callable[[float], Any]]:
    """[fig:opt_imp_vary_rm_S] optimal gains against v0 for a family of (r_m, s)."""
    from softlanding.plots.paper import plot_gain_families
    from softlanding.studies.sweeps import (
        optimal_impedance_curves,
        paper_observations,
        save_dataset,
    )

    curves = optimal_impedance_curves(st.curve_v0, PAPER_IMPEDANCE_ROBOT, r_m=FAMILIES[0],
                                      s=FAMILIES[1], grid=st.optimizer_grid, progress=progress)
    (out / "data").mkdir(exist_ok=True)
    save_dataset(curves, out / "data" / "optimal_gains.nc")
    files.append("data/optimal_gains.nc")
    _save(plot_gain_families(curves), out, "fig_optimal_gains", files)
    nominal = curves.sel(r_m=PAPER_ROBOT.r_m, s=PAPER_ROBOT.s)
    infeasible = [{"r_m": float(r), "s": float(s), "v0": float(v)}
                  for r in curves.r_m.values for s in curves.s.values for v in curves.v0.values
                  if not bool(curves.feasible.sel(r_m=r, s=s, v0=v))]
    return ({"observations_r5_s20": paper_observations(curves, PAPER_IMPEDANCE_ROBOT),
             "curve_r5_s20": [{"v0": float(v), "k_p": float(nominal.k_p.sel(v0=v)),
                               "k_d": float(nominal.k_d.sel(v0=v)),
                               "depth": float(nominal.depth.sel(v0=v))}
                              for v in nominal.v0.values],
             "no_feasible_gains": infeasible}, _optimum_lookup(nominal, st.optimizer_grid))


def _optimum_lookup(nominal, grid: int) -> Callable[[float], Any]:
    """``v0 -> depth-optimal impedance`` of the paper's robot, reusing the curves' optima
    (the same :func:`optimize_impedance` call) and computing the others."""
    from types import SimpleNamespace

    from softlanding.studies.impedance import optimize_impedance

    index = {float(v): i for i, v in enumerate(nominal.v0.values)}

    def get(v0: float):
        i = index.get(float(v0))
        if i is None or not bool(nominal.feasible[i]):
            return optimize_impedance(v0, PAPER_IMPEDANCE_ROBOT, grid=grid)
        row = nominal.isel(v0=i)
        return SimpleNamespace(**{k: float(row[k]) for k in
                                  ("k_p", "k_d", "depth", "u_peak", "cot", "cot_lossless")})

    return get


def comparison(out: Path, files: list[str], st: Settings, progress: bool,
               depth_optimum: Callable[[float], Any]) -> dict:
    """[fig:imp_vs_bb_vs_rigid] rigid vs optimal impedance vs bang-bang."""
    from softlanding.plots.paper import plot_controller_comparison
    from softlanding.studies.comparison import compare_controllers, comparison_arrays

    rows = compare_controllers(st.compare_v0, PAPER_ROBOT, grid=st.optimizer_grid,
                               progress=progress, impedance_optimum=depth_optimum)
    cols = comparison_arrays(rows)
    _save(plot_controller_comparison(cols, PAPER_ROBOT), out, "fig_depth_vs_velocity", files)
    moving = cols["v0"] < 0
    fastest = int(np.argmin(cols["v0"]))
    return {"rows": rows, "u_max": PAPER_ROBOT.u_max,
            "bang_bang_over_rigid": [float(x) for x in _range(cols["bang_bang"] / cols["rigid"])],
            "impedance_over_rigid": [float(x) for x in _range(cols["impedance"] / cols["rigid"])],
            "bang_bang_below_impedance_everywhere": bool(np.all(
                cols["bang_bang"][moving] < cols["impedance"][moving])),
            "impedance_u_peak_at_fastest": float(cols["impedance_u_peak"][fastest]),
            "fastest_v0": float(cols["v0"][fastest]), "paper_u_max": PAPER_ROBOT.u_max}


def _range(x: np.ndarray) -> tuple[float, float]:
    return float(np.min(x)), float(np.max(x))


def experiment(out: Path, files: list[str], st: Settings) -> list[dict]:
    """[fig:nd_exp_results] simulated depth against k_d, dimensionless and for the paper's rig."""
    from softlanding.model.scaling import paper_rig
    from softlanding.plots.paper import plot_experiment_curves
    from softlanding.studies.sweeps import impedance_dataset

    kd = np.round(np.linspace(0.0, 2.5, st.experiment_kd_n), 12)
    ds = impedance_dataset(EXPERIMENT_V0, EXPERIMENT_KP, kd, PAPER_IMPEDANCE_ROBOT, energy=False)
    ds = ds.squeeze(("r_m", "s")).transpose("k_p", "v0", "k_d")
    _save(plot_experiment_curves(ds), out, "fig_experiment", files)
    rig = paper_rig()
    _save(plot_experiment_curves(ds, si=rig), out, "fig_experiment_si", files)
    units = rig.units
    rows = []
    for kp in EXPERIMENT_KP:
        for v in EXPERIMENT_V0:
            c = ds.sel(k_p=kp, v0=v)
            ok = c.strictly_feasible.values
            d = np.where(ok, c.depth.values, np.nan)
            best = int(np.nanargmin(d)) if ok.any() else None
            rows.append({
                "k_p": kp, "v0": v, "speed_m_per_s": abs(v) * units.velocity,
                "feasible_fraction": float(ok.mean()),
                "best_k_d": None if best is None else float(kd[best]),
                "best_depth": None if best is None else float(d[best]),
                "best_depth_mm": None if best is None else float(d[best] * units.length * 1e3),
                "depth_at_k_d_0": float(c.depth.values[0])})
    return rows


def cost_of_transport(out: Path, files: list[str], st: Settings, progress: bool,
                      depth_optimum: Callable[[float], Any]) -> list[dict]:
    """[fig:CoT_opt_imp] minimum-CoT against minimum-depth impedance."""
    from softlanding.model.controllers import Rigid
    from softlanding.plots.paper import plot_cot_comparison
    from softlanding.simulation.simulator import simulate
    from softlanding.studies.comparison import rigid_depth
    from softlanding.studies.impedance import optimize_impedance
    from softlanding.util.progress import progress as show_progress

    robot = PAPER_IMPEDANCE_ROBOT
    rows = []
    for v in show_progress(st.cot_v0, progress, "CoT optima", "v0"):
        dep = depth_optimum(v)
        cot = optimize_impedance(v, robot, objective="cot", grid=st.optimizer_grid)
        los = optimize_impedance(v, robot, objective="cot-lossless", grid=st.optimizer_grid)
        rig = simulate(robot, Impact(v), Rigid())
        rows.append({"v0": v, "rigid_depth": rigid_depth(v), "rigid_cot": rig.energy.cot,
                     "depth_opt_k_p": dep.k_p, "depth_opt_k_d": dep.k_d,
                     "depth_opt_depth": dep.depth, "depth_opt_cot": dep.cot,
                     "depth_opt_cot_lossless": dep.cot_lossless,
                     "cot_opt_k_p": cot.k_p, "cot_opt_k_d": cot.k_d, "cot_opt_depth": cot.depth,
                     "cot_opt_cot": cot.cot, "cot_lossless_opt_k_p": los.k_p,
                     "cot_lossless_opt_k_d": los.k_d, "cot_lossless_opt_depth": los.depth,
                     "cot_lossless_opt_cot_lossless": los.cot_lossless})
    cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    _save(plot_cot_comparison(cols["v0"], cols), out, "fig_cot", files)
    return rows


def robustness(out: Path, files: list[str], st: Settings, progress: bool) -> dict:
    """Nominal bang-bang and impedance replayed on a perturbed model (+-30 %)."""
    from softlanding.plots.paper import plot_robustness
    from softlanding.studies.robustness import robustness_study, robustness_table
    from softlanding.studies.sweeps import save_dataset

    ds = robustness_study(BANG_BANG_V0, PAPER_ROBOT, spread=0.3, n=st.robustness_n,
                          grid=st.optimizer_grid, progress=progress)
    save_dataset(ds, out / "data" / "robustness.nc")
    files.append("data/robustness.nc")
    _save(plot_robustness(ds), out, "fig_robustness", files)
    return {"v0": BANG_BANG_V0, "spread": 0.3, "factors": [float(f) for f in ds.factor.values],
            "table": robustness_table(ds),
            "depth_ratio": {f"{c}|{m:g}|{p}": [float(x) for x in
                                              ds.depth_ratio.sel(controller=c, margin=m,
                                                                 parameter=p).values]
                            for c in ds.controller.values for m in ds.margin.values
                            for p in ds.parameter.values}}


# ------------------------------------------------------------------ driver
def hybrid(out: Path, files: list[str], st: Settings, progress: bool) -> dict:
    """Beyond the paper: the arrest optimised, leg extension, minimum-energy hopping."""
    from softlanding.report.phased import hybrid_findings

    return hybrid_findings(out, files, st.quick, progress)


SECTIONS = ("bang-bang example", "stepped intrusions", "depth maps", "optimal gains",
            "comparison", "experiment", "cost of transport", "robustness", "terrain models",
            "hybrid phases")


def reproduce(out_dir: str | Path, quick: bool = False, *, progress: bool = True,
              log: Callable[[str], None] | None = print) -> dict:
    """Regenerate every figure of the paper, the summary files and the robustness study.

    Parameters
    ----------
    out_dir : str or Path
        Folder to write into (created if missing; files of the same names are replaced,
        and only once the whole run has succeeded).
    quick : bool
        Coarser grids and fewer impact velocities (about a minute on 2 cores).
    progress : bool
        Progress bars for the long sweeps.
    log : callable or None
        Receives one line per finished section (None: silent).

    Returns
    -------
    dict
        The contents of ``summary.json``.
    """
    final = Path(out_dir)
    if not final.parent.is_dir():
        final.parent.mkdir(parents=True)
    # written into a temporary folder and moved into place at the end: an interrupted or
    # failed run leaves nothing half-written in out_dir
    with atomic_folder(final) as out:
        (out / "data").mkdir()
        summary = _run_sections(out, Settings.make(quick), progress, log)
    return summary


def _run_sections(out: Path, st: Settings, progress: bool,
                  log: Callable[[str], None] | None) -> dict:
    files: list[str] = []
    summary: dict = {}
    timings: dict[str, float] = {}
    t_all = time.perf_counter()

    def run(i: int, key: str, fn, *args):
        t0 = time.perf_counter()
        result = fn(*args)
        timings[key] = time.perf_counter() - t0
        if log is not None:
            log(f"[{i}/{len(SECTIONS)}] {SECTIONS[i - 1]:<20} {timings[key]:6.1f} s")
        return result

    summary["bang_bang_example"] = run(1, "bang_bang_example", bang_bang_example, out, files)
    maps: dict = {}
    summary["stepped_intrusions"] = run(2, "stepped_intrusions", stepped_intrusions, out,
                                        files, st, maps)
    summary["depth_maps"] = run(3, "depth_maps", depth_maps, out, files, st, maps)
    summary["optimal_gains"], depth_optimum = run(4, "optimal_gains", optimal_gains, out, files,
                                                  st, progress)
    summary["comparison"] = run(5, "comparison", comparison, out, files, st, progress,
                                depth_optimum)
    summary["experiment"] = run(6, "experiment", experiment, out, files, st)
    summary["cost_of_transport"] = run(7, "cost_of_transport", cost_of_transport, out, files,
                                       st, progress, depth_optimum)
    summary["robustness"] = run(8, "robustness", robustness, out, files, st, progress)
    from softlanding.studies.terrain_study import terrain_section

    summary["terrain_models"] = run(9, "terrain_models", terrain_section, out, files, st.quick)
    summary["hybrid"] = run(10, "hybrid", hybrid, out, files, st, progress)
    from softlanding._version import __version__

    summary["meta"] = {"quick": st.quick, "elapsed_s": time.perf_counter() - t_all,
                       "section_s": timings, "version": __version__,
                       "settings": {k: v for k, v in st.__dict__.items()},
                       "units": "dimensionless (x_s = m_t g / k_g, tau_s = sqrt(m_t / k_g), "
                                "force m_t g) unless a key says otherwise"}
    files += ["summary.json", "summary.md"]
    summary["files"] = files
    (out / "summary.json").write_text(json.dumps(json_safe(summary), indent=1))
    (out / "summary.md").write_text(summary_markdown(summary))
    return summary


__all__ = ["EXPERIMENT_KP", "EXPERIMENT_V0", "SECTIONS", "Settings", "reproduce"]
