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
from softlanding.report.markdown import cell, table
from softlanding.report.registry import Section, save_figure

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
    from softlanding.plots.phased import plot_hop, plot_hybrid_findings, plot_phased_landing

    cfg = QUICK if quick else FULL
    two, two_rows = _two_phase(cfg["v0"], progress)
    steps = [two_step_check(v).to_dict() for v in cfg["two_step_v0"]]
    legs, leg_rows = _legs(cfg["v0"], "impact", progress)
    drop_rows = _legs(cfg["v0"], "drop", progress)[1] if not quick else []
    hops = sweep_hops(cfg["hop_v0"], PAPER_ROBOT, 0.0, grid=cfg["hop_grid"],
                      progress=progress)
    save_figure(plot_hybrid_findings(two, legs, hops), out, "fig_hybrid_findings", files)
    example = next(r for r in two if r.impact.v0 == -3.0)
    save_figure(plot_phased_landing(example), out, "fig_two_phase_landing", files)
    leg_example = next(r for r in legs if r.impact.v0 == -3.0)
    save_figure(plot_phased_landing(leg_example), out, "fig_leg_extension", files)
    free = [h for h in hops["free"] if h is not None]
    if free:
        save_figure(plot_hop(free[-1]), out, "fig_hop_cycle", files)
    hop_rows = [{leg: (None if h is None else h.to_dict()) for leg, h in
                 zip(hops, col, strict=True)} for col in zip(*hops.values(), strict=True)]
    return {"two_phase": two_rows, "two_step": steps, "leg_extension": leg_rows,
            "leg_extension_drop": drop_rows, "hopping": hop_rows, "hop_eta": 0.0,
            "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in cfg.items()}}


def _two_phase_md(h: dict) -> list[str]:
    rows = h["two_phase"]
    worst = max(abs(r["difference"]) for r in rows)
    spread = max(r["arrest_force_spread"] for r in rows)
    return [
        "### 1. The body-arrest phase optimised (fig_hybrid_findings, fig_two_phase_landing)",
        "", "Two phases: yielding until the foot stops, then static stance until the body "
        "stops; the phase-2 force free within |u| <= u_max with the support force within "
        "[0, crater depth].", "",
        table(["v0", "two-phase depth", "paper's depth", "difference", "phase-2 force",
                "crater depth - foot weight", "arcs", "replay diff."],
               [[cell(r["v0"], 3), cell(r["depth"], 9), cell(r["paper_depth"], 9),
                 f"{r['difference']:.1e}", cell(r["arrest_force"], 6),
                 cell(r["crater_capacity_minus_foot_weight"], 6),
                 " / ".join(" ".join(a) for a in r["arcs"]),
                 f"{r['replay_difference']:.1e}"] for r in rows[::max(1, len(rows) // 8)]]),
        "", f"Largest |two-phase - paper| over {len(rows)} velocities: {worst:.1e}. The optimal "
        f"phase-2 force is constant (largest spread {spread:.1e}) and equals the crater's "
        "capacity minus the foot's weight: the paper's constant arrest u_b, with its "
        "condition active, is optimal (confirms the paper's assumption).", ""]


def _two_step_md(h: dict) -> list[str]:
    rows = h["two_step"]
    return [
        "Second yielding step (yielding, static, yielding, static) from several starts:", "",
        table(["v0", "one-step depth", "two-step depth", "gain", "middle phases collapse"],
               [[cell(r["v0"], 2), cell(r["one_step_depth"], 9), cell(r["two_step_depth"], 9),
                 f"{r['gain']:.1e}", cell(r["collapsed"])] for r in rows]),
        "", "A gain <= 0 (to the four-phase transcription's grid error) means a second step "
        "never lowers the depth.", ""]


def _legs_md(h: dict) -> list[str]:
    rows = h["leg_extension"]
    out = ["### 2. Pre-impact leg extension (fig_leg_extension)", "",
           "Changes the paper's initial condition: the leg length at impact is a decision in "
           "[0, s] (both masses at v0).", "",
           table(["v0", "depth", "paper (leg s/2)", "gain", "optimal leg length", "verified"],
                  [[cell(r["v0"], 3), cell(r["depth"], 6), cell(r["paper_depth"], 6),
                    cell(r["gain"], 4), cell(r["extension"], 4), cell(not r["unverified_reasons"])]
                   for r in rows[::max(1, len(rows) // 8)]]), ""]
    drop = h.get("leg_extension_drop") or []
    if drop:
        out += ["From a drop (a flight phase, the actuator free in flight):", "",
                table(["v0", "depth", "gain", "leg length", "rate", "CoM velocity",
                        "verified"],
                       [[cell(r["v0"], 3), cell(r["depth"], 6), cell(r["gain"], 4),
                         cell(r["extension"], 4), cell(r["rate"], 4), cell(r["com_velocity"], 4),
                         cell(not r["unverified_reasons"])]
                        for r in drop[::max(1, len(drop) // 8)]]),
                ""]
    return out


def _hops_md(h: dict) -> list[str]:
    rows = h["hopping"]

    def field(c: Any, key: str, nd: int = 4) -> str:
        return "n/a" if c is None else cell(c[key], nd)

    return [f"### 3. Minimum-energy hopping, eta = {h['hop_eta']:g} (fig_hybrid_findings, "
            "fig_hop_cycle)", "",
            table(["v0", "apex", "optimum: energy", "crater", "CoT", "impedance: energy",
                    "(k_p, k_d, u_t)", "rigid: energy", "crater"],
                   [[cell(r["free"]["v0"], 2), cell(r["free"]["apex_height"], 3),
                     field(r["free"], "energy"), field(r["free"], "depth"),
                     field(r["free"], "cot", 3), field(r["impedance"], "energy"),
                     "n/a" if r["impedance"] is None else
                     "({k_p:.3g}, {k_d:.3g}, {u_t:.3g})".format(**r["impedance"]["gains"]),
                     field(r["rigid"], "energy"), field(r["rigid"], "depth")] for r in rows]),
            "", "Energies per cycle in m_t g x_s, evaluated on the exact replay of each control. "
            "The optimum's is a grid's value (discretised, one grid per velocity), above the "
            "continuous optimum by the grid's error: `softlanding hop --doublings K` estimates "
            "it.", ""]


def hybrid_markdown(h: dict) -> list[str]:
    """The section's Markdown lines.

    Parameters
    ----------
    h : dict
        ``summary["hybrid"]``.
    """
    return (["## Beyond the paper: the landing as a hybrid multi-phase problem", ""]
            + _two_phase_md(h) + _two_step_md(h) + _legs_md(h) + _hops_md(h))



PHASED_SECTION = Section("hybrid", "hybrid phases",
                         lambda c: hybrid_findings(c.out, c.files, c.settings.quick, c.progress),
                         hybrid_markdown)

__all__ = ["FULL", "PHASED_SECTION", "QUICK", "hybrid_findings", "hybrid_markdown"]
