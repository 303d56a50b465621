"""Figures of the hybrid studies: phases shaded and labelled, and the three findings.

Every function returns a :class:`matplotlib.figure.Figure` (nothing is shown or
saved here).
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from softlanding.model.ground import LINEAR_GROUND, ground_label

PHASE_COLOURS = {"yielding": "#f4c7a1", "static": "#b9d7ea", "flight": "#d9ead3",
                 "flight up": "#d9ead3", "flight down": "#d9ead3"}


def _colour(name: str) -> str:
    for key, c in PHASE_COLOURS.items():
        if name.startswith(key):
            return c
    return "0.9"


def shade_phases(axes: Sequence[Any], spans: list[tuple[float, float, str]]) -> None:
    """Shade and label ``(start, end, name)`` spans on every axis (labels on the first).

    Parameters
    ----------
    axes : sequence of matplotlib axes
        Axes sharing the time axis.
    spans : list of (float, float, str)
        Phase start, end and name.
    """
    for ax in axes:
        for a, b, name in spans:
            ax.axvspan(a, b, color=_colour(name), alpha=0.55, lw=0, zorder=0)
    top = axes[0]
    lo, hi = top.get_xlim()
    for a, b, name in spans:
        if b - a >= 0.06 * (hi - lo):  # a sliver's label would overprint its neighbours'
            top.text(0.5 * (a + b), 1.0, name, transform=top.get_xaxis_transform(),
                     ha="center", va="bottom", fontsize=8)


def plot_phases(t: np.ndarray, x: np.ndarray, u: np.ndarray,
                spans: list[tuple[float, float, str]], title: str,
                switches: Sequence[float] = ()) -> plt.Figure:
    """Heights, velocities and force against time with the phases shaded and labelled.

    Parameters
    ----------
    t : ndarray (n,)
        Times.
    x : ndarray (n, >= 4)
        States ``x_b, v_b, x_f, v_f``.
    u : ndarray (n,)
        Force.
    spans : list of (float, float, str)
        Phases.
    title : str
        Figure title.
    switches : sequence of float
        Switch times (dashed).
    """
    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(8.0, 7.0))
    a1.plot(t, x[:, 0], label=r"body $x_b$")
    a1.plot(t, x[:, 2], label=r"foot $x_f$", color="C3")
    a2.plot(t, x[:, 1], label=r"body $\dot x_b$")
    a2.plot(t, x[:, 3], label=r"foot $\dot x_f$", color="C3")
    a3.plot(t, u, color="C2")
    for ax in (a1, a2, a3):
        for ts in switches:
            ax.axvline(ts, color="0.3", ls="--", lw=0.8)
        ax.grid(alpha=0.3)
    shade_phases([a1, a2, a3], spans)
    a1.set_ylabel(r"height [$x_s$]")
    a2.set_ylabel(r"velocity [$x_s/\tau_s$]")
    a3.set_ylabel(r"force $u$ [$m_t g$]")
    a3.set_xlabel(r"time $\tau$ [$\sqrt{m_t/k_g}$]")
    a1.legend(fontsize=8, loc="best")
    a2.legend(fontsize=8, loc="best")
    fig.suptitle(wrapped_title(title), fontsize=10)
    fig.tight_layout()
    return fig


TITLE_WIDTH = 90
"""Characters per line of a figure's title (about the width of an 8-inch figure at 10 pt)."""


def wrapped_title(title: str, width: int = TITLE_WIDTH) -> str:
    """``title`` broken into lines of at most ``width`` characters (a long title would run
    off both sides of the figure), never inside a ``$...$`` formula.

    Parameters
    ----------
    title : str
        The title on one line.
    width : int
        Characters per line (mathtext counts as its source).
    """
    words = title.split(" ")
    merged: list[str] = []  # words, with a formula's spaces kept inside one word
    for w in words:
        if merged and merged[-1].count("$") % 2:
            merged[-1] += " " + w
        else:
            merged.append(w)
    lines = textwrap.wrap(" ".join(w.replace(" ", "\0") for w in merged), width,
                          break_long_words=False, break_on_hyphens=False)
    return "\n".join(line.replace("\0", " ") for line in lines)


def plot_variant_sweep(v0: np.ndarray, depth: np.ndarray, label: str,
                       objective: tuple[str, np.ndarray] | None = None,
                       references: dict[str, np.ndarray] | None = None) -> plt.Figure:
    """A variant's sweep over ``v0``: the depth and, for a variant that minimises
    something else (the peak force within a depth budget...), its objective in a second
    panel.

    Parameters
    ----------
    v0 : ndarray
        Impact velocities.
    depth : ndarray
        The depth at each.
    label : str
        The variant's name.
    objective : (str, ndarray), optional
        The objective's name and values (None: the depth is the objective).
    references : dict, optional
        Other depths at ``v0`` for scale (label -> depths: the rigid leg's...), drawn
        first on the depth panel.
    """
    fig, axes = plt.subplots(1, 1 if objective is None else 2, squeeze=False,
                             figsize=(6.4 if objective is None else 11.0, 4.4))
    a = axes[0, 0]
    for i, (name, values) in enumerate((references or {}).items()):
        a.plot(v0, values, f"C{i + 1}s--", ms=3, lw=1, label=name)
    a.plot(v0, depth, "C0o-", ms=3, label=label)
    a.set_xlabel(r"impact velocity $v_0$ [$x_s / \tau_s$]")
    a.set_ylabel(r"penetration depth $-x_f(T)$ [$x_s$]")
    a.set_title("depth", fontsize=9)
    a.legend(fontsize=8)
    if objective is not None:
        what, values = objective
        b = axes[0, 1]
        b.plot(v0, values, "C3o-", ms=3, label=label)
        b.set_xlabel(r"impact velocity $v_0$ [$x_s / \tau_s$]")
        b.set_ylabel(what)
        b.set_title(f"objective: {what}", fontsize=9)
        b.legend(fontsize=8)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _refined_spans(ref: Any) -> list[tuple[float, float, str]]:
    ends = [float(t) for t in ref.t0] + [float(ref.T)]
    return [(a, b, r.problem.name) for a, b, r in zip(ends[:-1], ends[1:], ref.phases,
                                                      strict=True)]


def plot_phased_landing(res: Any) -> plt.Figure:
    """A phased landing (two-phase, leg extension, any variant on the pipeline): the refined
    exact arcs, or the transcription when there is no refinement, phases shaded.

    Parameters
    ----------
    res : PhasedLanding
        A solved landing (its ``label`` heads the title).
    """
    ref = res.refined
    if ref is not None:
        tr = ref.trajectory(1200)
        sw = [t for ph in ref.switch_times for t in ph]
        spans = _refined_spans(ref)
        what = ""
    elif res.transcribed is not None:
        tr = res.transcribed.trajectory(1200)
        sw = []
        ends = [float(t) for t in res.phase_times]
        spans = [(a, b, p.problem.name) for a, b, p in zip(ends[:-1], ends[1:],
                                                           res.transcribed.phases, strict=True)]
        smooth = getattr(res, "smooth", None)
        what = f" (smooth, mesh {smooth.convergence})" if smooth is not None else \
            " (transcribed, not refined)"
    else:
        raise ValueError("neither a refinement nor a transcription to plot")
    p = res.robot
    title = (f"{res.label}{what}, $v_0$={res.impact.v0:g}, $r_m$={p.r_m:g}, $s$={p.s:g}, "
             f"$u_{{max}}$={p.u_max:g}, {ground_label(getattr(res, 'ground', LINEAR_GROUND))}: "
             f"depth {res.depth:.6f} ({res.REFERENCE}: {res.paper_depth:.6f})")
    return plot_phases(tr.t, tr.x, tr.u[:, 0], spans, title, sw)


def plot_hop(cycle: Any) -> plt.Figure:
    """One hop cycle from its exact simulations, ground modes shaded and labelled.

    Parameters
    ----------
    cycle : HopCycle
        A solved cycle.
    """
    tr = cycle.trajectory(1500)
    # shade what the foot does: a "yielding" foot held still at exactly the crater's
    # capacity (the optimum pushes with just that force; it creeps by rounding, ~1e-9) is
    # at rest, not sinking
    still = np.abs(tr.x[:, 3]) <= 1e-6 * max(1.0, abs(cycle.impact.v0))
    modes = np.where((np.asarray(tr.mode) == "yielding") & still, "static", tr.mode)
    spans = []
    k = 0
    for i in range(1, len(tr.t) + 1):
        if i == len(tr.t) or modes[i] != modes[k]:
            spans.append((float(tr.t[k]), float(tr.t[min(i, len(tr.t) - 1)]), str(modes[k])))
            k = i
    merged: list[tuple[float, float, str]] = []
    for a, b, name in spans:
        if merged and merged[-1][2] == name:
            merged[-1] = (merged[-1][0], b, name)
        else:
            merged.append((a, b, name))
    extra = "" if not cycle.gains else ", " + ", ".join(f"{k_}={v:.3g}"
                                                        for k_, v in cycle.gains.items())
    title = (f"hop ({cycle.leg}{extra}), $v_0$={cycle.impact.v0:g}, apex "
             f"{cycle.apex_height:.3g}, $\\eta$={cycle.eta:g}: energy {cycle.energy:.4f} "
             f"per cycle, crater {cycle.depth:.4f}")
    return plot_phases(tr.t, tr.x, tr.u[:, 0], merged, title)


def _depth_panel(a: Any, title: str) -> None:
    """Labels of a depth-against-v0 panel."""
    a.set_xlabel(r"$v_0$")
    a.set_ylabel("depth")
    a.legend(fontsize=8, loc="upper right")
    a.set_title(title, fontsize=9)


def plot_hybrid_findings(two: Sequence[Any], legs: Sequence[Any],
                         hops: Mapping[str, Sequence[Any]]) -> plt.Figure:
    """The three findings: two-phase vs paper depth; leg extension; hop energy per cycle.

    Parameters
    ----------
    two : sequence of TwoPhaseLanding
        The two-phase sweep.
    legs : sequence of LegExtensionLanding
        The leg-extension sweep.
    hops : dict
        Leg -> sequence of HopCycle (or None).
    """
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4))
    a = axes[0]
    v = np.array([r.impact.v0 for r in two])
    a.plot(v, [r.paper_depth for r in two], "k-", label="paper (constant arrest)")
    a.plot(v, [r.depth for r in two], "C0o", ms=3, label="two-phase (arrest optimised)")
    b = a.twinx()
    b.semilogy(v, [max(abs(r.gain), 1e-17) for r in two], "C3.", ms=3)
    b.set_ylabel("|depth difference|", color="C3")
    _depth_panel(a, "1. the body-arrest phase optimised")
    a = axes[1]
    v = np.array([r.impact.v0 for r in legs])
    a.plot(v, [r.paper_depth for r in legs], "k-", label=r"leg $s/2$ at impact (paper)")
    a.plot(v, [r.depth for r in legs], "C0o", ms=3, label="optimal extension")
    b = a.twinx()
    b.plot(v, [r.extension for r in legs], "C2--", label="optimal leg length")
    b.set_ylabel("leg length at impact", color="C2")
    _depth_panel(a, "2. pre-impact leg extension")
    a = axes[2]
    pts = {leg: np.array([(r.apex_height, r.energy) for r in rows if r is not None]).reshape(
        -1, 2) for leg, rows in hops.items()}
    heights = np.unique(np.concatenate([p[:, 0] for p in pts.values()]))
    if len(heights) > 1:  # a curve over apex heights
        for k, (leg, p) in enumerate(pts.items()):
            if len(p):
                a.plot(p[:, 0], p[:, 1] / p[:, 0], f"C{k}o-", ms=3, label=leg)
        a.set_xscale("log" if heights[-1] > 10 * heights[0] else "linear")
        a.set_xlabel(r"apex height $v_0^2/2$")
        a.legend(fontsize=8)
    else:  # one apex height: a bar per leg, not one point on an empty axis
        legs_ = [leg for leg, p in pts.items() if len(p)]
        a.bar(legs_, [pts[leg][0, 1] / pts[leg][0, 0] for leg in legs_],
              color=[f"C{k}" for k, leg in enumerate(pts) if len(pts[leg])])
        a.set_xlabel(f"leg (apex height {heights[0]:.3g})" if len(heights) else "leg")
    a.set_ylabel("energy per cycle / apex height")
    eta = next((r.eta for rows in hops.values() for r in rows if r is not None), 0.0)
    a.set_title(f"3. minimum-energy hopping ($\\eta$ = {eta:g})", fontsize=9)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


__all__ = ["PHASE_COLOURS", "TITLE_WIDTH", "plot_hop", "plot_hybrid_findings",
           "plot_phased_landing", "plot_phases", "plot_variant_sweep", "shade_phases",
           "wrapped_title"]
