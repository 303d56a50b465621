"""Rigid leg vs optimal impedance vs bang-bang force control (the paper's Section V).

One function, :func:`compare_controllers`, used by ``softlanding compare``,
``softlanding reproduce`` and ``benchmarks/compare_controllers.py``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ._progress import progress as show_progress
from .impedance import optimize_impedance
from .landing import sweep_landing


def rigid_depth(v0: float) -> float:
    """Depth of a rigid leg, ``1 + sqrt(1 + v0^2)`` (one mass on the one-way spring)."""
    return 1.0 + math.sqrt(1.0 + v0 * v0)


def compare_controllers(v0: Sequence[float], r_m: float = 5.0, s: float = 20.0,
                        u_max: float = 8.2, *, grid: int = 101, progress: bool = False,
                        impedance_optimum: Callable[[float], Any] | None = None) -> list[dict]:
    """Depth of the three controllers at each impact velocity.

    Parameters
    ----------
    v0 : sequence of float
        Impact velocities, solved in the order given (bang-bang by continuation:
        start from the easy end, near 0).
    r_m, s : float
        Mass ratio and stroke.
    u_max : float
        Force bound of the bang-bang controller (the impedance is unsaturated,
        as in the paper).
    grid : int
        Starting grid of the impedance optimisation.
    progress : bool
        Progress bars.
    impedance_optimum : callable, optional
        ``v0 -> optimum`` (with ``depth, kp, kd, u_peak``) to reuse optima already
        computed; default :func:`~softlanding.impedance.optimize_impedance`.

    Returns
    -------
    list of dict
        Per ``v0``: ``rigid``, ``impedance`` (depth-optimal gains ``impedance_kp``,
        ``impedance_kd``, peak force ``impedance_u_peak``), ``bang_bang`` (refined
        depth, ``bang_bang_switch``, ``bang_bang_T``), all depths in ``x_s``.
    """
    v = [float(x) for x in v0]
    bang = sweep_landing(v, r_m, s, u_max, progress=progress)
    opt = impedance_optimum or (lambda x: optimize_impedance(x, r_m, s, grid=grid))
    imp = [opt(x) for x in show_progress(v, progress, "optimal impedance", "landing problem")]
    return [{"v0": x, "rigid": rigid_depth(x), "impedance": o.depth, "impedance_kp": o.kp,
             "impedance_kd": o.kd, "impedance_u_peak": o.u_peak, "bang_bang": b.depth,
             "bang_bang_switch": b.switch_times[0] if b.switch_times else math.nan,
             "bang_bang_T": b.T}
            for x, o, b in zip(v, imp, bang, strict=True)]


def comparison_arrays(rows: list[dict]) -> dict[str, np.ndarray]:
    """Columns of :func:`compare_controllers` rows as arrays."""
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}
