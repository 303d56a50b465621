"""The terrain study: the paper's conclusions under inertial drag and added mass.

For the paper's robot (``r_m = 5``, ``s = 20``, bang-bang ``u_max = 8.2``, impedance
without force limit) and each ground model of :func:`study_grounds` (the paper's spring,
inertial drag ``c_d`` in {0.05, 0.2, 1}, the poppy-seed accreted cone), against ``v0``:

* the optimal bang-bang landing (refined, replayed, PMP-certified or not): arcs, switches,
  verdict (the paper's Section III claim that bang-bang stays optimal for any
  time-invariant control-affine ground model, tested);
* the depth of bang-bang, optimal impedance and a rigid leg, and their ratios;
* the optimal gains ``(k_p*, k_d*)``;
* the experiment figure's curves (depth against ``k_d`` at ``v0 = -4.8``) with and
  without drag, and the direction drag moves them (the paper's Section VI remark).

Every number is what the public API returns (:func:`~softlanding.optimal.landing.sweep_landing`,
:func:`ocp.certify`, :func:`~softlanding.studies.impedance.optimize_impedance`,
:func:`~softlanding.studies.comparison.rigid_depth`,
:func:`~softlanding.studies.sweeps.impedance_dataset`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from softlanding.model.ground import LINEAR_GROUND, DragGround, Ground
from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, PAPER_ROBOT
from softlanding.model.scaling import EXPERIMENT_KP, EXPERIMENT_V0
from softlanding.model.terrain import paper_rig_units, poppy_seed_added_mass, poppy_seed_drag

STUDY_CD = (0.05, 0.2, 1.0)
"""Drag numbers of the study (besides 0, the paper's spring)."""
EXPERIMENT_FASTEST_V0 = EXPERIMENT_V0[-1]
"""The experiment curves under the terrain models: the paper's fastest impact."""


def study_grounds() -> dict[str, Ground]:
    """The study's ground models by label: linear, drag per :data:`STUDY_CD`, added mass."""
    out: dict[str, Ground] = {"linear": LINEAR_GROUND}
    for c in STUDY_CD:
        out[f"drag {c:g}"] = DragGround(c)
    out["added mass (poppy)"] = poppy_seed_added_mass(paper_rig_units())
    return out


def bang_bang_rows(v0s: Any, ground: Ground) -> list[dict]:
    """Optimal bang-bang landings over ``v0`` (continuation from 0), each certified.

    Parameters
    ----------
    v0s : sequence of float
        Impact velocities, from the easy end.
    ground : Ground
        Ground model.
    """
    from ocp import certify
    from softlanding.optimal.landing import solve_landing

    rows, prev = [], None
    for v in v0s:
        r = solve_landing(float(v), PAPER_ROBOT, ground, warm_start=prev)
        cert = None
        if r.transcribed is None:  # a structure re-solve: certify a cold solve instead
            r = solve_landing(float(v), PAPER_ROBOT, ground)
        if r.transcribed is not None:
            cert = certify(r.transcribed, r.refined)
        reasons = r.unverified_reasons(cert)
        rows.append({"v0": float(v), "depth": r.depth, "arcs": r.arcs,
                     "switches": len(r.switch_times), "switch_times": r.switch_times,
                     "T": r.T, "replay_difference": r.replay_difference,
                     "verdict": cert.verdict if cert is not None else "not checked",
                     "verified": not reasons, "reasons": reasons})
        prev = r
    return rows


def model_rows(v0s: Any, ground: Ground, grid: int) -> list[dict]:
    """Bang-bang, optimal impedance and rigid depths (and gains) of one ground model.

    Parameters
    ----------
    v0s : sequence of float
        Impact velocities, from 0 down.
    ground : Ground
        Ground model.
    grid : int
        Starting grid of the impedance optimiser.
    """
    from softlanding.studies.comparison import rigid_depth
    from softlanding.studies.impedance import optimize_impedance

    rows = bang_bang_rows(v0s, ground)
    for r in rows:
        o = optimize_impedance(r["v0"], PAPER_IMPEDANCE_ROBOT, ground, grid=grid)
        rig = rigid_depth(r["v0"], ground)
        r.update(bang_bang=r.pop("depth"), impedance=o.depth, k_p=o.k_p, k_d=o.k_d,
                 impedance_steps=o.steps, rigid=rig)
        r["bb_over_rigid"] = r["bang_bang"] / rig
        r["imp_over_rigid"] = o.depth / rig
        r["bb_over_imp"] = r["bang_bang"] / o.depth
    return rows


def experiment_curves(kd: Any, grounds: dict[str, Ground]) -> dict[str, Any]:
    """Depth against ``k_d`` at ``v0 = -4.8`` for ``k_p`` in (0.2, 0.5, 0.9), per ground.

    Parameters
    ----------
    kd : array
        Damping values.
    grounds : dict
        Label -> ground model.

    Returns
    -------
    dict
        Label -> dataset with dims ``(k_p, k_d)``.
    """
    from softlanding.studies.sweeps import impedance_dataset

    return {lab: impedance_dataset(EXPERIMENT_FASTEST_V0, EXPERIMENT_KP, kd,
                                   PAPER_IMPEDANCE_ROBOT, g,
                                   energy=False).squeeze(("v0", "r_m", "s"))
            for lab, g in grounds.items()}


def experiment_grounds() -> dict[str, Ground]:
    """The experiment comparison: linear, the RFT drag estimate of the paper's rig
    (``c_d ~ 0.019``), drag 0.2, and the poppy-seed cone."""
    rft = poppy_seed_drag(paper_rig_units())
    return {"linear": LINEAR_GROUND, f"drag {rft.c_d:.3g} (RFT estimate)": rft,
            "drag 0.2": DragGround(0.2),
            "added mass (poppy)": poppy_seed_added_mass(paper_rig_units())}


def experiment_shift(curves: dict[str, Any]) -> list[dict]:
    """Depth change against the linear model at the largest ``k_d`` (the paper's "large
    k_d"), per ground and ``k_p``: its sign is the direction the model moves the curve.

    Parameters
    ----------
    curves : dict
        From :func:`experiment_curves` (with a ``"linear"`` entry).
    """
    lin = curves["linear"]
    rows = []
    for lab, ds in curves.items():
        if lab == "linear":
            continue
        for kp in EXPERIMENT_KP:
            a = lin.sel(k_p=kp).depth.values
            b = ds.sel(k_p=kp).depth.values
            rows.append({"ground": lab, "k_p": kp, "k_d": float(ds.k_d.values[-1]),
                         "depth_linear": float(a[-1]), "depth": float(b[-1]),
                         "change": float(b[-1] - a[-1]),
                         "relative_change": float((b[-1] - a[-1]) / a[-1]),
                         "max_relative_change": float(np.nanmax(np.abs(b - a) / a))})
    return rows


__all__ = ["EXPERIMENT_FASTEST_V0", "STUDY_CD", "bang_bang_rows", "experiment_curves",
           "experiment_grounds", "experiment_shift", "model_rows", "study_grounds"]
