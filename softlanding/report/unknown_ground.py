"""The reproduction's section on landing on ground the robot does not know (issue 25).

Runs :func:`softlanding.studies.unknown_ground_study` on the run's grid (``Settings``:
``unknown_v0`` x ``unknown_stiffness`` x ``unknown_drag``), writes its figure
(``fig_unknown_ground``, :func:`softlanding.plots.plot_unknown_ground_study`) and its rows
(``data/unknown_ground.json``, every number; ``data/unknown_ground.csv``, one line per case
and controller), and reports per impact velocity each controller's worst depth over the grounds,
the MPC's goals and its step times (wall time on this machine, against the sample period on
the paper's rig).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from softlanding.report.markdown import cell, table
from softlanding.report.registry import Section, Settings, save_figure
from softlanding.util.jsonable import json_safe

WITHIN = 1.02
"""The MPC's goal: depth at most this times the clairvoyant depth."""
BELOW_TOL = 1e-9
"""A depth below ``(1 - BELOW_TOL)`` times the clairvoyant depth counts as below it."""


def _case(row: Mapping[str, Any], keys: Sequence[str]) -> dict[str, Any]:
    """One row reduced to what the summary reports."""
    g = row["ground"]
    out: dict[str, Any] = {"v0": float(row["v0"]), "stiffness": float(g.get("stiffness", 1.0)),
                           "c_d": float(g.get("c_d", 0.0)),
                           "clairvoyant_depth": float(row["clairvoyant_depth"]),
                           "clairvoyant_verified": bool(row.get("clairvoyant_verified", True))}
    for k in keys:
        c = row[k]
        out[k] = {"depth": float(c["depth"]), "ratio": float(c["ratio"]),
                  "feasible": bool(c["feasible"])}
    m = row.get("mpc")
    if isinstance(m, Mapping) and "mpc" in keys:
        out["mpc"].update({n: m[n] for n in ("step_time_median_ms", "step_time_p99_ms",
                                             "step_times_ms", "replans", "fallbacks")
                           if n in m})
    return out


def _group(cases: Sequence[Mapping[str, Any]], keys: Sequence[str]) -> dict[str, Any]:
    """The numbers of one impact velocity (or of all of them)."""
    d: dict[str, Any] = {
        "cases": len(cases),
        "clairvoyant_worst": max(c["clairvoyant_depth"] for c in cases),
        "clairvoyant_verified": sum(c["clairvoyant_verified"] for c in cases),
        "worst": {k: max(c[k]["depth"] for c in cases) for k in keys},
        "feasible": {k: sum(c[k]["feasible"] for c in cases) for k in keys}}
    if "mpc" in keys:
        ratios = np.array([c["mpc"]["ratio"] for c in cases])
        # over every step of every case, as the study's goals (the cases' own medians and
        # 99th percentiles when the steps were not kept)
        steps = [np.asarray(c["mpc"]["step_times_ms"], float) for c in cases
                 if "step_times_ms" in c["mpc"]]
        if len(steps) == len(cases) and any(x.size for x in steps):
            pooled = np.concatenate(steps)
            med, p99 = float(np.median(pooled)), float(np.percentile(pooled, 99))
        else:
            med = float(np.median([c["mpc"].get("step_time_median_ms", np.nan) for c in cases]))
            p99 = float(np.max([c["mpc"].get("step_time_p99_ms", np.nan) for c in cases]))
        d["mpc"] = {"within_2_percent": int((ratios <= WITHIN).sum()),
                    "never_below": int((ratios >= 1.0 - BELOW_TOL).sum()),
                    "max_ratio": float(ratios.max()), "min_ratio": float(ratios.min()),
                    "step_time_median_ms": med, "step_time_p99_ms": p99}
    return d


def unknown_ground_entry(rows: Sequence[Mapping[str, Any]], *, period: float,
                         tau_s: float) -> dict[str, Any]:
    """The section's ``summary.json`` entry from the study's rows (no computation).

    Parameters
    ----------
    rows : sequence of dict
        From :func:`softlanding.studies.unknown_ground_study`.
    period : float
        The MPC's sample period (the paper's time unit).
    tau_s : float
        The paper's time unit on its rig, in seconds
        (:func:`softlanding.model.terrain.paper_rig_units`).
    """
    from softlanding.plots.control import STUDY_CONTROLLERS, study_controllers

    keys = study_controllers(rows)
    cases = [_case(r, keys) for r in rows]
    v0s = list(dict.fromkeys(c["v0"] for c in cases))
    robot = next((r["mpc"].get("robot") for r in rows if isinstance(r.get("mpc"), Mapping)),
                 None)
    return {"robot": robot,
        "controllers": keys,
        "labels": {k: STUDY_CONTROLLERS.get(k, k.replace("_", " ")) for k in keys},
        "v0": v0s, "stiffness": sorted({c["stiffness"] for c in cases}),
        "c_d": sorted({c["c_d"] for c in cases}),
        "period": period, "tau_s": tau_s, "rig_period_ms": 1e3 * period * tau_s,
        "by_v0": {f"{v:g}": _group([c for c in cases if c["v0"] == v], keys) for v in v0s},
        "all": _group(cases, keys), "cases": cases}


def unknown_ground_section(out: Path, files: list[str], st: Settings,
                           progress: bool) -> dict[str, Any]:
    """The reproduce section: the study, its figure and its data.

    Parameters
    ----------
    out : Path
        The run's folder (``data/`` exists).
    files : list of str
        Receives the names of the files written.
    st : Settings
        The run's grids (``unknown_v0``, ``unknown_stiffness``, ``unknown_drag``).
    progress : bool
        A progress bar over the cases.
    """
    from softlanding.control.mpc import DEFAULT_PERIOD
    from softlanding.model.terrain import paper_rig_units
    from softlanding.plots.control import plot_unknown_ground_study
    from softlanding.studies.unknown_ground import unknown_ground_study

    rows = unknown_ground_study(st.unknown_v0, st.unknown_stiffness, st.unknown_drag,
                                period=DEFAULT_PERIOD, progress=progress)
    save_figure(plot_unknown_ground_study(rows), out, "fig_unknown_ground", files)
    entry = unknown_ground_entry(rows, period=DEFAULT_PERIOD, tau_s=paper_rig_units().time)
    (out / "data" / "unknown_ground.json").write_text(json.dumps(json_safe(rows), indent=1))
    files.append("data/unknown_ground.json")
    _write_csv(out / "data" / "unknown_ground.csv", entry)
    files.append("data/unknown_ground.csv")
    return entry


def _write_csv(path: Path, entry: Mapping[str, Any]) -> None:
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["v0", "stiffness", "c_d", "clairvoyant_depth", "clairvoyant_verified",
                    "controller", "depth", "ratio", "feasible"])
        for c in entry["cases"]:
            for k in entry["controllers"]:
                w.writerow([c["v0"], c["stiffness"], c["c_d"], repr(c["clairvoyant_depth"]),
                            c["clairvoyant_verified"], k, repr(c[k]["depth"]),
                            repr(c[k]["ratio"]), c[k]["feasible"]])


def _worst(d: Mapping[str, Any], key: str) -> str:
    flag = "" if d["feasible"][key] == d["cases"] else " !"
    return f"{cell(d['worst'][key], 4)}{flag}"


def unknown_ground_markdown(s: Mapping[str, Any]) -> list[str]:
    """The section's lines of ``summary.md``.

    Parameters
    ----------
    s : dict
        The section's entry (:func:`unknown_ground_entry`).
    """
    keys, labels = s["controllers"], s["labels"]
    groups = [(v, d) for v, d in s["by_v0"].items()] + [("all", s["all"])]
    n_grounds = len(s["stiffness"]) * len(s["c_d"])
    p = s.get("robot")
    robot = ("The robot" if not p else
             f"The robot (r_m = {p['r_m']:g}, s = {p['s']:g}, u_max = "
             f"{'none' if p.get('u_max') is None else format(p['u_max'], 'g')})")
    out = ["## Landing on an unknown ground (fig_unknown_ground)", "",
           f"{robot} lands at v0 in {{{', '.join(f'{v:g}' for v in s['v0'])}}} on "
           f"{n_grounds} true grounds f = K d + c_d v_f^2, K in "
           f"{{{', '.join(f'{k:g}' for k in s['stiffness'])}}}, c_d in "
           f"{{{', '.join(f'{c:g}' for c in s['c_d'])}}}, none of them known to the "
           "controllers, against the clairvoyant optimum (solved for the true ground). "
           "Worst final depth over the grounds (x_s); `!`: on at least one ground a limit "
           "broken (stroke, force) or the rest not proven.", "",
           table(["v0", "clairvoyant"] + [labels[k] for k in keys],
                 [[v, cell(d["clairvoyant_worst"], 4)] + [_worst(d, k) for k in keys]
                  for v, d in groups[:-1]]), "",
           "Cases with every limit held and the rest proven (of the cases per v0):", "",
           table(["v0", "cases", "clairvoyant verified"] + [labels[k] for k in keys],
                 [[v, d["cases"], d["clairvoyant_verified"]] + [d["feasible"][k] for k in keys]
                  for v, d in groups]), ""]
    if "mpc" in keys:
        both = sum(not c["mpc"]["feasible"] and not c["clairvoyant_verified"]
                   for c in s["cases"])
        bad = s["all"]["cases"] - s["all"]["feasible"]["mpc"]
        if bad:
            out += [f"MPC landings with a limit broken or the rest not proven: {bad}; on a "
                    f"ground whose clairvoyant optimum is not verified either: {both} (where drag "
                    "stops the foot before the crater holds the robot's weight, the best landing "
                    "creeps down with a singular force, and no finite simulation proves rest).",
                    ""]
        rig = s["rig_period_ms"]
        out += [f"The MPC with on-line estimation (sample period {s['period']:g}, "
                f"{rig:.3g} ms on the paper's rig, tau_s = {1e3 * s['tau_s']:.3g} ms): depth "
                f"within {100 * (WITHIN - 1):.0f} % of the clairvoyant depth, never below it, "
                "and the wall time of one sample's estimate and re-plan (median and 99th "
                "percentile over every step of the cases) in ms on this machine and in periods "
                "of the rig (real time needs at most 1).", "",
                table(["v0", "cases", f"within {100 * (WITHIN - 1):.0f} %", "never below",
                       "largest ratio", "step median [ms]", "step p99 [ms]",
                       "median / rig period", "p99 / rig period"],
                      [[v, d["cases"], d["mpc"]["within_2_percent"], d["mpc"]["never_below"],
                        cell(d["mpc"]["max_ratio"], 4),
                        cell(d["mpc"]["step_time_median_ms"], 2),
                        cell(d["mpc"]["step_time_p99_ms"], 1),
                        cell(d["mpc"]["step_time_median_ms"] / rig, 1),
                        cell(d["mpc"]["step_time_p99_ms"] / rig, 0)] for v, d in groups]), ""]
    return out


UNKNOWN_GROUND_SECTION = Section(
    "unknown_ground", "unknown ground",
    lambda c: unknown_ground_section(c.out, c.files, c.settings, c.progress),
    unknown_ground_markdown)

__all__ = ["BELOW_TOL", "UNKNOWN_GROUND_SECTION", "WITHIN", "unknown_ground_entry",
           "unknown_ground_markdown", "unknown_ground_section"]
