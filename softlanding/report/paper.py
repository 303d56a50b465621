"""The paper's sections of the reproduction: each figure of the paper, its numbers and tables.

Each section is a :class:`~softlanding.report.registry.Section`: a run (the computation,
its figure as PNG and PDF, its rows for ``summary.json``) and its Markdown.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT, Impact
from softlanding.model.scaling import EXPERIMENT_KP, EXPERIMENT_V0
from softlanding.report.markdown import cell, table
from softlanding.report.registry import Context, Section, Settings, save_figure

BANG_BANG_V0 = -3.0
"""Impact velocity of the paper's bang-bang example figure."""

STEP_MAP_V0 = (-0.5, -1.0, -2.0, -4.0, -6.0, -10.0)
DEPTH_MAP_V0 = (-1.0, -3.0, -5.0, -10.0)
FAMILIES = ((2.0, 5.0, 10.0), (10.0, 20.0, 40.0))


def bang_bang_example(out: Path, files: list[str]) -> dict:
    """[fig:ex_bb_traj] the optimal landing at v0 = -3, with its PMP certificate."""
    from ocp import certify
    from softlanding.optimal.landing import solve_landing
    from softlanding.plots.paper import plot_bang_bang

    res = solve_landing(BANG_BANG_V0, PAPER_ROBOT)
    assert res.transcribed is not None  # a cold solve always transcribes
    cert = certify(res.transcribed, res.refined)
    save_figure(plot_bang_bang(res), out, "fig_bang_bang_trajectory", files)
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
    save_figure(plot_stepped_intrusion_figure(runs, maps), out, "fig_stepped_intrusions", files)
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
    save_figure(plot_depth_maps(maps, optima), out, "fig_depth_maps", files)
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
    save_figure(plot_gain_families(curves), out, "fig_optimal_gains", files)
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
    save_figure(plot_controller_comparison(cols, PAPER_ROBOT), out, "fig_depth_vs_velocity", files)
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
    save_figure(plot_experiment_curves(ds), out, "fig_experiment", files)
    rig = paper_rig()
    save_figure(plot_experiment_curves(ds, si=rig), out, "fig_experiment_si", files)
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
    save_figure(plot_cot_comparison(cols["v0"], cols), out, "fig_cot", files)
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
    save_figure(plot_robustness(ds), out, "fig_robustness", files)
    return {"v0": BANG_BANG_V0, "spread": 0.3, "factors": [float(f) for f in ds.factor.values],
            "table": robustness_table(ds),
            "depth_ratio": {f"{c}|{m:g}|{p}": [float(x) for x in
                                              ds.depth_ratio.sel(controller=c, margin=m,
                                                                 parameter=p).values]
                            for c in ds.controller.values for m in ds.margin.values
                            for p in ds.parameter.values}}



# ------------------------------------------------------------------ Markdown
def _bang_bang_md(s: Any) -> list[str]:
    bb = s
    out: list[str] = []
    out += ["## Bang-bang landing (fig_bang_bang_trajectory)", "",
            table(["quantity", "ours", "paper"], [
                ["depth -x_f(T)", cell(bb["depth"], 9), "-"],
                ["arcs", " -> ".join(bb["arcs"]), "max -> min"],
                ["switch time", ", ".join(cell(t, 6) for t in bb["switch_times"]), "-"],
                ["foot stops at T", cell(bb["T"], 6), "about 0.5 (caption: the stomp)"],
                ["body stops at", cell(bb["body_stops_at"], 6), "-"],
                ["arrest force u_b", cell(bb["u_b"], 6), "-"],
                ["simulator replay difference", f"{bb['replay_difference']:.1e}", "-"],
                ["PMP verdict", bb["pmp_verdict"], "-"],
                ["max abs H (scaled)", f"{bb['pmp_H_max_abs']:.1e}", "-"]]), ""]
    return out


def _stepped_md(s: Any) -> list[str]:
    si = s
    out: list[str] = []
    out += ["## Stepped intrusions (fig_stepped_intrusions)", "",
            table(["k_d", "steps (ours)", "steps (paper)", "depth"],
                   [[cell(t["k_d"], 2), t["steps"], p, cell(t["depth"], 6)]
                    for t, p in zip(si["trajectories"], si["paper_steps"], strict=True)]), "",
            table(["v0", "multi-step share of the gain square", "... and within the stroke",
                    "most steps (rest proven)", "rest unproven (k_p = 0 creep, k_d = 0 hops)"],
                   [[cell(r["v0"], 1), cell(r["multi_step_fraction"], 3),
                     cell(r["multi_step_feasible_fraction"], 3), r["max_steps_rest_proven"],
                     cell(r["rest_unproven_fraction"], 3)] for r in si["regions"]]), "",
            "The paper describes the multi-step regions as emerging, morphing and vanishing as "
            "v0 grows; here they grow with |v0| over the whole range.", ""]
    return out


def _maps_md(s: Any) -> list[str]:
    out: list[str] = []
    out += ["## Optimal impedance on the maps (fig_depth_maps)", "",
            table(["v0", "k_p*", "k_d*", "depth*", "steps", "active limit"],
                   [[cell(r["v0"], 1), cell(r["k_p"], 6), cell(r["k_d"], 6), cell(r["depth"], 6),
                     r["steps"], r["active_constraint"] or "none"] for r in s]),
            "", "The paper: every optimum lies on the stroke-limit boundary.", ""]
    return out


def _gains_md(s: Any) -> list[str]:
    obs = s["observations_r5_s20"]
    out: list[str] = []
    out += ["## Optimal gains against v0 (fig_optimal_gains)", "",
            table(["claim (paper, r_m = 5, s = 20)", "ours"], [
                ["k_p* increases with |v0|", cell(obs["kp_increasing_with_speed"])],
                ["k_d* first decreases, then increases", cell(
                    obs["kd_first_decreasing_then_increasing"])],
                ["critical |v0| between 2 and 6",
                 f"{cell(obs['critical_speed_between_2_and_6'])} "
                 f"(minimum at |v0| = {obs['kd_min_at_speed']:g})"],
                ["all optima on the stroke limit", cell(obs["all_on_stroke_boundary"])],
                ["peak force at the fastest v0 (paper: 8.2)", cell(obs["u_peak_at_fastest"], 3)]]),
            ""]
    nf = s["no_feasible_gains"]
    if nf:
        out += ["No gains in [0, 1]^2 keep the stroke at: " + ", ".join(
            f"(r_m={r['r_m']:g}, s={r['s']:g}, v0={r['v0']:g})" for r in nf) + ".", ""]
    return out


def _comparison_md(s: Any) -> list[str]:
    cmp = s
    out: list[str] = []
    out += ["## Rigid vs optimal impedance vs bang-bang (fig_depth_vs_velocity)", "",
            table(["v0", "rigid", "impedance", "(k_p*, k_d*)", "bang-bang", "imp/rigid",
                    "bb/rigid"],
                   [[cell(r["v0"], 2), cell(r["rigid"], 5), cell(r["impedance"], 5),
                     f"({r['impedance_k_p']:.4f}, {r['impedance_k_d']:.4f})",
                     cell(r["bang_bang"], 5),
                     cell(r["impedance"] / r["rigid"], 4), cell(r["bang_bang"] / r["rigid"], 4)]
                    for r in cmp["rows"]]), "",
            f"Bang-bang / rigid: {cmp['bang_bang_over_rigid'][0]:.4f} to "
            f"{cmp['bang_bang_over_rigid'][1]:.4f} (paper: at most 1/2). Impedance / rigid: "
            f"{cmp['impedance_over_rigid'][0]:.4f} to {cmp['impedance_over_rigid'][1]:.4f}. "
            f"Bang-bang below impedance at every v0 < 0: "
            f"{cell(cmp['bang_bang_below_impedance_everywhere'])}. Peak force of the optimal "
            f"impedance at v0 = {cmp['fastest_v0']:g}: {cmp['impedance_u_peak_at_fastest']:.3f} "
            f"(the paper takes u_max = 8.2 from it).", ""]
    return out


def _experiment_md(s: Any) -> list[str]:
    out: list[str] = []
    out += ["## Experiment curves (fig_experiment, fig_experiment_si)", "",
            "The paper does not list its impact velocities (up to v0 = -4.8); we use "
            + ", ".join(f"{v:g}" for v in sorted({r["v0"] for r in s},
                                                 reverse=True)) + ".", "",
            table(["k_p", "v0", "speed [m/s], paper rig", "best k_d", "depth there",
                    "depth [mm]", "depth at k_d = 0", "gains kept in stroke"],
                   [[r["k_p"], r["v0"], cell(r["speed_m_per_s"], 3), cell(r["best_k_d"], 3),
                     cell(r["best_depth"], 4), cell(r["best_depth_mm"], 2),
                     cell(r["depth_at_k_d_0"], 4), cell(r["feasible_fraction"], 3)]
                    for r in s]), ""]
    return out


def _cot_md(s: Any) -> list[str]:
    out: list[str] = []
    out += ["## Minimum CoT against minimum depth (fig_cot)", "",
            table(["v0", "rigid CoT", "min-depth: depth", "CoT", "lossless CoT",
                    "min-CoT: (k_p, k_d)", "depth", "CoT"],
                   [[cell(r["v0"], 2), cell(r["rigid_cot"], 3), cell(r["depth_opt_depth"], 4),
                     cell(r["depth_opt_cot"], 3), cell(r["depth_opt_cot_lossless"], 3),
                     f"({r['cot_opt_k_p']:.3f}, {r['cot_opt_k_d']:.3f})",
                     cell(r["cot_opt_depth"], 4),
                     cell(r["cot_opt_cot"], 3)] for r in s]), ""]
    return out


def _robustness_md(s: Any) -> list[str]:
    out: list[str] = []
    rb = s
    out += ["## Robustness (fig_robustness)", "",
            f"Nominal controllers designed at v0 = {rb['v0']:g}, r_m = 5, s = 20 (bang-bang "
            f"u_max = 8.2), replayed unchanged in SI units when the true value differs by up to "
            f"+-{rb['spread']:.0%} ({len(rb['factors'])} factors). Regret = depth / depth of "
            "the same kind of controller designed for the true model. A margin m designs for "
            "the stroke (1 - m) s.", "",
            table(["controller", "margin", "error in", "nominal depth", "worst regret",
                    "left the stroke limits", "body never stops",
                    "largest finite excursion [stroke]"],
                   [[r["controller"], f"{r['margin']:.0%}", r["parameter"],
                     cell(r["nominal_depth"], 4), cell(r["worst_depth_ratio"], 4),
                     f"{r['violations']}/{r['cases']}", r["body_never_stops"],
                     cell(r["largest_violation"], 4)] for r in rb["table"]]), ""]
    return out



def _gains_run(c: Context) -> dict:
    entry, c.shared["depth_optimum"] = optimal_gains(c.out, c.files, c.settings, c.progress)
    return entry


PAPER_SECTIONS = (
    Section("bang_bang_example", "bang-bang example",
            lambda c: bang_bang_example(c.out, c.files), _bang_bang_md),
    Section("stepped_intrusions", "stepped intrusions",
            lambda c: stepped_intrusions(c.out, c.files, c.settings,
                                         c.shared.setdefault("maps", {})), _stepped_md),
    Section("depth_maps", "depth maps",
            lambda c: depth_maps(c.out, c.files, c.settings, c.shared.setdefault("maps", {})),
            _maps_md),
    Section("optimal_gains", "optimal gains", _gains_run, _gains_md),
    Section("comparison", "comparison",
            lambda c: comparison(c.out, c.files, c.settings, c.progress,
                                 c.shared["depth_optimum"]), _comparison_md),
    Section("experiment", "experiment", lambda c: experiment(c.out, c.files, c.settings),
            _experiment_md),
    Section("cost_of_transport", "cost of transport",
            lambda c: cost_of_transport(c.out, c.files, c.settings, c.progress,
                                        c.shared["depth_optimum"]), _cot_md),
    Section("robustness", "robustness",
            lambda c: robustness(c.out, c.files, c.settings, c.progress), _robustness_md),
)
"""The paper's sections, in the paper's order."""

__all__ = ["BANG_BANG_V0", "DEPTH_MAP_V0", "FAMILIES",
           "PAPER_SECTIONS", "STEP_MAP_V0"]
