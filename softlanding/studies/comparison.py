"""Rigid leg vs optimal impedance vs bang-bang force control (the paper's Section V).

One function, :func:`compare_controllers`, used by ``softlanding compare``,
``softlanding reproduce`` and ``benchmarks/compare_controllers.py``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from softlanding.model.ground import LINEAR_GROUND, Ground, LinearGround
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.util.progress import progress as show_progress


def rigid_depth(v0: float, ground: Ground = LINEAR_GROUND) -> float:
    """Depth of a rigid leg: ``1 + sqrt(1 + v0^2)`` on the paper's spring (one mass on a
    one-way spring); on another ground, the simulated rigid leg (without force limit: one
    body, so the mass ratio does not matter).

    Parameters
    ----------
    v0 : float
        Impact velocity.
    ground : Ground
        Ground model.
    """
    if isinstance(ground, LinearGround):
        return 1.0 + math.sqrt(1.0 + v0 * v0)
    from softlanding.model.controllers import Rigid
    from softlanding.simulation.simulator import simulate

    res = simulate(PAPER_ROBOT.without_force_limit(), Impact(v0), Rigid(), ground)
    return res.depth if res.rest_proven else math.nan


def compare_controllers(v0: Sequence[float], robot: Robot = PAPER_ROBOT,
                        ground: Ground = LINEAR_GROUND, *, grid: int = 101,
                        saturate_impedance: bool = False, progress: bool | None = False,
                        impedance_optimum: Callable[[float], Any] | None = None) -> list[dict]:
    """Depth of the three controllers at each impact velocity.

    Parameters
    ----------
    v0 : sequence of float
        Impact velocities, solved in the order given (bang-bang by continuation:
        start from the easy end, near 0).
    robot : Robot
        The robot; its force limit bounds the bang-bang force.
    ground : Ground
        Ground model (the rigid column: :func:`rigid_depth`).
    grid : int
        Starting grid of the impedance optimisation.
    saturate_impedance : bool
        Also limit the impedance's force to ``u_max``. The paper does not (it takes
        ``u_max`` from the optimal impedance's peak force), and neither does the default.
    progress : bool, optional
        Progress bars.
    impedance_optimum : callable, optional
        ``v0 -> optimum`` (with ``depth, k_p, k_d, u_peak``) to reuse optima already
        computed; default :func:`~softlanding.studies.impedance.optimize_impedance`.

    Returns
    -------
    list of dict
        Per ``v0``: ``rigid``, ``impedance`` (depth-optimal gains ``impedance_k_p``,
        ``impedance_k_d``, peak force ``impedance_u_peak``), ``bang_bang`` (refined
        depth, ``bang_bang_switch``, ``bang_bang_T``), all depths in ``x_s``.
    """
    # imported here: the optimal-control stack (CasADi, ocp) is 0.2 s of imports that
    # rigid_depth, all the demo needs, does without
    from softlanding.optimal.landing import sweep_landing
    from softlanding.studies.impedance import optimize_impedance

    impacts = [Impact.of(x) for x in v0]
    bang = sweep_landing([i.v0 for i in impacts], robot, ground, progress=progress)
    imp_robot = robot if saturate_impedance else robot.without_force_limit()
    opt = impedance_optimum or (lambda x: optimize_impedance(x, imp_robot, ground, grid=grid))
    imp = [opt(i.v0) for i in show_progress(impacts, progress, "optimal impedance",
                                            "landing problem")]
    return [{"v0": i.v0, "rigid": rigid_depth(i.v0, ground),
             "impedance": o.depth, "impedance_k_p": o.k_p, "impedance_k_d": o.k_d,
             "impedance_u_peak": o.u_peak, "bang_bang": b.depth,
             "bang_bang_switch": b.switch_times[0] if b.switch_times else math.nan,
             "bang_bang_T": b.T}
            for i, o, b in zip(impacts, imp, bang, strict=True)]


def comparison_arrays(rows: list[dict]) -> dict[str, np.ndarray]:
    """Columns of :func:`compare_controllers` rows as arrays.

    Parameters
    ----------
    rows : list of dict
        From :func:`compare_controllers`.
    """
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}


__all__ = ["compare_controllers", "comparison_arrays", "rigid_depth"]
