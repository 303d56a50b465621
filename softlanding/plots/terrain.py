"""Figures of the terrain study (:mod:`softlanding.studies.terrain_study`)."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np


def plot_terrain_study(models: dict[str, list[dict]]) -> plt.Figure:
    """Depth of bang-bang, optimal impedance and rigid leg, and the optimal gains, against
    ``v0`` for each ground model.

    Parameters
    ----------
    models : dict
        Ground label -> rows of :func:`softlanding.studies.terrain_study.model_rows`.
    """
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for i, (lab, rows) in enumerate(models.items()):
        v = np.array([r["v0"] for r in rows])
        c = f"C{i}"
        axes[0].plot(v, [r["rigid"] for r in rows], ":", color=c)
        axes[0].plot(v, [r["impedance"] for r in rows], "--", color=c)
        axes[0].plot(v, [r["bang_bang"] for r in rows], "-", color=c, label=lab)
        axes[1].plot(v, [r["bb_over_rigid"] for r in rows], "-", color=c, label=lab)
        axes[1].plot(v, [r["imp_over_rigid"] for r in rows], "--", color=c)
        axes[2].plot(v, [r["k_p"] for r in rows], "-o", color=c, ms=3, label=f"{lab}: k_p*")
        axes[2].plot(v, [r["k_d"] for r in rows], "--s", color=c, ms=3)
    axes[0].set(xlabel="$v_0$", ylabel="depth $-x_f(T)$",
                title="bang-bang (solid), impedance (dashed), rigid (dotted)")
    axes[1].set(xlabel="$v_0$", ylabel="depth / rigid depth",
                title="bang-bang (solid) and impedance (dashed) over rigid")
    axes[2].set(xlabel="$v_0$", ylabel="gain", title="optimal $k_p^*$ (solid), $k_d^*$ (dashed)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_experiment_drag(curves: dict[str, Any]) -> plt.Figure:
    """The experiment figure's simulated curves (depth against ``k_d`` at ``v0 = -4.8``, one
    panel per ``k_p``) for the paper's spring and the other ground models.

    Parameters
    ----------
    curves : dict
        Label -> dataset with dims ``(k_p, k_d)`` (:func:`~softlanding.studies.terrain_study.
        experiment_curves`).
    """
    first = next(iter(curves.values()))
    kps = first.k_p.values
    fig, axes = plt.subplots(1, len(kps), figsize=(4.4 * len(kps), 4.0), sharey=True)
    for ax, kp in zip(np.atleast_1d(axes), kps, strict=True):
        for i, (lab, ds) in enumerate(curves.items()):
            c = ds.sel(k_p=kp)
            ok = c.strictly_feasible.values
            d = c.depth.values
            ax.plot(c.k_d.values, np.where(ok, d, np.nan), color=f"C{i}", label=lab)
            ax.plot(c.k_d.values, np.where(ok, np.nan, d), ":", color=f"C{i}", lw=1)
        ax.set(title=f"$k_p$ = {kp:g}, $v_0$ = -4.8", xlabel="$k_d$")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("depth $-x_f(T)$")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


__all__ = ["plot_experiment_drag", "plot_terrain_study"]
