"""Figures a person can read: legends for every line style, marked special cases."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from softlanding import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT  # noqa: E402
from softlanding.plots import paper as F  # noqa: E402
from softlanding.report.demo import stepped_intrusions  # noqa: E402
from softlanding.studies.sweeps import depth_map  # noqa: E402


def _legend_texts(fig):
    return [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().texts]


def test_bang_bang_figure_explains_its_event_lines():
    from softlanding.optimal.landing import solve_landing

    fig = F.plot_bang_bang(solve_landing(-3.0, PAPER_ROBOT))
    texts = _legend_texts(fig)
    for what in ("switch of u", "foot stops (T)", "body stops"):
        assert what in texts


def test_step_regions_mark_unproven_rest_instead_of_colouring_it():
    maps = [depth_map(-1.0, PAPER_IMPEDANCE_ROBOT, n=21, energy=False)]
    assert (maps[0].status.values != 0).any()  # k_p = 0 or k_d = 0 columns
    fig = F.plot_stepped_intrusion_figure(stepped_intrusions(), maps)
    assert "rest not proven" in _legend_texts(fig)


def test_optima_on_the_gain_box_edge_are_flagged():
    c = xr.Dataset({"k_p": ("v0", [0.2, 1.0, 0.5]), "k_d": ("v0", [0.3, 0.4, 0.0])},
                   coords={"v0": [-1.0, -2.0, -3.0]})
    assert F._on_box_edge(c).tolist() == [False, True, True]


def test_depth_map_keeps_its_legend_off_the_data():
    ds = depth_map(-3.0, PAPER_IMPEDANCE_ROBOT, n=21, energy=False)

    class Opt:
        k_p, k_d, depth = 0.14, 0.26, float(ds.depth.where(ds.strictly_feasible).min())

    fig = F.plot_depth_map(ds, Opt())
    assert fig.axes[0].get_legend() is None
    assert any("optimum" in t.get_text() for t in fig.axes[0].texts)


@pytest.mark.parametrize("kp", [0.5, 0.9])
def test_experiment_figure_shows_the_k_d_0_points(kp):
    from softlanding.studies.sweeps import impedance_dataset

    ds = impedance_dataset([-1.6, -3.2], [kp], np.linspace(0, 1, 11), PAPER_IMPEDANCE_ROBOT,
                           energy=False).squeeze(("r_m", "s")).transpose("k_p", "v0", "k_d")
    fig = F.plot_experiment_curves(ds)
    ax = fig.axes[0]
    # every k_d = 0 depth is drawn as a point (a lone point makes no line)
    pts = [(x, y) for ln in ax.lines for x, y in zip(*ln.get_data(), strict=True)
           if ln.get_marker() not in ("None", None, "") and np.isfinite(y)]
    for v in (-1.6, -3.2):
        d0 = float(ds.depth.sel(k_p=kp, v0=v, k_d=0.0))
        assert any(x == 0.0 and abs(y - d0) < 1e-12 for x, y in pts)
