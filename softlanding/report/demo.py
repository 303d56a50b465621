"""The ``softlanding demo``: rigid against impedance landings, and the paper's stepped intrusions.

Computed here (not in the CLI) so a notebook can call the same thing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from softlanding.model.controllers import Impedance, Rigid
from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, Impact, Robot
from softlanding.simulation.simulator import LandingResult, simulate
from softlanding.studies.comparison import rigid_depth
from softlanding.util.progress import step

DEMO_V0 = (0.0, -1.0, -3.0, -5.0, -10.0)
"""Impact velocities of the demo table."""
DEMO_GAINS = Impedance(0.5, 0.5)
"""The impedance of the demo table."""
STEPPED_V0 = -1.0
STEPPED_KP = 0.2
STEPPED_KD = (0.4, 0.18, 0.0)
"""The paper's stepped-intrusion cases (Fig. 3a): 1, 2 and 3 steps."""
PLOT_V0 = np.linspace(-10, 0, 41)
"""Impact velocities of the figure's depth curves."""
DEMO_LANDINGS = 2 * len(DEMO_V0) + len(STEPPED_KD) + 2 * len(PLOT_V0)
"""Landings the demo simulates (table, stepped intrusions, figure): a progress bar's total."""


def _land(robot: Robot, v0: float, controller: Rigid | Impedance) -> LandingResult:
    """One landing, a step of the caller's progress bar (if one is open)."""
    result = simulate(robot, Impact(v0), controller)
    step()
    return result


def demo_table(robot: Robot = PAPER_IMPEDANCE_ROBOT,
               impedance: Impedance = DEMO_GAINS) -> list[dict[str, Any]]:
    """Rigid and impedance landings at :data:`DEMO_V0`, with the analytic rigid depth.

    Parameters
    ----------
    robot : Robot
        The robot.
    impedance : Impedance
        The leg compared with the rigid one.

    Returns
    -------
    list of dict
        Per ``v0``: ``rigid_depth``, ``rigid_depth_analytic``, ``impedance_depth``,
        ``impedance_steps``, ``impedance_feasible``, ``impedance_u_peak``, ``impedance_cot``.
    """
    rows = []
    for v0 in DEMO_V0:
        rig = _land(robot, v0, Rigid())
        imp = _land(robot, v0, impedance)
        rows.append({"v0": v0, "rigid_depth": rig.depth, "rigid_depth_analytic": rigid_depth(v0),
                     "impedance_depth": imp.depth, "impedance_steps": imp.steps,
                     "impedance_feasible": imp.feasible, "impedance_u_peak": imp.u_peak,
                     "impedance_cot": imp.energy.cot})
    return rows


def stepped_intrusions(robot: Robot = PAPER_IMPEDANCE_ROBOT) -> list[LandingResult]:
    """The paper's three stepped-intrusion landings (v0 = -1, k_p = 0.2, k_d = 0.4, 0.18, 0).

    Parameters
    ----------
    robot : Robot
        The robot.
    """
    return [_land(robot, STEPPED_V0, Impedance(STEPPED_KP, kd)) for kd in STEPPED_KD]


def plot_demo(robot: Robot = PAPER_IMPEDANCE_ROBOT, impedance: Impedance = DEMO_GAINS,
              stepped: list[LandingResult] | None = None):
    """Depth against v0 (rigid and impedance) beside the stepped intrusions.

    Parameters
    ----------
    robot, impedance
        As :func:`demo_table`.
    stepped : list of LandingResult, optional
        :func:`stepped_intrusions` if already computed.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    from softlanding.plots.paper import plot_depth_vs_velocity, plot_stepped_intrusions

    v = PLOT_V0
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2))
    plot_depth_vs_velocity(v, {
        "rigid leg": np.array([_land(robot, x, Rigid()).depth for x in v]),
        f"impedance $k_p$={impedance.k_p:g}, $k_d$={impedance.k_d:g}": np.array(
            [_land(robot, x, impedance).depth for x in v]),
    }, ax=ax1)
    ax1.set_title(f"depth against impact velocity ($r_m$={robot.r_m:g}, $s$={robot.s:g})",
                  fontsize=9)
    plot_stepped_intrusions(stepped or stepped_intrusions(robot), ax=ax2)
    ax2.set_title(f"stepped intrusions, $v_0$={STEPPED_V0:g}, $k_p$={STEPPED_KP:g}", fontsize=9)
    fig.tight_layout()
    return fig


__all__ = ["DEMO_GAINS", "DEMO_LANDINGS", "DEMO_V0", "PLOT_V0", "demo_table", "plot_demo",
           "stepped_intrusions"]
