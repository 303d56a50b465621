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
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from softlanding.errors import ClusterError, ParameterError, check_count, plain
from softlanding.model.ground import LINEAR_GROUND, Ground, ground_attrs
from softlanding.model.robot import PAPER_IMPEDANCE_ROBOT, Impact, Robot
from softlanding.simulation.simulator import BATCH_FIELDS, check_batch_size, simulate_batch
from softlanding.studies.impedance import MAX_GRID, optimize_impedance
from softlanding.util.progress import progress as show_progress
from softlanding.util.progress import progress_bar

CURVE_VARIABLES = ("feasible", "k_p", "k_d", "depth", "steps", "u_peak", "stroke_min",
                   "stroke_max", "cot", "cot_lossless", "on_stroke_boundary", "value")
WORKER_TIMEOUT_S = 30.0
"""How long a Dask scheduler may go without a worker before the run gives up."""
DASK_TIMEOUT_S = 600.0
"""Default of ``dask_timeout``: how long a Dask run may go without any result arriving."""
MAX_DASK_TIMEOUT_S = 86_400.0
"""Largest ``dask_timeout`` (a day): a longer wait for one result is a stalled cluster."""
MAX_LANDINGS = 50_000_000
"""Largest dataset (about 6 GiB of results); larger requests are refused up front."""


def _client(scheduler: str | None, timeout: float = DASK_TIMEOUT_S):
    if scheduler is None:
        return None
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - depends on the environment
        raise ParameterError("scheduler", "needs dask.distributed: pip install "
                                          "'softlanding[dask]'") from None
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ParameterError("scheduler", f"cannot reach {scheduler}: {exc}") from None
    wait = min(WORKER_TIMEOUT_S, timeout)
    try:
        client.wait_for_workers(1, timeout=wait)
    except TimeoutError:
        client.close()
        raise ParameterError("scheduler", f"no worker joined {scheduler} within "
                                          f"{wait:g} s; start one with "
                                          f"'dask worker {scheduler}'") from None
    return client


def _batch_chunk(robot: Robot, ground: Ground, v0, kp, kd, energy: bool,
                 progress: bool | None = False) -> dict[str, np.ndarray]:
    """Run one chunk (a top-level function, so Dask can ship it to workers)."""
    b = simulate_batch(robot, v0, kp, kd, ground, energy=energy, progress=progress)
    out = {k: b.data[k] for k in BATCH_FIELDS}
    out["cot"] = b.cot
    out["cot_lossless"] = b.cot_lossless
    out["strictly_feasible"] = b.strictly_feasible
    return out


def _family(robot: Robot, r_m, s) -> tuple[np.ndarray, np.ndarray, list[Robot]]:
    """The robots of a (r_m, s) family (the robot's own values when not given)."""
    rr = np.atleast_1d(np.asarray(robot.r_m if r_m is None else r_m, dtype=float))
    ss = np.atleast_1d(np.asarray(robot.s if s is None else s, dtype=float))
    return rr, ss, [robot.replace(r_m=float(a), s=float(b)) for a in rr for b in ss]


def impedance_dataset(v0, k_p, k_d, robot: Robot = PAPER_IMPEDANCE_ROBOT,
                      ground: Ground = LINEAR_GROUND, *, r_m=None, s=None, energy: bool = True,
                      scheduler: str | None = None, progress: bool | None = None,
                      chunks: int = 32, dask_timeout: float = DASK_TIMEOUT_S) -> xr.Dataset:
    """Landings on the outer product of the given coordinates, as a labelled dataset.

    Parameters
    ----------
    v0, k_p, k_d : float or 1-D array
        Coordinates (each becomes a dimension; scalars have length 1).
    robot : Robot
        The robot (its force limit saturates every landing).
    ground : Ground
        Ground model.
    r_m, s : float or 1-D array, optional
        A family of robots: these mass ratios and strokes replace the robot's
        (dimensions ``r_m`` and ``s`` are always present).
    energy : bool
        Compute the energy ledger (CoT).
    scheduler : str, optional
        Dask scheduler address; None runs on local cores.
    progress : bool, optional
        Progress bar (default: for more than 50,000 landings).
    chunks : int
        Number of chunks per robot sent to a Dask cluster.
    dask_timeout : float
        Seconds a Dask run may go without a result arriving (or without any worker) before
        it fails with :class:`~softlanding.errors.ClusterError`.

    Returns
    -------
    xarray.Dataset
        Dims ``(k_p, k_d, v0, r_m, s)``; every figure of every landing.
    """
    coords = {name: np.atleast_1d(np.asarray(v, dtype=float))
              for name, v in (("k_p", k_p), ("k_d", k_d), ("v0", v0))}
    rr, ss, robots = _family(robot, r_m, s)
    size = math.prod(c.size for c in coords.values()) * len(robots)
    if size > MAX_LANDINGS:
        raise ParameterError("grid", f"{size:,} landings requested; the limit is "
                                     f"{MAX_LANDINGS:,} (about 6 GiB of results)")
    check_batch_size(2 * size)  # the results, and the dataset built from them
    grids = np.meshgrid(*coords.values(), indexing="ij")
    kp, kd, v = (g.ravel() for g in grids)
    dask_timeout = _check_timeout(dask_timeout)
    client = _client(scheduler, dask_timeout)
    if client is None:
        parts = [_batch_chunk(r, ground, v, kp, kd, energy, progress) for r in robots]
    else:
        with client:  # closed also when the run fails or is interrupted
            parts = _on_cluster(client, robots, ground, v, kp, kd, energy, chunks, progress,
                                dask_timeout)
    shape = grids[0].shape + (len(rr), len(ss))
    data = {k: (("k_p", "k_d", "v0", "r_m", "s"),
                np.stack([p[k].reshape(grids[0].shape) for p in parts], axis=-1).reshape(shape))
            for k in parts[0]}
    ds = xr.Dataset(data, coords={**coords, "r_m": rr, "s": ss})
    ds.attrs.update(title="soft landing, impedance control (exact simulation)",
                    u_max=-1.0 if robot.u_max is None else float(robot.u_max),
                    l0=-1.0 if robot.l0 is None else float(robot.l0), **ground_attrs(ground),
                    note="u_max = -1 means unlimited, l0 = -1 means s/2; feasible allows "
                         "1e-9 s rounding at a stroke limit, strictly_feasible none")
    _describe(ds)
    return ds


def _check_timeout(timeout: float) -> float:
    if not (isinstance(timeout, int | float) and math.isfinite(timeout)
            and 0 < timeout <= MAX_DASK_TIMEOUT_S):
        raise ParameterError("dask_timeout", f"must be in (0, {MAX_DASK_TIMEOUT_S:g}] "
                                             f"seconds, got {plain(timeout)}")
    return float(timeout)


def _completed(client, futures: list, timeout: float) -> Any:
    """Yield futures as they finish; fail when none has for ``timeout`` s or no worker is left.

    A sweep whose only worker died would otherwise wait for ever: the scheduler keeps the
    tasks until a worker joins.
    """
    from distributed import wait

    pending = set(futures)
    last = time.monotonic()
    no_worker_since: float | None = None
    while pending:
        try:
            done, pending = wait(pending, timeout=min(1.0, timeout), return_when="FIRST_COMPLETED")
        except TimeoutError:
            done = set()
        now = time.monotonic()
        if done:
            last, no_worker_since = now, None
            yield from done
            continue
        try:
            workers = len(client.nthreads())
        except Exception:  # the scheduler itself is gone or unreachable
            workers = 0
        if workers:
            no_worker_since = None
        elif no_worker_since is None:
            no_worker_since = now
        where = f"{len(pending)} of {len(futures)} tasks unfinished"
        if no_worker_since is not None and now - no_worker_since >= min(timeout,
                                                                        WORKER_TIMEOUT_S):
            raise ClusterError(f"no Dask worker left ({where}); start one with 'dask worker "
                               f"{client.scheduler.address}' and run again")
        if now - last >= timeout:
            raise ClusterError(f"no result from the Dask cluster for {timeout:g} s ({where}); "
                               "see --dask-timeout")


def _gather(client, futures: list, progress: bool | None, desc: str, unit: str,
            timeout: float = DASK_TIMEOUT_S) -> list:
    """Results of the futures in order, with a progress bar as they complete."""
    from distributed import KilledWorker

    try:
        with progress_bar(len(futures) if progress else 0, desc, unit) as bar:
            for _ in _completed(client, futures, timeout):
                bar.update()
        return client.gather(futures)
    except KilledWorker as exc:  # a task that kept killing its workers
        raise ClusterError(f"Dask workers died running a task ({exc})") from None


def _on_cluster(client, robots, ground, v, kp, kd, energy, chunks, progress,
                timeout: float = DASK_TIMEOUT_S) -> list[dict]:
    """Map the chunks of every robot over a Dask cluster; one result dict per robot."""
    n = min(chunks, kp.size)
    pieces = [np.array_split(a, n) for a in (v, kp, kd)]
    futures = [f for r in robots for f in client.map(
        _batch_chunk, [r] * n, [ground] * n, *pieces, [energy] * n, pure=False)]
    show = progress or (progress is None and kp.size * len(robots) > 50_000)
    got = _gather(client, futures, show, "simulating (Dask)", "chunk", timeout)
    return [{k: np.concatenate([g[k] for g in got[i * n:(i + 1) * n]]) for k in got[0]}
            for i in range(len(robots))]


def _describe(ds: xr.Dataset) -> None:
    units = {"depth": "x_s (= m_t g / k_g)", "stroke_min": "x_s", "stroke_max": "x_s",
             "u_peak": "m_t g", "T": "sqrt(m_t / k_g)", "t_first_stop": "sqrt(m_t / k_g)",
             "E0": "m_t g x_s", "ET": "m_t g x_s", "ground": "m_t g x_s",
             "actuator": "m_t g x_s"}
    for k, u in units.items():
        if k in ds:
            ds[k].attrs["units"] = u


def depth_map(impact: Impact | float, robot: Robot = PAPER_IMPEDANCE_ROBOT,
              ground: Ground = LINEAR_GROUND, n: int = 101, **kw: Any) -> xr.Dataset:
    """The paper's (k_p, k_d) map at one impact velocity (gains in [0, 1]).

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot.
    ground : Ground
        Ground model.
    n : int
        Points per axis.
    **kw
        Passed to :func:`impedance_dataset` (``energy``, ``scheduler``, ``progress``).
    """
    impact = Impact.of(impact)
    check_count("n", n, 2, MAX_GRID)
    g = np.round(np.linspace(0.0, 1.0, n), 12)
    return impedance_dataset(impact.v0, g, g, robot, ground, **kw).squeeze(("v0", "r_m", "s"))


# ----------------------------------------------------------------- curves
def _optimum_row(v0: float, robot: Robot, ground: Ground, objective: str,
                 grid: int) -> dict[str, Any]:
    try:
        o = optimize_impedance(v0, robot, ground, objective=objective, grid=grid)
    except ParameterError as exc:
        if "no feasible gains" not in str(exc):
            raise
        # no gains in the box keep the stroke: recorded, not fatal for the sweep
        row: dict[str, Any] = {k: math.nan for k in CURVE_VARIABLES}
        row.update(steps=-1, on_stroke_boundary=False, feasible=False)
        return row
    row = {k: getattr(o, k) for k in CURVE_VARIABLES if k != "feasible"}
    row["feasible"] = True
    return row


def optimal_impedance_curves(v0: Sequence[float], robot: Robot = PAPER_IMPEDANCE_ROBOT,
                             ground: Ground = LINEAR_GROUND, *, r_m=None, s=None,
                             objective: str = "depth", grid: int = 101,
                             scheduler: str | None = None,
                             progress: bool | None = True,
                             dask_timeout: float = DASK_TIMEOUT_S) -> xr.Dataset:
    """Optimal gains against impact velocity, for the robot or a family of robots.

    Parameters
    ----------
    v0 : sequence of float
        Impact velocities.
    robot : Robot
        The robot (or the template of the family).
    ground : Ground
        Ground model.
    r_m, s : sequence of float, optional
        A family: every combination of these mass ratios and strokes.
    objective : {"depth", "cot", "cot-lossless"}
        What the gains minimise.
    grid : int
        Starting grid of each optimisation.
    scheduler : str, optional
        Dask scheduler address (one task per problem).
    progress : bool, optional
        Progress bar.
    dask_timeout : float
        As :func:`impedance_dataset`'s.

    Returns
    -------
    xarray.Dataset
        Dims ``(r_m, s, v0)``, variables :data:`CURVE_VARIABLES`; where no gains in
        the box keep the stroke, ``feasible`` is False and the figures are NaN.
    """
    v0s = np.atleast_1d(np.asarray(v0, dtype=float))
    for v in v0s:  # bad input fails before any work (and any progress bar)
        Impact(float(v))
    check_count("grid", grid, 2, MAX_GRID)
    rr, ss, robots = _family(robot, r_m, s)
    tasks = [(float(v), r) for r in robots for v in v0s]
    dask_timeout = _check_timeout(dask_timeout)
    client = _client(scheduler, dask_timeout)
    if client is None:
        rows = [_optimum_row(v, r, ground, objective, grid) for v, r in
                show_progress(tasks, progress, "optimal gains", "landing problem")]
    else:
        with client:  # closed also when the run fails or is interrupted
            futures = client.map(_optimum_row, *zip(*tasks, strict=True),
                                 [ground] * len(tasks), [objective] * len(tasks),
                                 [grid] * len(tasks), pure=False)
            rows = _gather(client, futures, progress, "optimal gains (Dask)",
                           "landing problem", dask_timeout)
    shape = (len(rr), len(ss), len(v0s))
    data = {k: (("r_m", "s", "v0"), np.array([row[k] for row in rows]).reshape(shape))
            for k in CURVE_VARIABLES}
    ds = xr.Dataset(data, coords={"r_m": rr, "s": ss, "v0": v0s})
    ds.attrs.update(objective=objective, grid=grid, **ground_attrs(ground),
                    title=f"optimal impedance (objective: {objective})")
    return ds


def paper_observations(curves: xr.Dataset, robot: Robot = PAPER_IMPEDANCE_ROBOT) -> dict:
    """Check the paper's Section IV claims on one curve; numbers, not adjectives.

    A trend needs two feasible velocities and a minimum inside the range three: with fewer,
    its claim is None (cannot tell), not a vacuous True.

    Parameters
    ----------
    curves : xarray.Dataset
        From :func:`optimal_impedance_curves`.
    robot : Robot
        Which curve (its ``r_m`` and ``s``).
    """
    c = curves.sel(r_m=robot.r_m, s=robot.s)
    c = c.isel(v0=np.flatnonzero(c.feasible.values.astype(bool)))
    if c.v0.size == 0:  # no gains keep the stroke at any velocity: nothing to observe
        return {"feasible_velocities": 0}
    order = np.argsort(np.abs(c.v0.values))
    speed = np.abs(c.v0.values[order])
    kp = c.k_p.values[order]
    kd = c.k_d.values[order]
    dkp = np.diff(kp)
    i_min = int(np.argmin(kd))
    n = len(speed)  # a trend needs two speeds, a minimum between two others three: else None
    return {
        "feasible_velocities": int(c.v0.size),
        "kp_increasing_with_speed": bool(np.all(dkp >= -1e-9)) if n >= 2 else None,
        "kp_decreases": [(float(speed[i]), float(speed[i + 1])) for i in
                         np.flatnonzero(dkp < -1e-9)],
        "kd_min_at_speed": float(speed[i_min]),
        "kd_first_decreasing_then_increasing": bool(
            0 < i_min < len(kd) - 1 and np.all(np.diff(kd[:i_min + 1]) <= 1e-9)
            and np.all(np.diff(kd[i_min:]) >= -1e-9)) if n >= 3 else None,
        "critical_speed_between_2_and_6": bool(2.0 <= speed[i_min] <= 6.0) if n >= 3 else None,
        "all_on_stroke_boundary": bool(np.all(c.on_stroke_boundary.values[speed > 0])),
        "u_peak_at_fastest": float(c.u_peak.values[order][-1]),
        "fastest_speed": float(speed[-1]),
    }


# --------------------------------------------------------------- netCDF I/O
def save_dataset(ds: xr.Dataset, path: str | Path) -> None:
    """Write netCDF (v3, through scipy: no extra dependency); booleans as int8.

    Parameters
    ----------
    ds : xarray.Dataset
        What to write.
    path : str or Path
        Where.
    """
    out = ds.copy()
    for k, v in out.data_vars.items():
        if v.dtype == bool:
            out[k] = v.astype(np.int8)
            out[k].attrs["boolean"] = 1
        elif v.dtype == np.int64:
            out[k] = v.astype(np.int32)
    out.to_netcdf(path, engine="scipy")


def load_dataset(path: str | Path) -> xr.Dataset:
    """Read a dataset written by :func:`save_dataset` (booleans restored).

    Parameters
    ----------
    path : str or Path
        The netCDF file.
    """
    ds = xr.load_dataset(path, engine="scipy")
    for k, v in ds.data_vars.items():
        if v.attrs.get("boolean") == 1:
            ds[k] = v.astype(bool)
    return ds
