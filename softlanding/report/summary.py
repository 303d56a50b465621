"""``summary.md``: the reproduction's numbers as Markdown tables, the paper's beside ours."""

from __future__ import annotations

import math
from typing import Any


def _f(x: Any, nd: int = 4) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a" if x is None or math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return str(x)
    return f"{x:.{nd}f}"


def _table(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def _bang_bang(s: dict) -> list[str]:
    bb = s["bang_bang_example"]
    out: list[str] = []
    out += ["## Bang-bang landing (fig_bang_bang_trajectory)", "",
            _table(["quantity", "ours", "paper"], [
                ["depth -x_f(T)", _f(bb["depth"], 9), "-"],
                ["arcs", " -> ".join(bb["arcs"]), "max -> min"],
                ["switch time", ", ".join(_f(t, 6) for t in bb["switch_times"]), "-"],
                ["foot stops at T", _f(bb["T"], 6), "about 0.5 (caption: the stomp)"],
                ["body stops at", _f(bb["body_stops_at"], 6), "-"],
                ["arrest force u_b", _f(bb["u_b"], 6), "-"],
                ["simulator replay difference", f"{bb['replay_difference']:.1e}", "-"],
                ["PMP verdict", bb["pmp_verdict"], "-"],
                ["max abs H (scaled)", f"{bb['pmp_H_max_abs']:.1e}", "-"]]), ""]
    return out


def _stepped(s: dict) -> list[str]:
    si = s["stepped_intrusions"]
    out: list[str] = []
    out += ["## Stepped intrusions (fig_stepped_intrusions)", "",
            _table(["k_d", "steps (ours)", "steps (paper)", "depth"],
                   [[_f(t["k_d"], 2), t["steps"], p, _f(t["depth"], 6)]
                    for t, p in zip(si["trajectories"], si["paper_steps"], strict=True)]), "",
            _table(["v0", "multi-step share of the gain square", "... and within the stroke",
                    "most steps (rest proven)", "rest unproven (k_p = 0 creep, k_d = 0 hops)"],
                   [[_f(r["v0"], 1), _f(r["multi_step_fraction"], 3),
                     _f(r["multi_step_feasible_fraction"], 3), r["max_steps_rest_proven"],
                     _f(r["rest_unproven_fraction"], 3)] for r in si["regions"]]), "",
            "The paper describes the multi-step regions as emerging, morphing and vanishing as "
            "v0 grows; here they grow with |v0| over the whole range.", ""]
    return out


def _maps(s: dict) -> list[str]:
    out: list[str] = []
    out += ["## Optimal impedance on the maps (fig_depth_maps)", "",
            _table(["v0", "k_p*", "k_d*", "depth*", "steps", "active limit"],
                   [[_f(r["v0"], 1), _f(r["k_p"], 6), _f(r["k_d"], 6), _f(r["depth"], 6),
                     r["steps"], r["active_constraint"] or "none"] for r in s["depth_maps"]]),
            "", "The paper: every optimum lies on the stroke-limit boundary.", ""]
    return out


def _gains(s: dict) -> list[str]:
    obs = s["optimal_gains"]["observations_r5_s20"]
    out: list[str] = []
    out += ["## Optimal gains against v0 (fig_optimal_gains)", "",
            _table(["claim (paper, r_m = 5, s = 20)", "ours"], [
                ["k_p* increases with |v0|", _f(obs["kp_increasing_with_speed"])],
                ["k_d* first decreases, then increases", _f(
                    obs["kd_first_decreasing_then_increasing"])],
                ["critical |v0| between 2 and 6",
                 f"{_f(obs['critical_speed_between_2_and_6'])} "
                 f"(minimum at |v0| = {obs['kd_min_at_speed']:g})"],
                ["all optima on the stroke limit", _f(obs["all_on_stroke_boundary"])],
                ["peak force at the fastest v0 (paper: 8.2)", _f(obs["u_peak_at_fastest"], 3)]]),
            ""]
    nf = s["optimal_gains"]["no_feasible_gains"]
    if nf:
        out += ["No gains in [0, 1]^2 keep the stroke at: " + ", ".join(
            f"(r_m={r['r_m']:g}, s={r['s']:g}, v0={r['v0']:g})" for r in nf) + ".", ""]
    return out


def _comparison(s: dict) -> list[str]:
    cmp = s["comparison"]
    out: list[str] = []
    out += ["## Rigid vs optimal impedance vs bang-bang (fig_depth_vs_velocity)", "",
            _table(["v0", "rigid", "impedance", "(k_p*, k_d*)", "bang-bang", "imp/rigid",
                    "bb/rigid"],
                   [[_f(r["v0"], 2), _f(r["rigid"], 5), _f(r["impedance"], 5),
                     f"({r['impedance_k_p']:.4f}, {r['impedance_k_d']:.4f})",
                     _f(r["bang_bang"], 5),
                     _f(r["impedance"] / r["rigid"], 4), _f(r["bang_bang"] / r["rigid"], 4)]
                    for r in cmp["rows"]]), "",
            f"Bang-bang / rigid: {cmp['bang_bang_over_rigid'][0]:.4f} to "
            f"{cmp['bang_bang_over_rigid'][1]:.4f} (paper: at most 1/2). Impedance / rigid: "
            f"{cmp['impedance_over_rigid'][0]:.4f} to {cmp['impedance_over_rigid'][1]:.4f}. "
            f"Bang-bang below impedance at every v0 < 0: "
            f"{_f(cmp['bang_bang_below_impedance_everywhere'])}. Peak force of the optimal "
            f"impedance at v0 = {cmp['fastest_v0']:g}: {cmp['impedance_u_peak_at_fastest']:.3f} "
            f"(the paper takes u_max = 8.2 from it).", ""]
    return out


def _experiment(s: dict) -> list[str]:
    out: list[str] = []
    out += ["## Experiment curves (fig_experiment, fig_experiment_si)", "",
            "The paper does not list its impact velocities (up to v0 = -4.8); we use "
            + ", ".join(f"{v:g}" for v in sorted({r["v0"] for r in s["experiment"]},
                                                 reverse=True)) + ".", "",
            _table(["k_p", "v0", "speed [m/s], paper rig", "best k_d", "depth there",
                    "depth [mm]", "depth at k_d = 0", "gains kept in stroke"],
                   [[r["k_p"], r["v0"], _f(r["speed_m_per_s"], 3), _f(r["best_k_d"], 3),
                     _f(r["best_depth"], 4), _f(r["best_depth_mm"], 2),
                     _f(r["depth_at_k_d_0"], 4), _f(r["feasible_fraction"], 3)]
                    for r in s["experiment"]]), ""]
    return out


def _cot(s: dict) -> list[str]:
    out: list[str] = []
    out += ["## Minimum CoT against minimum depth (fig_cot)", "",
            _table(["v0", "rigid CoT", "min-depth: depth", "CoT", "lossless CoT",
                    "min-CoT: (k_p, k_d)", "depth", "CoT"],
                   [[_f(r["v0"], 2), _f(r["rigid_cot"], 3), _f(r["depth_opt_depth"], 4),
                     _f(r["depth_opt_cot"], 3), _f(r["depth_opt_cot_lossless"], 3),
                     f"({r['cot_opt_k_p']:.3f}, {r['cot_opt_k_d']:.3f})",
                     _f(r["cot_opt_depth"], 4),
                     _f(r["cot_opt_cot"], 3)] for r in s["cost_of_transport"]]), ""]
    return out


def _robustness(s: dict) -> list[str]:
    out: list[str] = []
    rb = s["robustness"]
    out += ["## Robustness (fig_robustness)", "",
            f"Nominal controllers designed at v0 = {rb['v0']:g}, r_m = 5, s = 20 (bang-bang "
            f"u_max = 8.2), replayed unchanged in SI units when the true value differs by up to "
            f"+-{rb['spread']:.0%} ({len(rb['factors'])} factors). Regret = depth / depth of "
            "the same kind of controller designed for the true model. A margin m designs for "
            "the stroke (1 - m) s.", "",
            _table(["controller", "margin", "error in", "nominal depth", "worst regret",
                    "left the stroke limits", "body never stops",
                    "largest finite excursion [stroke]"],
                   [[r["controller"], f"{r['margin']:.0%}", r["parameter"],
                     _f(r["nominal_depth"], 4), _f(r["worst_depth_ratio"], 4),
                     f"{r['violations']}/{r['cases']}", r["body_never_stops"],
                     _f(r["largest_violation"], 4)] for r in rb["table"]]), ""]
    return out


def _terrain(s: dict) -> list[str]:
    if "terrain_models" not in s:
        return []
    from softlanding.studies.terrain_study import terrain_markdown

    return terrain_markdown(s["terrain_models"])


def _hybrid(s: dict) -> list[str]:
    if "hybrid" not in s:
        return []
    from softlanding.report.summary_phased import hybrid_markdown

    return hybrid_markdown(s["hybrid"])


SECTIONS = (_bang_bang, _stepped, _maps, _gains, _comparison, _experiment, _cot, _robustness,
            _terrain, _hybrid)


def summary_markdown(s: dict) -> str:
    """The summary as Markdown tables (paper values beside ours where it gives them).

    Parameters
    ----------
    s : dict
        The contents of ``summary.json`` (see :func:`softlanding.report.reproduction.reproduce`).
    """
    m = s["meta"]
    out = [f"# Soft landing: reproduction of the paper ({'quick' if m['quick'] else 'full'} run)",
           "", f"Computed in {m['elapsed_s']:.1f} s by softlanding {m['version']}. Units are the "
           "paper's dimensionless ones unless stated. Figures: PNG and PDF beside this file.", ""]
    for section in SECTIONS:
        out += section(s)
    out += ["## Files", "", ", ".join(s["files"]), ""]
    return "\n".join(out)


__all__ = ["summary_markdown"]
