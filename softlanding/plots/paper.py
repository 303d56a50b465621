"""Figures in the style of the paper; one function per figure.

All functions return a :class:`matplotlib.figure.Figure` and never call
``plt.show()``; save with ``fig.savefig(path)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import matplotlib.patches
import matplotlib.pyplot as plt
import numpy as np

from softlanding.model.ground import LINEAR_GROUND, Ground, ground_label, ground_of_attrs
from softlanding.model.robot import PAPER_ROBOT, Robot
from softlanding.simulation.simulator import LandingResult

MODE_COLOURS = {"yielding": "#f4cccc", "static": "#d9ead3", "flight": "#cfe2f3"}


def _shade_modes(ax, traj) -> None:
    """Shade the background by ground mode."""
    m = traj.mode
    edges = np.flatnonzero(m[1:] != m[:-1]) + 1
    starts = np.r_[0, edges]
    ends = np.r_[edges, len(m) - 1]
    for a, b in zip(starts, ends, strict=True):
        ax.axvspan(traj.t[a], traj.t[b], color=MODE_COLOURS[m[a]], lw=0, zorder=0)


_DEPTH_PHRASE = {"final": "depth {:.4f}", "limit": "depth $\\to$ {:.4f} (limit)",
                 "reached": "depth {:.4f} reached, rest not proven"}


def plot_trajectory(result: LandingResult, title: str | None = None) -> plt.Figure:
    """Body and foot heights, actuator force and ground mode against time.

    The background colour gives the ground mode (red: yielding, green: static,
    blue: flight); the dashed line is the crater bottom.

    Parameters
    ----------
    result : LandingResult
        A simulated landing.
    title : str, optional
        Figure title (default: the controller and the impact).
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
    ax2.plot(traj.t, traj.u[:, 0], color="C2")
    ax2.set_ylabel(r"force $u$ [$m_t g$]")
    ax2.set_xlabel(r"time $\tau$ [$\sqrt{m_t / k_g}$]")
    handles = [matplotlib.patches.Patch(color=c, label=n) for n, c in MODE_COLOURS.items()]
    ax2.legend(handles=handles, loc="best", fontsize=8, title="ground mode", title_fontsize=8)
    r = result.robot
    ax1.set_title(title or (f"{result.controller.describe()}; $v_0$={result.impact.v0:g}, "
                            f"$r_m$={r.r_m:g}, $s$={r.s:g}: "
                            + _DEPTH_PHRASE[result.depth_kind].format(result.depth)
                            + f", {result.steps} step(s)"
                            + ("" if result.depth_kind == "final" else " simulated")
                            + f"; {ground_label(result.ground)}"),
                  fontsize=9)
    fig.tight_layout()
    return fig


def _axes(ax, figsize):
    if ax is None:
        return plt.subplots(figsize=figsize)
    return ax.figure, ax


def plot_stepped_intrusions(results: Sequence[LandingResult], ax=None) -> plt.Figure:
    """Foot height against time for several landings (the paper's stepped-intrusion figure),
    all drawn to the same time (1.2 x the latest foot stop).

    Parameters
    ----------
    results : sequence of LandingResult
        The landings.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).
    """
    fig, ax = _axes(ax, (6.5, 4.0))
    t_end = 1.2 * max(r.T for r in results)
    for r in results:
        tr = r.trajectory(t_end=t_end, n=400)  # the events are added: every corner exact
        ax.plot(tr.t, tr.x[:, 2],
                label=f"{r.controller.describe()}: {r.steps} step(s), depth {r.depth:.3f}")
    ax.set_xlabel(r"time $\tau$ [$\sqrt{m_t / k_g}$]")
    ax.set_ylabel(r"foot height $x_f$ [$x_s = m_t g / k_g$]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def plot_depth_vs_velocity(v0: np.ndarray, curves: dict[str, np.ndarray], ax=None,
                           colours: dict[str, str] | None = None) -> plt.Figure:
    """Penetration depth against impact velocity for several policies (label -> depths).

    Parameters
    ----------
    v0 : ndarray
        Impact velocities.
    curves : dict
        Label -> depths at ``v0``.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).
    colours : dict, optional
        Label -> colour.
    """
    fig, ax = _axes(ax, (6.4, 4.4))
    markers = "os^vD"
    for i, (label, depth) in enumerate(curves.items()):
        ax.plot(v0, depth, marker=markers[i % len(markers)], ms=3, label=label,
                color=(colours or {}).get(label))
    ax.axhline(1.0, color="0.5", ls=":", lw=1, label="lower bound $-x_f$ = 1")
    ax.set_xlabel(r"impact velocity $v_0$ [$x_s / \tau_s$]")
    ax.set_ylabel(r"penetration depth $-x_f(T)$ [$x_s$]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def plot_bang_bang(landing) -> plt.Figure:
    """The paper's bang-bang trajectory figure: positions, velocities and force against time.

    Left: the foot's motion, from the refined (exact-arc) solution when there is
    one, switches dashed and the foot's stop dash-dotted. Right (when the
    landing was replayed): the whole landing in the exact simulator, through
    the arrest force until the body stops, then the body's weight.

    Parameters
    ----------
    landing : BangBangLanding
        A solved landing (its refined schedule is plotted).
    """
    if landing.refined is not None:
        t, x, u = landing.refined.sample(800)
    else:
        t, x, uu = landing.transcribed.sample(800)
        u = uu[:, 0]
    # the whole landing only when its replay comes to rest (else there is no end to draw)
    ncol = 1 if landing.replay is None or not landing.replay.rest_proven else 2
    fig, axes = plt.subplots(3, ncol, sharex="col", figsize=(6.5 + 4.5 * (ncol - 1), 7.0),
                             squeeze=False, gridspec_kw={"width_ratios": [1.3, 1][:ncol]})
    cols: list[tuple[Any, Any, Any, str | None]] = [(t, x, u, "post")]
    if ncol == 2:
        t_rest = landing.schedule().times[-1]
        tr = landing.replay.trajectory(t_end=1.1 * t_rest)
        cols.append((tr.t, tr.x, tr.u[:, 0], None))
    for j, (tt, xx, uu, where) in enumerate(cols):
        a1, a2, a3 = axes[:, j]
        a1.plot(tt, xx[:, 0], label=r"body $x_b$")
        a1.plot(tt, xx[:, 2], label=r"foot $x_f$", color="C3")
        a2.plot(tt, xx[:, 1], label=r"body $\dot x_b$")
        a2.plot(tt, xx[:, 3], label=r"foot $\dot x_f$", color="C3")
        if where:
            a3.step(tt, uu, where=where, color="C2")
        else:
            a3.plot(tt, uu, color="C2")
        a3.set_xlabel(r"time $\tau$ [$\sqrt{m_t/k_g}$]")
        for ax in (a1, a2, a3):
            for t0, t1 in _boundary_spans(landing):
                ax.axvspan(t0, t1, color="#fde0c5", lw=0, zorder=0)
            for ts in landing.switch_times:
                ax.axvline(ts, color="0.3", ls="--", lw=0.8)
            ax.axvline(landing.T, color="0.5", ls="-.", lw=0.8)
            if j == 1:
                ax.axvline(t_rest, color="0.5", ls=":", lw=1.0)
            ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel(r"height [$x_s$]")
    axes[1, 0].set_ylabel(r"velocity [$x_s/\tau_s$]")
    axes[2, 0].set_ylabel(r"force $u$ [$m_t g$]")
    axes[0, 0].legend(fontsize=8)
    axes[1, 0].legend(fontsize=8)
    from matplotlib.lines import Line2D

    events: list[Any] = [Line2D([], [], color="0.3", ls="--", lw=0.8, label="switch of u"),
              Line2D([], [], color="0.5", ls="-.", lw=0.8, label="foot stops (T)")]
    if ncol == 2:
        events.append(Line2D([], [], color="0.5", ls=":", lw=1.0, label="body stops"))
    if _boundary_spans(landing):
        events.append(matplotlib.patches.Patch(color="#fde0c5",
                                               label="boundary arc (stroke limit held)"))
    axes[2, ncol - 1].legend(handles=events, fontsize=8, loc="best")
    axes[0, 0].set_title("stance: until the foot stops", fontsize=9)
    if ncol == 2:
        axes[0, 1].set_title(f"whole landing (exact simulator): body stops at {t_rest:.3f}",
                             fontsize=9)
    p = landing.robot
    sw = ", ".join(f"{ts:.4f}" for ts in landing.switch_times)
    kind = "bang-bang" if not _boundary_spans(landing) else "optimal"
    fig.suptitle(f"{kind} landing, $v_0$={landing.impact.v0:g}, $r_m$={p.r_m:g}, "
                 f"$s$={p.s:g}, $u_{{max}}$={p.u_max:g}, {ground_label(landing.ground)}: "
                 f"depth {landing.depth:.6f}, "
                 f"switch at {sw}, "
                 f"foot stops at {landing.T:.4f}", fontsize=10)
    fig.tight_layout()
    return fig


def _boundary_spans(landing) -> list[tuple[float, float]]:
    """Time spans of the refined boundary arcs (a path constraint held)."""
    r = landing.refined
    if r is None:
        return []
    edges = np.r_[0.0, np.cumsum(r.durations)]
    return [(float(edges[i]), float(edges[i + 1])) for i, k in enumerate(r.kinds)
            if k == "boundary"]


def plot_depth_map(ds, optimum=None, ax=None) -> plt.Figure:
    """The paper's (k_p, k_d) map: depth normalised by its feasible minimum.

    Infeasible gains (the stroke is left) are blank; the optimum is starred.

    Parameters
    ----------
    ds : xarray.Dataset
        A depth map (:func:`~softlanding.studies.sweeps.depth_map`).
    optimum : ImpedanceOptimum, optional
        Starred on the map.
    ax : matplotlib Axes, optional
        Draw into it (default: a new figure).
    """
    own = ax is None
    fig, ax = _axes(ax, (5.8, 4.6))
    d = ds.depth.where(ds.strictly_feasible)
    dmin = optimum.depth if optimum is not None else float(d.min())
    im = ax.pcolormesh(ds.k_p, ds.k_d, (d / dmin).T, shading="nearest", cmap="viridis",
                       vmin=1.0, rasterized=True)
    fig.colorbar(im, ax=ax, label=r"$x_f / x_f^*$ (depth / minimum depth)")
    if optimum is not None:
        ax.plot(optimum.k_p, optimum.k_d, "*", color="w", mec="k", ms=16)
        # said below the axes, where it covers no data
        ax.annotate(f"$\\star$ optimum: $k_p$={optimum.k_p:.4f}, $k_d$={optimum.k_d:.4f}",
                    xy=(0.0, -0.2), xycoords="axes fraction", fontsize=8, va="top")
    ax.set_xlabel(r"stiffness $k_p = K_p / k_g$")
    ax.set_ylabel(r"damping $k_d = K_d / \sqrt{m_t k_g}$")
    ax.set_title(f"$v_0$={float(ds.v0):g}, $r_m$={float(ds.r_m):g}, $s$={float(ds.s):g}; "
                 f"{ground_label(ground_of_attrs(ds.attrs))}\nblank: stroke limit exceeded",
                 fontsize=9)
    if own:  # a figure of its own: keep every label (and the optimum's line) inside it
        fig.tight_layout()
    return fig


def plot_optimal_curves(curves) -> plt.Figure:
    """k_p*, k_d* and depth* against ``|v0|`` for each (r_m, s) in the dataset.

    Parameters
    ----------
    curves : xarray.Dataset
        Optimal gains over v0 (:func:`~softlanding.studies.sweeps.optimal_impedance_curves`).
    """
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for r in curves.r_m.values:
        for s in curves.s.values:
            c = curves.sel(r_m=r, s=s)
            speed = np.abs(c.v0.values)
            lw = 2.5 if (r == 5 and s == 20) else 1.2
            lab = f"$r_m$={r:g}, $s$={s:g}"
            axes[0].plot(speed, c.k_p, lw=lw, label=lab)
            axes[1].plot(speed, c.k_d, lw=lw, label=lab)
            axes[2].plot(speed, c.depth, lw=lw, label=lab)
    for ax, lab in zip(axes, (r"optimal stiffness $k_p^*$", r"optimal damping $k_d^*$",
                              r"minimum depth $-x_f^*$ [$x_s$]"), strict=True):
        ax.set_xlabel(r"impact speed $|v_0|$ [$x_s/\tau_s$]")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"optimal impedance (objective: {curves.attrs.get('objective', 'depth')}; "
                 f"{ground_label(ground_of_attrs(curves.attrs))})", fontsize=10)
    fig.tight_layout()
    return fig


# ------------------------------------------------------------ reproduction set
#: One colour per controller, in every comparison figure.
CONTROLLER_COLOURS = {"rigid": "0.35", "impedance": "C0", "bang-bang": "C3",
                      "min-CoT impedance": "C2"}
STEP_COLOURS = ["#deebf7", "#9ecae1", "#4292c6", "#08519c", "#08306b"]


def plot_stepped_intrusion_figure(results: Sequence[LandingResult], maps) -> plt.Figure:
    """The paper's Fig. 3: (a) stepped trajectories, (b) step-count regions for several v0.

    Parameters
    ----------
    results : sequence of LandingResult
        The stepped landings of panel (a).
    maps : sequence of xarray.Dataset
        Depth maps whose step counts panel (b) shows.
    """
    fig = plt.figure(figsize=(14, 6.2))
    sub: Any = fig.subfigures(1, 2, width_ratios=[1, 1.5])
    ax = sub[0].subplots()
    plot_stepped_intrusions(results, ax=ax)
    p = results[0].robot
    ax.set_title(f"(a) $v_0$={results[0].impact.v0:g}, $r_m$={p.r_m:g}, $s$={p.s:g}",
                 fontsize=10)
    from matplotlib.colors import BoundaryNorm, ListedColormap

    n = len(maps)
    cols = 3 if n > 4 else 2
    rows = -(-n // cols)
    axes = sub[1].subplots(rows, cols, sharex=True, sharey=True, squeeze=False)
    cmap = ListedColormap(STEP_COLOURS)
    norm = BoundaryNorm([0.5, 1.5, 2.5, 3.5, 4.5, 5.5], cmap.N)
    for a, ds in zip(axes.flat, maps, strict=False):
        proven = ds.status.values == 0
        steps = np.where(proven, np.clip(ds.steps.values, 1, 5), np.nan)
        im = a.pcolormesh(ds.k_p, ds.k_d, steps.T, shading="nearest", cmap=cmap, norm=norm,
                          rasterized=True)
        if not proven.all():  # rest not proven: a step count would be meaningless
            a.pcolormesh(ds.k_p, ds.k_d, np.where(proven, np.nan, 1.0).T, shading="nearest",
                         cmap=ListedColormap(["#f4a582"]), rasterized=True)
        a.contour(ds.k_p, ds.k_d, ds.strictly_feasible.values.T.astype(float), levels=[0.5],
                  colors="k", linewidths=1.0)
        a.set_title(f"$v_0$ = {float(ds.v0):g}", fontsize=9)
    for a in axes.flat[n:]:
        a.set_visible(False)
    for a in axes[-1]:
        a.set_xlabel(r"stiffness $k_p$")
    for a in axes[:, 0]:
        a.set_ylabel(r"damping $k_d$")
    cb = sub[1].colorbar(im, ax=axes.ravel().tolist(), ticks=[1, 2, 3, 4, 5], shrink=0.9)
    cb.ax.set_yticklabels(["1", "2", "3", "4", "5+"])
    cb.set_label("intrusion steps (rest proven)")
    axes.flat[0].legend(handles=[matplotlib.patches.Patch(color="#f4a582",
                                                          label="rest not proven")],
                        fontsize=7, loc="upper right")
    sub[1].suptitle("(b) intrusion steps over the gains\n(black line: stroke limit; "
                    "gains below-left leave the stroke)", fontsize=10, y=0.99)
    return fig


def plot_depth_maps(maps, optima) -> plt.Figure:
    """The paper's Fig. 4: x_f/x_f* over (k_p, k_d) for several v0, optimum starred
    (one :func:`plot_depth_map` panel per v0).

    Parameters
    ----------
    maps : sequence of xarray.Dataset
        Depth maps, one per v0.
    optima : sequence of ImpedanceOptimum
        Their optima.
    """
    n = len(maps)
    cols = 2 if n <= 4 else 3
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.2 * rows), squeeze=False)
    for ax, ds, opt in zip(axes.flat, maps, optima, strict=False):
        plot_depth_map(ds, opt, ax=ax)
        ax.set_title(f"$v_0$ = {float(ds.v0):g}" + (f": $x_f^*$ = {opt.depth:.4f}"
                                                     if opt is not None else ""), fontsize=10)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.suptitle(f"Normalised depth, $r_m$={float(maps[0].r_m):g}, $s$={float(maps[0].s):g}, "
                 f"{ground_label(ground_of_attrs(maps[0].attrs))} "
                 "(blank: stroke limit exceeded; $\\star$: optimum)", fontsize=11)
    fig.tight_layout()
    return fig


def _on_box_edge(c, lo: float = 0.0, hi: float = 1.0, tol: float = 1e-9) -> np.ndarray:
    """Optima whose gains sit on the edge of the searched box (the box, not the stroke,
    binds there: a larger box might give a better optimum)."""
    kp, kd = c.k_p.values, c.k_d.values
    with np.errstate(invalid="ignore"):
        return ((np.abs(kp - lo) <= tol) | (np.abs(kp - hi) <= tol)
                | (np.abs(kd - lo) <= tol) | (np.abs(kd - hi) <= tol))


def plot_gain_families(curves) -> plt.Figure:
    """The paper's Fig. 5: k_p*(v0) and k_d*(v0); colour = r_m, line style = s, thick = (5, 20).

    Parameters
    ----------
    curves : xarray.Dataset
        Optimal gains over v0 for each (r_m, s).
    """
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    styles = ["--", "-", ":", "-."]
    for ir, r in enumerate(curves.r_m.values):
        for js, s in enumerate(curves.s.values):
            c = curves.sel(r_m=r, s=s)
            speed = np.abs(c.v0.values)
            thick = r == PAPER_ROBOT.r_m and s == PAPER_ROBOT.s
            kw = dict(color=f"C{ir}", ls=styles[js % len(styles)], lw=3.0 if thick else 1.3,
                      label=f"$r_m$={r:g}, $s$={s:g}")
            axes[0].plot(speed, c.k_p, **kw)
            axes[1].plot(speed, c.k_d, **kw)
            edge = _on_box_edge(c)
            for ax, var in ((axes[0], c.k_p), (axes[1], c.k_d)):
                ax.plot(speed[edge], var.values[edge], "s", mfc="none", color=f"C{ir}", ms=7)
    axes[0].set_ylabel(r"optimal stiffness $k_p^*$")
    axes[1].set_ylabel(r"optimal damping $k_d^*$")
    for ax in axes:
        ax.set_xlabel(r"impact speed $|v_0|$ [$x_s/\tau_s$]")
        ax.grid(alpha=0.3)
    from matplotlib.lines import Line2D

    handles, labels = axes[1].get_legend_handles_labels()
    handles.append(Line2D([], [], ls="", marker="s", mfc="none", color="0.3"))
    labels.append("optimum on the edge of the gain box $[0,1]^2$")
    axes[1].legend(handles, labels, fontsize=7, ncol=3, loc="upper left")
    fig.suptitle("Depth-optimal impedance against impact speed (thick: $r_m$=5, $s$=20; "
                 "colour: $r_m$; line style: $s$; gaps: no feasible gains in $[0,1]^2$)",
                 fontsize=10)
    fig.tight_layout()
    return fig


def plot_controller_comparison(cmp: dict[str, np.ndarray], robot: Robot = PAPER_ROBOT,
                               ground: Ground = LINEAR_GROUND) -> plt.Figure:
    """The paper's Fig. 6: depth against v0 for rigid, optimal impedance and bang-bang.

    Parameters
    ----------
    cmp : dict
        The columns of :func:`softlanding.studies.comparison.compare_controllers`.
    robot : Robot
        The robot compared (its force limit bounds the bang-bang force).
    ground : Ground
        The ground they landed on (named in the title).
    """
    r_m, s, u_max = robot.r_m, robot.s, robot.u_max
    bb = f"bang-bang force control ($u_{{max}}$={u_max:g})"
    fig = plot_depth_vs_velocity(
        cmp["v0"], {"rigid leg": cmp["rigid"], "optimal impedance": cmp["impedance"],
                    bb: cmp["bang_bang"]},
        colours={"rigid leg": CONTROLLER_COLOURS["rigid"],
                 "optimal impedance": CONTROLLER_COLOURS["impedance"],
                 bb: CONTROLLER_COLOURS["bang-bang"]})
    fig.axes[0].set_title(f"Depth against impact velocity, $r_m$={r_m:g}, $s$={s:g}, "
                          f"{ground_label(ground)}", fontsize=10)
    fig.tight_layout()
    return fig


def plot_experiment_curves(ds, si=None) -> plt.Figure:
    """The paper's Fig. 7b (simulated curves): depth against k_d for each k_p and v0.

    ``ds`` has dims ``(k_p, v0, k_d)`` (from :func:`softlanding.studies.sweeps.impedance_dataset`).
    Dotted where the landing leaves the stroke. With ``si`` (a
    :class:`~softlanding.model.scaling.PhysicalParams`) the axes are in SI units.

    Parameters
    ----------
    ds : xarray.Dataset
        Landings with dims ``(k_p, v0, k_d)``.
    si : PhysicalParams, optional
        A physical robot: axes in mm, N s/m and m/s.
    """
    units = None if si is None else si.units
    kps = ds.k_p.values
    fig, axes = plt.subplots(1, len(kps), figsize=(4.4 * len(kps), 4.0), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, kp in zip(axes, kps, strict=True):
        for iv, v in enumerate(ds.v0.values):
            c = ds.sel(k_p=kp, v0=v)
            kd = c.k_d.values
            depth = c.depth.values
            ok = c.strictly_feasible.values
            if si is None:
                x, y = kd, depth
                lab = f"$v_0$ = {v:g}"
            else:
                assert units is not None
                x = kd * units.damping
                y = depth * units.length * 1e3
                lab = f"$V_0$ = {abs(v) * units.velocity:.2f} m/s"
            ax.plot(x, np.where(ok, y, np.nan), color=f"C{iv}", label=lab)
            ax.plot(x, np.where(ok, np.nan, y), color=f"C{iv}", ls=":", lw=1)
            # an isolated point (k_d = 0) draws no line: mark where rest is not proven
            unproven = c.status.values != 0
            ax.plot(x[unproven], y[unproven], "x", color=f"C{iv}", ms=6)
            if ok.any():
                k = int(np.nanargmin(np.where(ok, depth, np.nan)))
                ax.plot(x[k], y[k], "o", color=f"C{iv}", ms=5)
        if si is None:
            ax.set_title(f"$k_p$ = {kp:g}", fontsize=10)
            ax.set_xlabel(r"damping $k_d$")
        else:
            ax.set_title(f"$K_p$ = {kp * si.k_g:.0f} N/m ($k_p$ = {kp:g})", fontsize=10)
            ax.set_xlabel(r"damping $K_d$ [N s/m]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(r"penetration depth $-x_f(T)$ [$x_s$]" if si is None
                       else "penetration depth [mm]")
    axes[0].legend(fontsize=8)
    where = ("" if si is None else
             f"; $m_b$={si.m_b:g} kg, $m_f$={si.m_f:g} kg, $k_g$={si.k_g / 1e3:g} kN/m")
    fig.suptitle(f"Simulated depth against damping ($r_m$={float(ds.r_m):g}, "
                 f"$s$={float(ds.s):g}{where}); dotted: stroke limit exceeded, "
                 "x: rest not proven (k_d = 0: the leg keeps hopping), dot: best damping",
                 fontsize=10)
    fig.tight_layout()
    return fig


def plot_cot_comparison(v0: np.ndarray, data: dict[str, np.ndarray]) -> plt.Figure:
    """The paper's Fig. 9: minimum-CoT vs minimum-depth impedance, (a) depth, (b) CoT.

    Parameters
    ----------
    v0 : ndarray
        Impact velocities.
    data : dict
        Columns of the CoT study (depth and CoT of each optimum).
    """
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.4))
    c = CONTROLLER_COLOURS
    a1.plot(v0, data["rigid_depth"], "o-", ms=3, color=c["rigid"], label="rigid leg")
    a1.plot(v0, data["depth_opt_depth"], "s-", ms=3, color=c["impedance"],
            label="min-depth impedance")
    a1.plot(v0, data["cot_opt_depth"], "^-", ms=3, color=c["min-CoT impedance"],
            label="min-CoT impedance (dissipative)")
    a1.plot(v0, data["cot_lossless_opt_depth"], "v--", ms=3, color="C4",
            label="min-CoT impedance (lossless)")
    a1.set_ylabel(r"penetration depth $-x_f(T)$ [$x_s$]")
    a1.set_title("(a) depth", fontsize=10)
    a2.plot(v0, data["rigid_cot"], "o-", ms=3, color=c["rigid"], label="rigid leg")
    a2.plot(v0, data["depth_opt_cot"], "s-", ms=3, color=c["impedance"],
            label="min-depth impedance, dissipative")
    a2.plot(v0, data["depth_opt_cot_lossless"], "s--", ms=3, color=c["impedance"],
            mfc="none", label="min-depth impedance, lossless")
    a2.plot(v0, data["cot_opt_cot"], "^-", ms=3, color=c["min-CoT impedance"],
            label="min-CoT impedance, dissipative")
    a2.set_ylabel(r"CoT $= (E(0) - E(T)) / E(0)$")
    a2.set_yscale("log")
    a2.set_title("(b) cost of transport", fontsize=10)
    for ax in (a1, a2):
        ax.set_xlabel(r"impact velocity $v_0$ [$x_s/\tau_s$]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle("Minimum-CoT against minimum-depth impedance ($r_m$=5, $s$=20); lossless: "
                 r"$E_{act}$ = 0, CoT = $E_{gnd}/E(0)$", fontsize=10)
    fig.tight_layout()
    return fig


ROBUSTNESS_TITLES = {"k_g": r"ground stiffness: true $k_g$ / nominal",
                     "r_m": r"mass ratio: true $r_m$ / nominal ($m_t$ fixed)",
                     "v0": r"impact velocity: true $v_0$ / nominal",
                     "switch": r"switch instant: actual / nominal"}


def plot_robustness(ds) -> plt.Figure:
    """Regret (depth / redesigned depth) against the model error, per parameter.

    Filled markers keep the stroke; crosses leave it (at any time).

    Parameters
    ----------
    ds : xarray.Dataset
        The robustness study (:func:`~softlanding.studies.robustness.robustness_study`).
    """
    params = list(ds.parameter.values)
    fig, axes = plt.subplots(1, len(params), figsize=(4.0 * len(params), 4.0), sharey=True)
    for ax, par in zip(axes, params, strict=True):
        for ctrl in ds.controller.values:
            for im, m in enumerate(ds.margin.values):
                d = ds.sel(controller=ctrl, margin=m, parameter=par)
                y = d.depth_ratio.values
                if not np.isfinite(y).any():
                    continue
                f = d.factor.values
                kept = d.stroke_kept.values
                col = CONTROLLER_COLOURS[str(ctrl)]
                lab = f"{ctrl}" + (f", {m:.0%} stroke margin" if m > 0 else ", no margin")
                # the margin curves often coincide with the no-margin ones: draw them on top,
                # dashed over a wide translucent band, so both stay visible
                if im == 0:
                    ax.plot(f, y, "-", color=col, lw=4, alpha=0.35, label=lab, zorder=2)
                else:
                    ax.plot(f, y, "--", color=col, lw=1.2, label=lab, zorder=3)
                ax.plot(f[kept], y[kept], "o", color=col, ms=4, mfc=col if im == 0 else "w",
                        zorder=4)
                ax.plot(f[~kept], y[~kept], "x", color=col, ms=7, mew=1.5, zorder=4)
        ax.axvline(1.0, color="0.6", lw=0.8)
        ax.set_xlabel(ROBUSTNESS_TITLES.get(str(par), str(par)), fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("depth / depth of the redesigned controller")
    axes[0].legend(fontsize=7, loc="upper center")
    a = ds.attrs
    fig.suptitle(f"Nominal controllers on a perturbed model ($v_0$={a['v0']:g}, "
                 f"$r_m$={a['r_m']:g}, $s$={a['s']:g}, bang-bang $u_{{max}}$={a['u_max']:g}); "
                 "o: stays within the stroke limits, x: leaves them", fontsize=10)
    fig.tight_layout()
    return fig
