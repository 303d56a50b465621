"""Figures of landings under feedback on an unknown ground."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from softlanding.model.ground import ground_label


def plot_mpc_landing(mpc: Any, clairvoyant: Any = None, open_loop: Any = None) -> plt.Figure:
    """Foot depth and actuator force against time: the MPC landing, and for comparison the
    clairvoyant optimum's replay and the nominal open-loop plan on the true ground.

    Parameters
    ----------
    mpc : MPCLanding
        The landing under MPC.
    clairvoyant, open_loop : LandingResult, optional
        Exact simulations on the true ground (of the clairvoyant optimum's schedule, of the
        nominal plan's).
    """
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 5.5))
    tr = mpc.trajectory()
    end = max([float(tr.t[-1])] + [1.05 * r.T for r in (clairvoyant, open_loop)
                                   if r is not None and r.T == r.T])
    for res, label, style in ((open_loop, "nominal open-loop plan", "C3--"),
                              (clairvoyant, "clairvoyant optimum", "k:")):
        if res is not None:
            ref = res.trajectory(t_end=end, n=800)
            a1.plot(ref.t, -ref.x[:, 2], style, lw=1.2, label=f"{label}: {res.depth:.4f}")
            a2.plot(ref.t, ref.u[:, 0], style, lw=1.0)
    a1.plot(tr.t, -tr.x[:, 2], "C0", lw=1.8, label=f"MPC with estimation: {mpc.depth:.4f}")
    a2.plot(tr.t, tr.u[:, 0], "C0", lw=1.4)
    a1.invert_yaxis()
    a1.set_ylabel(r"foot depth $-x_f$ [$x_s$]")
    a2.set_ylabel(r"force $u$ [$m_t g$]")
    a2.set_xlabel(r"time $\tau$ [$\sqrt{m_t/k_g}$]")
    a1.legend(fontsize=8, loc="upper right", title="final depth", title_fontsize=8)
    for ax in (a1, a2):
        ax.grid(alpha=0.3)
    fig.suptitle(f"Landing at $v_0$={mpc.impact.v0:g} on an unknown ground "
                 f"({ground_label(mpc.ground)}); sample period {mpc.period:g}", fontsize=10)
    fig.tight_layout()
    return fig



def plot_robust_landing(robust: Any, tree: Any = None,
                        clairvoyant: Sequence[float] | None = None) -> plt.Figure:
    """The depth on every ground of a set: the nominal plan replayed, the robust open-loop
    schedule, the two-stage tree and the clairvoyant optimum; a hatched bar broke a limit.

    Parameters
    ----------
    robust : RobustLanding
        The robust open-loop landing (its grounds and nominal replays).
    tree : RobustLanding, optional
        The two-stage tree on the same grounds.
    clairvoyant : sequence of float, optional
        The clairvoyant depth on each ground.
    """
    series = [("nominal open-loop", robust.nominal, "C3"), ("robust open-loop",
                                                            robust.landings, "C0")]
    if tree is not None:
        series.append(("two-stage tree", tree.landings, "C2"))
    n = len(robust.grounds)
    width = 0.8 / (len(series) + (clairvoyant is not None))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.55 * n * (len(series) + 1)), 4.2))
    x = np.arange(n)
    for k, (label, landings, colour) in enumerate(series):
        depths = [g.depth for g in landings]
        bars = ax.bar(x + k * width, depths, width, color=colour,
                      label=f"{label} (worst {max(depths):.4g})")
        for b, g in zip(bars, landings, strict=True):
            if not g.feasible:
                b.set_hatch("///")
                b.set_facecolor("white")
                b.set_edgecolor(colour)
    if clairvoyant is not None:
        ax.bar(x + len(series) * width, clairvoyant, width, color="0.3",
               label=f"clairvoyant (worst {max(clairvoyant):.4g})")
    ax.set_xticks(x + width * (len(series) - (clairvoyant is None)) / 2,
                  [ground_label(g).replace("ground: ", "") for g in robust.grounds],
                  rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(r"final depth $-x_f$ [$x_s$]")
    ax.set_xlabel("true ground")
    ax.legend(fontsize=8, title="hatched: a limit broken (stroke or rest)", title_fontsize=8)
    p = robust.robot
    ax.set_title(f"One plan for {n} grounds: $v_0$={robust.impact.v0:g}, $r_m$={p.r_m:g}, "
                 f"$s$={p.s:g}, $u_{{max}}$={p.u_max:g}", fontsize=10)
    fig.tight_layout()
    return fig


#: The unknown-ground study's controllers (keys of its rows) in the order drawn and tabled,
#: with their labels; a key a row has and this lacks is drawn after these, labelled by its key.
STUDY_CONTROLLERS: Mapping[str, str] = {
    "open_loop": "nominal open-loop plan",
    "robust": "robust open-loop schedule",
    "tree": "two-stage tree",
    "impedance_nominal": "impedance tuned for the paper's ground",
    "impedance_worst": "impedance tuned for the worst case",
    "mpc": "MPC with estimation",
}
_STUDY_STYLE = {"open_loop": ("C3", "v"), "robust": ("C0", "s"), "tree": ("C2", "D"),
                "impedance_nominal": ("C1", "^"), "impedance_worst": ("C4", "<"),
                "mpc": ("k", "o")}


def study_controllers(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The controllers every row of the unknown-ground study has, in the order of
    :data:`STUDY_CONTROLLERS` (then any other, in the rows' order).

    Parameters
    ----------
    rows : sequence of dict
        From :func:`softlanding.studies.unknown_ground_study`.
    """
    def is_controller(key: str) -> bool:
        return all(isinstance(r.get(key), Mapping) and "ratio" in r[key] for r in rows)

    seen = [k for k in STUDY_CONTROLLERS if rows and is_controller(k)]
    extra = [k for k in (rows[0] if rows else {}) if k not in seen and is_controller(k)]
    return seen + extra


def study_ground(row: Mapping[str, Any]) -> tuple[float, float]:
    """A study row's true ground as ``(K, c_d)``.

    Parameters
    ----------
    row : dict
        One row of :func:`softlanding.studies.unknown_ground_study`.
    """
    g = row["ground"]
    return float(g.get("stiffness", 1.0)), float(g.get("c_d", 0.0))


def _robot_title(rows: Sequence[Mapping[str, Any]]) -> str:
    robot = next((r["mpc"].get("robot") for r in rows if isinstance(r.get("mpc"), Mapping)),
                 None)
    if not robot:
        return "the robot"
    from softlanding.model.robot import PAPER_ROBOT

    name = "the paper's robot" if robot == PAPER_ROBOT.to_dict() else "the robot"
    return (f"{name} ($r_m$={robot['r_m']:g}, $s$={robot['s']:g}, "
            f"$u_{{max}}$={robot.get('u_max', float('inf')):g})")


def plot_unknown_ground_study(rows: Sequence[Mapping[str, Any]],
                              controllers: Sequence[str] | None = None) -> plt.Figure:
    """The unknown-ground study: each controller's depth over the clairvoyant depth on every
    true ground, one panel per impact velocity; a hollow marker broke a limit or its rest is
    not proven, a grey band is a ground whose clairvoyant optimum is not verified.

    Parameters
    ----------
    rows : sequence of dict
        From :func:`softlanding.studies.unknown_ground_study` (or read back from its JSON).
    controllers : sequence of str, optional
        The controllers drawn (keys of the rows); every one the rows have by default
        (:func:`study_controllers`).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    keys = list(controllers) if controllers is not None else study_controllers(rows)
    v0s = list(dict.fromkeys(r["v0"] for r in rows))
    grounds = sorted({study_ground(r) for r in rows})
    fig, axes = plt.subplots(len(v0s), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(max(7.5, 0.2 * len(grounds) * max(3, len(keys)) + 1.5),
                                      max(4.6, 1.4 + 2.2 * len(v0s))))
    x = np.arange(len(grounds))
    width = 0.8 / max(1, len(keys))
    colours = iter(f"C{i}" for i in range(5, 10))
    style = {k: _STUDY_STYLE.get(k) or (next(colours, "0.5"), "P") for k in keys}
    for ax, v0 in zip(axes[:, 0], v0s, strict=True):
        mine = {study_ground(r): r for r in rows if r["v0"] == v0}
        ax.axhline(1.0, color="0.4", lw=0.8, ls="--", zorder=1)
        for i, g in enumerate(grounds):
            if g in mine and not mine[g].get("clairvoyant_verified", True):
                ax.axvspan(i - 0.5, i + 0.5, color="0.88", zorder=0, lw=0)
        for k, key in enumerate(keys):
            colour, marker = style[key]
            at = [(i, mine[g][key]) for i, g in enumerate(grounds) if g in mine]
            xs = np.array([i for i, _ in at]) + (k - (len(keys) - 1) / 2) * width
            ys = np.array([c["ratio"] for _, c in at])
            ok = np.array([bool(c["feasible"]) for _, c in at])
            ax.vlines(xs, 1.0, ys, colors=colour, lw=1.0, alpha=0.5, zorder=2)
            ax.scatter(xs[ok], ys[ok], s=34, marker=marker, color=colour, zorder=3)
            ax.scatter(xs[~ok], ys[~ok], s=40, marker=marker, facecolors="white",
                       edgecolors=colour, linewidths=1.4, zorder=3)
        ax.set_ylabel(r"depth / clairvoyant depth $d/d^*$", fontsize=9)
        ax.margins(y=0.08)
        ax.set_title(f"impact velocity $v_0$ = {v0:g}", fontsize=9, loc="left")
        ax.grid(axis="y", alpha=0.3)
        for i in range(1, len(grounds)):  # darker where K changes
            new_k = grounds[i][0] != grounds[i - 1][0]
            ax.axvline(i - 0.5, color="0.55" if new_k else "0.85", lw=0.8 if new_k else 0.6,
                       zorder=0)
    bottom = axes[-1, 0]
    bottom.set_xticks(x, [f"$K$={k:g}\n$c_d$={c:g}" for k, c in grounds], fontsize=8)
    bottom.set_xlim(-0.5, len(grounds) - 0.5)
    bottom.set_xlabel(r"true ground $f = K d + c_d \dot{x}_f^2$ (paper's ground: $K$=1, $c_d$=0)")
    handles: list[Any] = [Line2D([], [], ls="", marker=style[k][1], color=style[k][0],
                                 label=STUDY_CONTROLLERS.get(k, k.replace("_", " ")))
                          for k in keys]
    handles += [Line2D([], [], ls="", marker="o", markerfacecolor="white",
                       markeredgecolor="0.3", label="hollow: a limit broken or rest not proven"),
                Line2D([], [], ls="--", color="0.4", lw=0.8,
                       label="1: the clairvoyant optimum (knows the ground)"),
                Patch(color="0.88", label="grey: clairvoyant optimum not verified")]
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=8,
               frameon=False)
    fig.suptitle(f"Landing on a ground the controller does not know: {_robot_title(rows)}",
                 fontsize=10)
    return fig


__all__ = ["STUDY_CONTROLLERS", "plot_mpc_landing", "plot_robust_landing",
           "plot_unknown_ground_study", "study_controllers", "study_ground"]
