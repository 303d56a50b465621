"""The ground model and its numbers are in every figure title and dataset (issue 23, item 8):
a drag landing's figure must not look like the paper's linear case."""

import pytest

from softlanding.model import PAPER_ROBOT, Impact, Impedance
from softlanding.model.ground import (
    LINEAR_GROUND,
    DragGround,
    ground_attrs,
    ground_label,
    ground_of_attrs,
)
from softlanding.plots.paper import plot_depth_map, plot_trajectory
from softlanding.simulation.simulator import simulate
from softlanding.studies.sweeps import depth_map

DRAG = DragGround(0.2)


def _titles(fig):
    return " ".join([fig._suptitle.get_text() if fig._suptitle else ""]
                    + [a.get_title() for a in fig.axes])


@pytest.mark.parametrize("ground,words", [(LINEAR_GROUND, ["ground: linear"]),
                                          (DRAG, ["ground: drag", "$c_d$=0.2"])])
def test_trajectory_title_names_the_ground(ground, words):
    res = simulate(PAPER_ROBOT.without_force_limit(), Impact(-3), Impedance(0.2, 0.3), ground)
    title = _titles(plot_trajectory(res))
    assert all(w in title for w in words), title


def test_dataset_records_the_ground_and_its_numbers():
    ds = depth_map(Impact(-3), PAPER_ROBOT.without_force_limit(), DRAG, n=5)
    assert ds.attrs["ground"] == "drag" and ds.attrs["ground_c_d"] == 0.2
    assert "$c_d$=0.2" in _titles(plot_depth_map(ds))


def test_attrs_round_trip():
    assert ground_of_attrs(ground_attrs(DRAG)) == DRAG.to_dict()
    assert ground_label(ground_of_attrs({})) == ground_label(LINEAR_GROUND)
