"""The landings whose outputs on the paper's ground (K = 1) must not move by a bit.

Their outputs were recorded at the branch point of the kernel's stiffness parameter, before
the kernel took ``K`` (``data/kernel_k1_reference.npz``, written by :func:`record`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from softlanding import PAPER_ROBOT, simulate, simulate_batch
from softlanding.model import ForceSchedule, Impedance, Rigid
from softlanding.model.ground import LinearGround
from softlanding.simulation.kernel import STATUS_NAMES

CODES = {name: code for code, name in STATUS_NAMES.items()}
REFERENCE = Path(__file__).with_name("data") / "kernel_k1_reference.npz"

CONTROLLERS = {
    "rigid": Rigid(),
    "imp_0.2_0.4": Impedance(0.2, 0.4),
    "imp_0.2_0.18": Impedance(0.2, 0.18),  # stepped intrusions
    "imp_0.2_0": Impedance(0.2, 0.0),  # undamped: hops
    "imp_0.5_0.05": Impedance(0.5, 0.05),
    "imp_0.1_0.3": Impedance(0.1, 0.3),
    "imp_0_0.3": Impedance(0.0, 0.3),  # no stiffness: creep proof
    "sched_3": ForceSchedule((0.1, 0.3), (8.0, -8.0, 1.0)),
    "sched_const": ForceSchedule((), (0.6,)),
}
ROBOTS = {"paper": PAPER_ROBOT, "free": PAPER_ROBOT.without_force_limit()}
SPEEDS = (-1.0, -3.0, -6.0)


def landing_row(res) -> np.ndarray:
    """Every number of a landing's result, as one float vector."""
    e = res.energy
    return np.array([res.depth, res.steps, res.feasible, res.u_peak, res.stroke_min,
                     res.stroke_max, res.t_first_stop, res.T, res.n_segments,
                     res.depth_limit, res.foot_rest, e.E0, e.ET, e.ground, e.actuator],
                    dtype=float)


def fingerprints(ground=None) -> dict[str, np.ndarray]:
    """The outputs of every landing and batch of this module on ``ground`` (default K = 1)."""
    ground = LinearGround() if ground is None else ground
    out = {}
    for rn, robot in ROBOTS.items():
        for cn, c in CONTROLLERS.items():
            rows = []
            for v0 in SPEEDS:
                res = simulate(robot, v0, c, ground)
                rows.append(np.append(landing_row(res), CODES[res.status]))
            out[f"{rn}/{cn}"] = np.array(rows)
    g = np.linspace(0.0, 1.0, 21)
    for rn, robot in ROBOTS.items():
        b = simulate_batch(robot, -3.0, g[:, None], g[None, :], ground)
        for f in ("depth", "steps", "status", "T", "stroke_min", "stroke_max", "u_peak",
                  "feasible"):
            out[f"batch/{rn}/{f}"] = np.asarray(getattr(b, f), dtype=float)
    return out


def record() -> None:
    """Write the reference outputs (run once, at the branch point)."""
    REFERENCE.parent.mkdir(exist_ok=True)
    np.savez_compressed(REFERENCE, **fingerprints())


if __name__ == "__main__":
    record()
