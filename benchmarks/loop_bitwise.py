"""The closed-loop landings recorded to the last bit, to check that a change of the loop's
code (not of its numbers) leaves every landing as it was.

Run:  python -m benchmarks.loop_bitwise --save FILE [--groups study,replan,stress]
      python -m benchmarks.loop_bitwise --compare FILE [--groups ...]

Groups: ``study``, the controller study's 180 landings (60 grounds and velocities, the
compiled controller with exact sensing and with noise 1e-3, one sample of delay, margins 0
and 2: :func:`softlanding.studies.unknown_ground.controller_case`'s); ``replan``, the
re-planning MPC on the unknown-ground study's 60 cases (exact sensing, as
:func:`~softlanding.studies.unknown_ground.unknown_ground_case` runs it) and on 6 noisy or
unestimated ones; ``stress``, the compiled controller where its structure does not cover
every sample (noise 1e-2, one and two samples of delay on soft draggy grounds: its fallback
runs). Each landing is recorded whole: every piece the plant simulated (its start, the
control it applied, every array of its segments), the depth, the stroke's range, the peak
force, every sample's path and estimate. ``--compare`` runs them again and says which differ
(a difference in the last bit counts) and where first.
"""

from __future__ import annotations

import argparse
import gzip
import itertools
import pickle
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from softlanding.control import mpc_landing
from softlanding.model.robot import PAPER_ROBOT
from softlanding.studies.unknown_ground import (
    REALISTIC_DELAY,
    REALISTIC_NOISE,
    STUDY_DRAG,
    STUDY_STIFFNESS,
    STUDY_V0,
    true_ground,
)


def _grid() -> list[tuple[float, float, float]]:
    return [(v, k, c) for v in STUDY_V0 for k, c in itertools.product(STUDY_STIFFNESS,
                                                                      STUDY_DRAG)]


def landings(groups: set[str]) -> Iterator[tuple[str, dict[str, Any]]]:
    """Every landing of the groups: a name and ``mpc_landing``'s keywords (the controller
    always named: a default may change)."""
    sensing = {"exact": {}, **{f"noisy_m{m:g}": {
        "noise": REALISTIC_NOISE, "delay": REALISTIC_DELAY, "seed": 0, "margin": m,
        "estimator": "filtered"} for m in (0.0, 2.0)}}
    if "study" in groups:
        for (v, k, c), (key, kw) in itertools.product(_grid(), sensing.items()):
            yield f"study v0={v:g} K={k:g} c_d={c:g} {key}", {
                "impact": v, "ground": true_ground(k, c), "controller": "bangbang", **kw}
    if "replan" in groups:
        for v, k, c in _grid():
            yield f"replan v0={v:g} K={k:g} c_d={c:g}", {
                "impact": v, "ground": true_ground(k, c), "controller": "replan"}
        for (k, c), kw in itertools.product(((2.0, 0.0), (0.5, 1.0)), (
                {"noise": 1e-3, "delay": 1, "estimator": "filtered"},
                {"noise": 1e-3, "delay": 0, "estimator": "measured"},
                {"estimate": False})):
            yield f"replan v0=-3 K={k:g} c_d={c:g} {kw}", {
                "impact": -3.0, "ground": true_ground(k, c), "controller": "replan", **kw}
    if "stress" in groups:
        for (v, k, c), delay, seed in itertools.product(((-1.0, 0.5, 0.2), (-1.0, 0.75, 0.2)),
                                                        (1, 2), (0, 1)):
            yield f"stress v0={v:g} K={k:g} c_d={c:g} delay={delay} seed={seed}", {
                "impact": v, "ground": true_ground(k, c), "controller": "bangbang",
                "noise": 1e-2, "delay": delay, "seed": seed, "margin": 2.0}


def _copied(v: Any) -> Any:
    """An array, or a list of them (a segment's ragged data), copied."""
    if isinstance(v, list | tuple):
        return [_copied(e) for e in v]
    return np.array(v, copy=True)


def record(m: Any) -> dict[str, Any]:
    """A landing's every number that the loop's code decides."""
    pieces = []
    for t0, r in m.pieces:
        pieces.append({"t0": t0, "control": r.controller.to_dict(), "depth": r.depth,
                       "T": r.T, "status": r.status, "u_peak": r.u_peak,
                       "stroke": (r.stroke_min, r.stroke_max),
                       "segments": {k: _copied(v) for k, v in r._segments.items()
                                    if k != "law"}})  # (the ground's compiled law)
    return {"depth": m.depth, "u_peak": m.u_peak, "stroke": (m.stroke_min, m.stroke_max),
            "samples": m.samples, "paths": list(m.step_paths),
            "counts": (m.replans, m.fallbacks, m.structure_changes, m.uncovered, m.deferred,
                       m.creep_samples),
            "work": list(m.step_work), "feasible": m.feasible,
            "estimates": [tuple(e.__dict__.values()) for e in m.estimates],
            "pieces": pieces}


def first_difference(a: Any, b: Any, where: str = "") -> str | None:
    """Where ``a`` and ``b`` first differ, to the last bit (None: identical)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return f"{where}: keys {sorted(a)} vs {sorted(b)}"
        for k in a:
            d = first_difference(a[k], b[k], f"{where}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        if len(a) != len(b):
            return f"{where}: length {len(a)} vs {len(b)}"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            d = first_difference(x, y, f"{where}[{i}]")
            if d:
                return d
        return None
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        same = a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
        return None if same else f"{where}: arrays differ"
    if isinstance(a, float) and isinstance(b, float):
        return None if np.float64(a).tobytes() == np.float64(b).tobytes() else \
            f"{where}: {a!r} vs {b!r}"
    return None if a == b else f"{where}: {a!r} vs {b!r}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("--save", help="record the landings to this file (gzipped pickle)")
    what.add_argument("--compare", help="run again and compare with this record")
    ap.add_argument("--groups", default="study,replan,stress")
    a = ap.parse_args()
    groups = set(a.groups.split(","))
    old = None
    if a.compare:
        with gzip.open(a.compare, "rb") as f:
            old = pickle.load(f)
    out: dict[str, Any] = {}
    same = differ = 0
    t_start = time.process_time()
    for name, kw in landings(groups):
        kw = dict(kw)
        t0 = time.process_time()
        rec = record(mpc_landing(kw.pop("impact"), PAPER_ROBOT, kw.pop("ground"), **kw))
        out[name] = rec
        cpu = time.process_time() - t0
        if old is None:
            print(f"{name}: depth {rec['depth']!r}, {rec['samples']} samples ({cpu:.1f} s)",
                  flush=True)
            continue
        if name not in old:
            print(f"{name}: not in the record")
            continue
        d = first_difference(old[name], rec)
        same, differ = same + (d is None), differ + (d is not None)
        print(f"{name}: {'identical' if d is None else 'DIFFERS at ' + d} ({cpu:.1f} s)",
              flush=True)
    if a.save:
        with gzip.open(Path(a.save), "wb") as f:
            pickle.dump(out, f)
        print(f"{len(out)} landings recorded in {time.process_time() - t_start:.0f} s CPU")
    else:
        print(f"{same} identical to the last bit, {differ} differ "
              f"({time.process_time() - t_start:.0f} s CPU)")


if __name__ == "__main__":
    main()
