"""Figures of landings under feedback on an unknown ground."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt

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
