"""The reproduction's section on the terrain models (the terrain study and its figures)."""

from __future__ import annotations

from typing import Any

import numpy as np

from softlanding.report.registry import Section, save_figure
from softlanding.studies.terrain_study import (
    EXPERIMENT_FASTEST_V0,
    experiment_curves,
    experiment_grounds,
    experiment_shift,
    model_rows,
    study_grounds,
)


def terrain_section(out: Any, files: list[str], quick: bool) -> dict:
    """The reproduce section: the study's numbers, figure and dataset.

    Parameters
    ----------
    out : Path
        Output folder.
    files : list of str
        Names of the files written (appended to).
    quick : bool
        The quick run (v0 = 0 and -4.8, coarse grids).
    """
    from softlanding.plots.terrain import plot_experiment_drag, plot_terrain_study

    # (quick: without v0 = -10, whose drag landings were 40 % of the quick section's time)
    v0s = (0.0, -4.8) if quick else tuple(np.round(np.linspace(0, -10, 11), 12))
    grid = 21 if quick else 101
    models = {lab: model_rows(v0s, g, grid) for lab, g in study_grounds().items()}
    kd = np.round(np.linspace(0.0, 2.5, 26 if quick else 126), 12)
    curves = experiment_curves(kd, experiment_grounds())
    save_figure(plot_terrain_study(models), out, "fig_terrain_models", files)
    save_figure(plot_experiment_drag(curves), out, "fig_terrain_experiment", files)
    shift = experiment_shift(curves)
    return {"v0": list(v0s), "grid": grid, "models": models, "experiment_v0": EXPERIMENT_FASTEST_V0,
            "experiment_shift": shift,
            "grounds": {lab: g.to_dict() for lab, g in study_grounds().items()}}


def terrain_markdown(s: dict) -> list[str]:
    """The section's tables for ``summary.md``.

    Parameters
    ----------
    s : dict
        The section's summary (:func:`terrain_section`).
    """
    out = ["## Terrain models (fig_terrain_models, fig_terrain_experiment)", "",
           "Bang-bang (refined, PMP-checked), optimal impedance (no force limit) and a rigid "
           "leg on each ground model; r_m = 5, s = 20, bang-bang u_max = 8.2.", "",
           "| ground | v0 | bang-bang | switches | PMP verdict | impedance (k_p*, k_d*) | "
           "rigid | bb/rigid | imp/rigid |", "|---|---|---|---|---|---|---|---|---|"]
    for lab, rows in s["models"].items():
        for r in rows:
            out.append(f"| {lab} | {r['v0']:g} | {r['bang_bang']:.6f} | {r['switches']} | "
                       f"{r['verdict']} | {r['impedance']:.6f} ({r['k_p']:.4f}, "
                       f"{r['k_d']:.4f}) | {r['rigid']:.5f} | {r['bb_over_rigid']:.4f} | "
                       f"{r['imp_over_rigid']:.4f} |")
    out += ["", f"Experiment curves at v0 = {s['experiment_v0']:g}: depth at the largest k_d "
                "against the paper's linear spring (negative: shallower).", "",
            "| ground | k_p | k_d | linear | with the model | change |",
            "|---|---|---|---|---|---|"]
    for r in s["experiment_shift"]:
        out.append(f"| {r['ground']} | {r['k_p']:g} | {r['k_d']:g} | {r['depth_linear']:.4f} |"
                   f" {r['depth']:.4f} | {100 * r['relative_change']:+.1f} % |")
    return out + [""]



TERRAIN_SECTION = Section("terrain_models", "terrain models",
                          lambda c: terrain_section(c.out, c.files, c.settings.quick),
                          terrain_markdown)

__all__ = ["TERRAIN_SECTION", "terrain_markdown", "terrain_section"]
