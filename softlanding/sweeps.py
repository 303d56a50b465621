"""Sweeps that scale: labelled N-d datasets of landings, on local cores or a Dask cluster.

Results are :class:`xarray.Dataset` objects with coordinates ``k_p, k_d, v0,
r_m, s`` (maps) or ``r_m, s, v0`` (optimal-gain curves), saved as netCDF so a
figure can be redrawn without recomputing. Locally, landings run on all cores
(numba threads) with a progress bar; given a Dask scheduler address
(``tcp://host:port``) the work is split into chunks and mapped over the
cluster's workers, which must have this package installed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from ._progress import progress as show_progress
from .errors import ParameterError
from .impedance import optimize_impedance, strictly_feasible
from .simulate import BATCH_FIELDS, simulate_batch

CURVE_VARIABLES = ("feasible", "kp", "kd", "depth", "steps", "u_peak", "stroke_min",
                   "stroke_max", "cot", "cot_lossless", "on_stroke_boundary", "value")


def _client(scheduler: str | None):
    if scheduler is None:
        return None
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - depends on the environment
        raise ParameterError("scheduler", "needs dask.distributed: pip install "
                                          "'softlanding[dask]'") from None
    try:
        return Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ParameterError("scheduler", f"cannot reach {scheduler}: {exc}") from None


def _batch_chunk(kp, kd, v0, r_m, s, u_max, energy, progress=False):
    """Run one chunk (a top-level function, so Dask can ship it to workers)."""
    b = simulate_batch(kp, kd, v0, r_m, s, u_max, energy=energy, progress=progress)
    out = {k: b.data[k] for k in BATCH_FIELDS}
    out["cot"] = b.cot
    out["cot_lossless"] = b.cot_lossless
    out["strictly_feasible"] = strictly_feasible(b)
    return out


def impedance_dataset(k_p, k_d, v0, r_m=5.0, s=20.0, u_max: float | None = None, *,
                      energy: bool = True, scheduler: str | None = None,
                      progress: bool | None = None, chunks: int = 32) -> xr.Dataset:
    """Landings on the outer product of the given coordinates, as a labelled dataset.

    Parameters
    ----------
    k_p, k_d, v0, r_m, s : float or 1-D array
        Coordinates (each becomes a dimension, scalars of length 1).
    u_max : float, optional
        Force saturation for every landing.
    energy : bool
        Compute the energy ledger (CoT).
    scheduler : str, optional
        Dask scheduler address; None runs on local cores.
    progress : bool, optional
        Progress bar (default: for more than 50,000 landings).
    chunks : int
        Number of chunks sent to a Dask cluster.
    """
    coords = {name: np.atleast_1d(np.asarray(v, dtype=float))
              for name, v in (("k_p", k_p), ("k_d", k_d), ("v0", v0), ("r_m", r_m), ("s", s))}
    grids = np.meshgrid(*coords.values(), indexing="ij")
    shape = grids[0].shape
    flat = [g.ravel() for g in grids]
    client = _client(scheduler)
    if client is None:
        res = _batch_chunk(*flat, u_max, energy, progress)
    else:
        pieces = [np.array_split(f, min(chunks, f.size)) for f in flat]
        futures = client.map(_batch_chunk, *pieces,
                             *[[x] * len(pieces[0]) for x in (u_max, energy)], pure=False)
        if progress or (progress is None and flat[0].size > 50_000):
            from distributed import progress as dprogress

            dprogress(futures)
        parts = client.gather(futures)
        res = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
        client.close()
    dims = tuple(coords)
    ds = xr.Dataset({k: (dims, np.asarray(v).reshape(shape)) for k, v in res.items()},
                    coords=coords)
    ds.attrs.update(title="soft landing, impedance control (exact simulation)",
                    u_max=-1.0 if u_max is None else float(u_max),
                    note="u_max = -1 means unlimited; feasible allows 1e-9 s rounding at a "
                         "stroke limit, strictly_feasible none")
    _describe(ds)
    return ds


def _describe(ds: xr.Dataset) -> None:
    units = {"depth": "x_s (= m_t g / k_g)", "stroke_min": "x_s", "stroke_max": "x_s",
             "u_peak": "m_t g", "T": "sqrt(m_t / k_g)", "t_first_stop": "sqrt(m_t / k_g)",
             "E0": "m_t g x_s", "ET": "m_t g x_s", "ground": "m_t g x_s",
             "actuator": "m_t g x_s"}
    for k, u in units.items():
        if k in ds:
            ds[k].attrs["units"] = u


def depth_map(v0: float, r_m: float = 5.0, s: float = 20.0, n: int = 101, **kw) -> xr.Dataset:
    """The paper's (k_p, k_d) map at one impact velocity (gains in [0, 1])."""
    g = np.round(np.linspace(0.0, 1.0, n), 12)
    return impedance_dataset(g, g, v0, r_m, s, **kw).squeeze(("v0", "r_m", "s"))


# ----------------------------------------------------------------- curves
def _optimum_row(v0, r_m, s, objective, grid):
    try:
        o = optimize_impedance(v0, r_m, s, objective=objective, grid=grid)
    except ParameterError as exc:
        if "no feasible gains" not in str(exc):
            raise
        # no gains in the box keep the stroke: recorded, not fatal for the sweep
        row = {k: math.nan for k in CURVE_VARIABLES}
        row.update(steps=-1, on_stroke_boundary=False, feasible=False)
        return row
    row = {k: getattr(o, k) for k in CURVE_VARIABLES if k != "feasible"}
    row["feasible"] = True
    return row


def optimal_impedance_curves(v0: Sequence[float], r_m: Sequence[float] = (5.0,),
                             s: Sequence[float] = (20.0,), *, objective: str = "depth",
                             grid: int = 101, scheduler: str | None = None,
                             progress: bool = True) -> xr.Dataset:
    """Optimal gains against impact velocity, for every (r_m, s) given.

    Returns a dataset with dims ``(r_m, s, v0)`` and variables
    :data:`CURVE_VARIABLES`; where no gains in the box keep the stroke,
    ``feasible`` is False and the figures are NaN.
    """
    v0 = np.atleast_1d(np.asarray(v0, dtype=float))
    r_m = np.atleast_1d(np.asarray(r_m, dtype=float))
    s = np.atleast_1d(np.asarray(s, dtype=float))
    tasks = [(float(v), float(r), float(ss)) for r in r_m for ss in s for v in v0]
    client = _client(scheduler)
    if client is None:
        rows = [_optimum_row(v, r, ss, objective, grid) for v, r, ss in
                show_progress(tasks, progress, "optimal gains", "landing problem")]
    else:
        futures = client.map(_optimum_row, *zip(*tasks, strict=True),
                             [objective] * len(tasks), [grid] * len(tasks), pure=False)
        rows = client.gather(futures)
        client.close()
    shape = (len(r_m), len(s), len(v0))
    data = {k: (("r_m", "s", "v0"), np.array([row[k] for row in rows]).reshape(shape))
            for k in CURVE_VARIABLES}
    ds = xr.Dataset(data, coords={"r_m": r_m, "s": s, "v0": v0})
    ds.attrs.update(objective=objective, grid=grid,
                    title=f"optimal impedance (objective: {objective})")
    return ds


def paper_observations(curves: xr.Dataset, r_m: float = 5.0, s: float = 20.0) -> dict:
    """Check the paper's Section IV claims on one curve; numbers, not adjectives."""
    c = curves.sel(r_m=r_m, s=s)
    c = c.isel(v0=np.flatnonzero(c.feasible.values.astype(bool)))
    order = np.argsort(np.abs(c.v0.values))
    speed = np.abs(c.v0.values[order])
    kp = c.kp.values[order]
    kd = c.kd.values[order]
    dkp = np.diff(kp)
    i_min = int(np.argmin(kd))
    return {
        "kp_increasing_with_speed": bool(np.all(dkp >= -1e-9)),
        "kp_decreases": [(float(speed[i]), float(speed[i + 1])) for i in
                         np.flatnonzero(dkp < -1e-9)],
        "kd_min_at_speed": float(speed[i_min]),
        "kd_first_decreasing_then_increasing": bool(
            0 < i_min < len(kd) - 1 and np.all(np.diff(kd[:i_min + 1]) <= 1e-9)
            and np.all(np.diff(kd[i_min:]) >= -1e-9)),
        "critical_speed_between_2_and_6": bool(2.0 <= speed[i_min] <= 6.0),
        "all_on_stroke_boundary": bool(np.all(c.on_stroke_boundary.values[speed > 0])),
        "u_peak_at_fastest": float(c.u_peak.values[order][-1]),
        "fastest_speed": float(speed[-1]),
    }


# --------------------------------------------------------------- netCDF I/O
def save_dataset(ds: xr.Dataset, path: str | Path) -> None:
    """Write netCDF (v3, through scipy: no extra dependency); booleans as int8."""
    out = ds.copy()
    for k, v in out.data_vars.items():
        if v.dtype == bool:
            out[k] = v.astype(np.int8)
            out[k].attrs["boolean"] = 1
        elif v.dtype == np.int64:
            out[k] = v.astype(np.int32)
    out.to_netcdf(path, engine="scipy")


def load_dataset(path: str | Path) -> xr.Dataset:
    """Read a dataset written by :func:`save_dataset` (booleans restored)."""
    ds = xr.load_dataset(path, engine="scipy")
    for k, v in ds.data_vars.items():
        if v.attrs.get("boolean") == 1:
            ds[k] = v.astype(bool)
    return ds
