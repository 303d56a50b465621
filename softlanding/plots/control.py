"""Figures of landings under feedback on an unknown ground."""

from __future__ import annotations

from collections.abc import Sequence
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


__all__ = ["plot_mpc_landing"]


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
