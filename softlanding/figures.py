"""Figures in the style of the paper; one function per figure.

All functions return a :class:`matplotlib.figure.Figure` and never call
``plt.show()``; save with ``fig.savefig(path)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg", force=False)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .simulate import MODE_NAMES, LandingResult  # noqa: E402

MODE_COLOURS = {"yielding": "#f4cccc", "static": "#d9ead3", "flight": "#cfe2f3"}


def _shade_modes(ax, traj) -> None:
    """Shade the background by ground mode."""
    m = traj.mode
    edges = np.flatnonzero(np.diff(m)) + 1
    starts = np.r_[0, edges]
    ends = np.r_[edges, len(m) - 1]
    for a, b in zip(starts, ends, strict=True):
        ax.axvspan(traj.t[a], traj.t[b], color=MODE_COLOURS[MODE_NAMES[m[a]]], lw=0, zorder=0)


def plot_trajectory(result: LandingResult, title: str | None = None) -> plt.Figure:
    """Body and foot heights, actuator force and ground mode against time.

    The background colour gives the ground mode (red: yielding, green: static,
    blue: flight); the dashed line is the crater bottom.
    """
    traj = result.trajectory()
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.0),
                                   gridspec_kw={"height_ratios": [2, 1]})
    for ax in (ax1, ax2):
        _shade_modes(ax, traj)
    ax1.plot(traj.t, traj.x[:, 0], label=r"body $x_b$", color="C0")
    ax1.plot(traj.t, traj.x[:, 2], label=r"foot $x_f$", color="C3")
    crater = -np.maximum.accumulate(np.maximum(-traj.x[:, 2], 0.0))
    ax1.plot(traj.t, crater, "k--", lw=0.8, label="crater bottom")
    ax1.axhline(0.0, color="0.4", lw=0.6)
    ax1.set_ylabel(r"height $x$ [$x_s = m_t g / k_g$]")
    ax1.legend(loc="best", fontsize=8)
    ax2.plot(traj.t, traj.u, color="C2")
    ax2.set_ylabel(r"force $u$ [$m_t g$]")
    ax2.set_xlabel(r"time $\tau$ [$\sqrt{m_t / k_g}$]")
    handles = [matplotlib.patches.Patch(color=c, label=n) for n, c in MODE_COLOURS.items()]
    ax2.legend(handles=handles, loc="best", fontsize=8, title="ground mode", title_fontsize=8)
    p = result.params
    ax1.set_title(title or (f"{result.policy.describe()}; $v_0$={p.v0:g}, $r_m$={p.r_m:g}, "
                            f"$s$={p.s:g}: depth {result.depth:.4f}, {result.steps} step(s)"),
                  fontsize=9)
    fig.tight_layout()
    return fig


def _axes(ax, figsize):
    if ax is None:
        return plt.subplots(figsize=figsize)
    return ax.figure, ax


def plot_stepped_intrusions(results: Sequence[LandingResult], ax=None) -> plt.Figure:
    """Foot height against time for several landings (the paper's stepped-intrusion figure)."""
    fig, ax = _axes(ax, (6.5, 4.0))
    for r in results:
        tr = r.trajectory()
        ax.plot(tr.t, tr.x[:, 2], label=f"{r.policy.describe()}: {r.steps} step(s)")
    ax.set_xlabel(r"time $\tau$ [$\sqrt{m_t / k_g}$]")
    ax.set_ylabel(r"foot height $x_f$ [$m_t g / k_g$]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def plot_depth_vs_velocity(v0: np.ndarray, curves: dict[str, np.ndarray], ax=None) -> plt.Figure:
    """Penetration depth against impact velocity for several policies."""
    fig, ax = _axes(ax, (6.0, 4.0))
    for label, depth in curves.items():
        ax.plot(v0, depth, "o-", ms=3, label=label)
    ax.axhline(1.0, color="0.5", ls=":", lw=1, label="lower bound (weight)")
    ax.set_xlabel(r"impact velocity $v_0$ [$x_s / \tau_s$]")
    ax.set_ylabel(r"penetration depth $-x_f(T)$ [$x_s$]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def plot_bang_bang(landing) -> plt.Figure:
    """The paper's bang-bang trajectory figure: positions, velocities and force against time.

    Uses the refined (exact-arc) solution when there is one; switches are marked.
    """
    if landing.refined is not None:
        t, x, u = landing.refined.sample(800)
    else:
        t, x, u = landing.transcribed.sample(800)
        u = u[:, 0]
    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(7.0, 7.0))
    a1.plot(t, x[:, 0], label=r"body $x_b$")
    a1.plot(t, x[:, 2], label=r"foot $x_f$", color="C3")
    a1.set_ylabel(r"height [$x_s$]")
    a2.plot(t, x[:, 1], label=r"body $\dot x_b$")
    a2.plot(t, x[:, 3], label=r"foot $\dot x_f$", color="C3")
    a2.set_ylabel(r"velocity [$x_s/\tau_s$]")
    a3.step(t, u, where="post", color="C2")
    a3.set_ylabel(r"force $u$ [$m_t g$]")
    a3.set_xlabel(r"time $\tau$ [$\sqrt{m_t/k_g}$]")
    for ax in (a1, a2, a3):
        for ts in landing.switch_times:
            ax.axvline(ts, color="0.3", ls="--", lw=0.8)
        ax.grid(alpha=0.3)
    a1.legend(fontsize=8)
    a2.legend(fontsize=8)
    p = landing.params
    sw = ", ".join(f"{ts:.4f}" for ts in landing.switch_times)
    a1.set_title(f"bang-bang landing, $v_0$={p.v0:g}, $r_m$={p.r_m:g}, $s$={p.s:g}, "
                 f"$u_{{max}}$={p.u_max:g}: depth {landing.depth:.6f}, switch at {sw}",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_depth_map(ds, optimum=None, ax=None) -> plt.Figure:
    """The paper's (k_p, k_d) map: depth normalised by its feasible minimum.

    Infeasible gains (the stroke is left) are blank; the optimum is starred.
    """
    fig, ax = _axes(ax, (5.8, 4.6))
    d = ds.depth.where(ds.strictly_feasible)
    dmin = float(d.min())
    im = ax.pcolormesh(ds.k_p, ds.k_d, (d / dmin).T, shading="nearest", cmap="viridis")
    fig.colorbar(im, ax=ax, label=r"$x_f / x_f^*$ (depth / minimum depth)")
    if optimum is not None:
        ax.plot(optimum.kp, optimum.kd, "*", color="w", mec="k", ms=16,
                label=f"optimum ($k_p$={optimum.kp:.4f}, $k_d$={optimum.kd:.4f})")
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel(r"stiffness $k_p = K_p / k_g$")
    ax.set_ylabel(r"damping $k_d = K_d / \sqrt{m_t k_g}$")
    ax.set_title(f"$v_0$={float(ds.v0):g}, $r_m$={float(ds.r_m):g}, $s$={float(ds.s):g}; "
                 f"blank: stroke limit exceeded", fontsize=9)
    return fig


def plot_optimal_curves(curves) -> plt.Figure:
    """k_p*, k_d* and depth* against |v0| for each (r_m, s) in the dataset."""
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for r in curves.r_m.values:
        for s in curves.s.values:
            c = curves.sel(r_m=r, s=s)
            speed = np.abs(c.v0.values)
            lw = 2.5 if (r == 5 and s == 20) else 1.2
            lab = f"$r_m$={r:g}, $s$={s:g}"
            axes[0].plot(speed, c.kp, lw=lw, label=lab)
            axes[1].plot(speed, c.kd, lw=lw, label=lab)
            axes[2].plot(speed, c.depth, lw=lw, label=lab)
    for ax, lab in zip(axes, (r"optimal stiffness $k_p^*$", r"optimal damping $k_d^*$",
                              r"minimum depth $-x_f^*$ [$x_s$]"), strict=True):
        ax.set_xlabel(r"impact speed $|v_0|$ [$x_s/\tau_s$]")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"optimal impedance (objective: {curves.attrs.get('objective', 'depth')})",
                 fontsize=10)
    fig.tight_layout()
    return fig
