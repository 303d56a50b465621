"""The reproduction's section on the hybrid multi-phase questions (beyond the paper).

Three findings, each with its figure and rows in ``summary.json``/``summary.md``:

1. the body-arrest phase optimised (two-phase landing) against the paper's
   constant-force arrest, over impact velocities; and whether a second yielding
   step ever lowers the depth (four-phase landing from several starts);
2. pre-impact leg extension (impact mode, and the drop mode with a flight phase):
   the depth gained and the optimal extension;
3. the minimum-energy hop cycle against the best impedance and a rigid leg.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from softlanding.model.robot import PAPER_ROBOT

QUICK: dict[str, Any] = {"v0": (-0.5, -3.0, -6.0, -10.0), "two_step_v0": (-1.0,),
                         "hop_v0": (-3.0,), "hop_grid": 5}
FULL: dict[str, Any] = {"v0": tuple(float(v) for v in np.round(np.linspace(-0.5, -10.0, 41), 12)),
                        "two_step_v0": (-1.0, -3.0, -6.0, -10.0),
                        "hop_v0": (-0.5, -1.5, -3.0, -5.0, -7.5, -10.0), "hop_grid": 9}


def _two_phase(v0s: tuple[float, ...], progress: bool) -> tuple[list, list[dict]]:
    from softlanding.optimal.two_phase import sweep_two_phase

    rows = sweep_two_phase(v0s, PAPER_ROBOT, progress=progress)
    return rows, [{"v0": r.impact.v0, "depth": r.depth, "paper_depth": r.paper_depth,
                   "difference": r.depth - r.paper_depth, "T1": r.T1, "T": r.T,
                   "arcs": r.arcs, "arrest_force": r.arrest_force,
                   "arrest_force_spread": r.arrest_force_range[1] - r.arrest_force_range[0],
                   "crater_capacity_minus_foot_weight": r.depth - PAPER_ROBOT.foot_mass,
                   "replay_difference": r.replay_difference, "path": r.path,
                   "unverified_reasons": r.unverified_reasons()} for r in rows]


def _legs(v0s: tuple[float, ...], mode: str, progress: bool) -> tuple[list, list[dict]]:
    from softlanding.optimal.leg_extension import sweep_leg_extension

    rows = sweep_leg_extension(v0s, PAPER_ROBOT, mode=mode, progress=progress)
    return rows, [{"v0": r.impact.v0, "mode": mode, "depth": r.depth,
                   "paper_depth": r.paper_depth, "gain": r.gain, "extension": r.extension,
                   "rate": r.rate, "com_velocity": r.com_velocity, "arcs": r.arcs,
                   "path": r.path, "unverified_reasons": r.unverified_reasons()}
                  for r in rows]


def hybrid_findings(out: Path, files: list[str], quick: bool, progress: bool) -> dict[str, Any]:
    """Run the section: figures into ``out``, the numbers returned for the summary.

    Parameters
    ----------
    out : Path
        Output folder.
    files : list of str
        Receives the names of the files written.
    quick : bool
        Fewer velocities and apex heights.
    progress : bool
        Progress bars.
    """
    from softlanding.optimal.hopping import sweep_hops
    from softlanding.optimal.two_phase import two_step_check
    from softlanding.plots.phased import plot_full_landing, plot_hop, plot_hybrid_findings
    from softlanding.report.reproduction import _save

    cfg = QUICK if quick else FULL
    two, two_rows = _two_phase(cfg["v0"], progress)
    steps = [two_step_check(v).to_dict() for v in cfg["two_step_v0"]]
    legs, leg_rows = _legs(cfg["v0"], "impact", progress)
    drop_rows = _legs(cfg["v0"], "drop", progress)[1] if not quick else []
    hops = sweep_hops(cfg["hop_v0"], PAPER_ROBOT, 0.0, grid=cfg["hop_grid"],
                      progress=progress)
    _save(plot_hybrid_findings(two, legs, hops), out, "fig_hybrid_findings", files)
    example = next(r for r in two if r.impact.v0 == -3.0)
    _save(plot_full_landing(example), out, "fig_two_phase_landing", files)
    leg_example = next(r for r in legs if r.impact.v0 == -3.0)
    _save(plot_full_landing(leg_example), out, "fig_leg_extension", files)
    free = [h for h in hops["free"] if h is not None]
    if free:
        _save(plot_hop(free[-1]), out, "fig_hop_cycle", files)
    hop_rows = [{leg: (None if h is None else h.to_dict()) for leg, h in
                 zip(hops, col, strict=True)} for col in zip(*hops.values(), strict=True)]
    return {"two_phase": two_rows, "two_step": steps, "leg_extension": leg_rows,
            "leg_extension_drop": drop_rows, "hopping": hop_rows, "hop_eta": 0.0,
            "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in cfg.items()}}


__all__ = ["FULL", "QUICK", "hybrid_findings"]
