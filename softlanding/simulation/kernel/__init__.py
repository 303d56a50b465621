"""Compiled core of the exact event-driven hybrid simulator (entry points).

Each (ground mode, control regime) pair is an affine system ``z' = A z`` in the
augmented state ``z = [x_b, v_b, x_f, v_f, 1]``. Within a segment the solution
is ``z(t) = exp(A t) z0``; we march with the exact step map ``exp(A h)`` on a
grid fine enough (``||A|| h <= 1``) that no event can hide between two grid
points without a sign change of the event function or of its derivative, then
locate the event time by safeguarded Newton iteration on the exact solution.
There is no ODE tolerance anywhere: errors are rounding only.

The compiled parts are this package's modules:

* :mod:`.const` -- codes, the output layout, tolerances;
* :mod:`.model` -- the mode data packed in one flat array; energy and ground work;
* :mod:`.linalg` -- matrix exponential, propagation, event-time refinement, Gramians;
* :mod:`.events` -- control regimes, the ground's mode logic, event functionals and search;
* :mod:`.rest` -- exact future ranges in the static mode (the rest proof);
* :mod:`.creep` -- the proof that a yielding foot creeps toward a limit depth forever;
* :mod:`.landing` -- the segment loop of one landing, its GIL-free entry points.

Compiled functions take the options :data:`.const.JIT`: they have no Python wrapper, as only
compiled code calls them (a call from Python would crash); the few that Python calls (the
entry points, and helpers the tests call) take :data:`.const.ENTRY`.

This module holds the Python entry points :func:`run_landing` and :func:`run_batch` used by
:mod:`softlanding.simulation.simulator`, and re-exports the output layout and status codes.
The mode data are read from :func:`softlanding.model.dynamics.mode_matrices`
(matrices, support force, the energy's quadratic form, the ground work and the crater's
hold ``K d``).

Statuses (``out[O_STATUS]``, names in :data:`STATUS_NAMES`): ``REST_PROVEN`` (the
foot rests forever and so does the body: the stroke stays bounded);
``BODY_THROUGH_FOOT`` / ``BODY_FLIES_OFF`` (the foot's rest is proven but the
stroke runs away to -inf / +inf); ``NEVER_RESTS_CREEP`` (proven: the foot creeps
toward the limit depth ``O_DLIM`` forever); ``HOPS_TO_LIMIT`` (rest not proven: an
undamped leg's hops shrink toward the lift-off threshold, and ``O_DEPTH`` =
``O_DLIM`` is their limit by energy balance, :mod:`softlanding.simulation.kernel.hops`);
``HORIZON``, ``TOO_MANY_SEGMENTS``, ``STEP_BUDGET`` (gave up: nothing proven);
``OUT_OF_RANGE`` (not simulated). Columns added to the first layout: ``O_DLIM``
(the depth's limit as t -> inf: the rest depth when the foot rests, a creep's or
shrinking hops' limit depth, else NaN) and
``O_FOOT_REST`` (1 if the foot's rest is proven, whatever the body does).
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np
from numba import njit

from softlanding.simulation.kernel_cache import drop_stale_cache

drop_stale_cache()  # before any compiled module is loaded (numba misses inlined edits)

# the output layout, status and event codes, re-exported for the simulator
from softlanding.simulation.kernel.const import *  # noqa: E402, F403

# ruff: noqa: F405  (the codes used below come from the star import above)
from softlanding.simulation.kernel.landing import batch_range, simulate_one  # noqa: E402
from softlanding.simulation.kernel.linalg import flat25, norm_rows4, prop4_t, row5  # noqa: E402
from softlanding.simulation.kernel.model import pack_model  # noqa: E402

# ------------------------------------------------------------ Python entry points
Segments = Mapping[str, np.ndarray]
"""A landing's segment records (``LandingResult.segments``): arrays by field."""

STATUS_NAMES = {
    REST_PROVEN: "rest proven",
    HORIZON: "horizon reached before rest could be proven",
    TOO_MANY_SEGMENTS: "segment limit reached before rest could be proven",
    NEVER_RESTS_CREEP: "never rests: the foot creeps toward a limit depth forever",
    HOPS_TO_LIMIT: "rest not proven: an undamped leg hops on, the hops shrinking toward a "
                   "limit depth (the depth given, exact by energy balance)",
    STEP_BUDGET: "step budget exhausted before rest could be proven",
    BODY_THROUGH_FOOT: "the foot rests but the body passes through it (stroke without bound)",
    BODY_FLIES_OFF: "the foot rests but the body moves off without bound (stroke without bound)",
    OUT_OF_RANGE: "not simulated: initial state or stroke beyond 1e8 or not finite (unresolvable "
                  "in double precision)",
}
"""Human-readable name of each status code of ``out[O_STATUS]``."""


# ------------------------------------------------------------------ the first compile
_CHECKED: set[str] = set()

FIRST_COMPILE = {
    # kind -> (what is compiled, its CPU seconds on a cold cache on 2 shared cores, rounded
    # up; how many functions numba compiles for it, for the bar), measured by
    # benchmarks/bench_first_run.py (the demo) and tests/softlanding/simulation/test_first_run.py
    "affine": ("the simulator", 10, 80),
    "proofs": ("the simulator's creep and hop proofs", 5, 30),
    "batch": ("the simulator's batch loop", 10, 40),
    "non-affine": ("the simulator for non-affine grounds", 15, 80),
    "non-affine batch": ("the non-affine simulator's batch loop", 10, 40),
}
"""What a first call of each kernel entry compiles (see :func:`first_compile`)."""


class _CompileProgress:
    """numba's compile events during a first call: the notice at the first one, then a bar
    (on a terminal) over the functions compiled."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.notice: str | None = None
        self.stack = contextlib.ExitStack()
        self.bar: Any = None

    def notify(self, event) -> None:
        if event.is_start and self.notice is None:
            what, seconds, total = FIRST_COMPILE[self.kind]
            self.notice = f"softlanding: compiling {what} (once, about {seconds} s)..."
            print(self.notice, file=sys.stderr, flush=True)
            from softlanding.util.progress import progress_bar

            self.bar = self.stack.enter_context(progress_bar(total, "compiling", "function"))
        elif event.is_end and self.bar is not None:
            self.bar.update(1)


@contextlib.contextmanager

def first_compile(kind: str) -> Iterator[_CompileProgress | None]:
    """Around a kernel entry's call: if numba compiles anything during it (a cold cache),
    say so on stderr once (``softlanding: compiling the simulator (once, about 10 s)...``)
    and, when stderr is a terminal, draw a bar over the functions compiled. Only the first
    call of each kind in a process is watched (numba compiles an entry once); a warm cache
    prints nothing (numba's compile event fires on a compile, not on a load from its cache).

    Parameters
    ----------
    kind : str
        A key of :data:`FIRST_COMPILE`.

    Yields
    ------
    object or None
        What was watched (its ``notice``: the line printed, or None), or None if this kind
        was watched before in this process.
    """
    if kind in _CHECKED:
        yield None
        return
    _CHECKED.add(kind)
    from numba.core import event

    watch = _CompileProgress(kind)
    listener = type("_Listener", (event.Listener,), {
        "on_start": lambda self, e: watch.notify(e), "on_end": lambda self, e: watch.notify(e)})()
    try:
        with event.install_listener("numba:compile", listener):
            yield watch
    finally:
        watch.stack.close()


_PACKED: dict[int, tuple[dict, np.ndarray]] = {}
_POOL: list = []  # [ThreadPoolExecutor, its size]
RECORDS_FIRST = 64  # segment records allocated first; a longer landing is re-run with all
_RECORDS = threading.local()  # per thread: the RECORDS_FIRST records landings fill, reused


def packed_model(mats: dict) -> np.ndarray:
    """The packed mode data of ``mats``, cached by the dict's identity.

    The dicts of :func:`softlanding.model.dynamics.mode_matrices` are cached and
    treated as immutable; a new dict (``dict(mats, Wg=...)``) is packed anew.

    Parameters
    ----------
    mats : dict
        :func:`softlanding.model.dynamics.mode_matrices` output.
    """
    hit = _PACKED.get(id(mats))
    if hit is not None and hit[0] is mats:
        return hit[1]
    P = pack_model(mats)
    if len(_PACKED) >= 256:
        _PACKED.clear()
    _PACKED[id(mats)] = (mats, P)
    return P


def _f64(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _gain_rows(sched_u) -> np.ndarray:
    """Open-loop schedule as gain rows (m + 1, 5): a constant force u is [0, 0, 0, 0, u]."""
    s = np.asarray(sched_u, dtype=np.float64)
    if s.ndim == 2:
        return np.ascontiguousarray(s)
    rows = np.zeros((s.shape[0], 5))
    rows[:, 4] = s
    return rows


def run_landing(mats, Kf, umax, sched_t, sched_u, x0, s_lim, t_max, max_seg, energy, *,
                max_steps=DEFAULT_MAX_STEPS):
    """One landing; returns the output row (layout ``O_*``) and the segment records.

    Parameters
    ----------
    mats : dict
        :func:`softlanding.model.dynamics.mode_matrices` of the robot and ground.
    Kf : (3, 5) array
        Feedback ``u = Kf[mode] . z`` per ground mode (ignored when open loop).
    umax : float
        Force limit (``inf`` for none).
    sched_t, sched_u : arrays (m,), and (m + 1,) or (m + 1, 5)
        Open-loop schedule on ``[sched_t[i-1], sched_t[i])``: constant forces
        ``u = sched_u[i]``, or affine laws ``u = sched_u[i] . [x_b, v_b, x_f, v_f, 1]``;
        empty ``sched_u`` means feedback.
    x0 : (4,) array
        Initial state.
    s_lim, t_max, max_seg, energy
        Stroke, horizon, segment limit, whether to compute the energy ledger.
    max_steps : int
        Budget of marching steps plus segments: the landing ends with status
        ``STEP_BUDGET`` when it is spent (bounded work for any input: about 0.1-0.3 s
        for the default of a million on one core).

    Returns
    -------
    out : (N_OUT,) array
    segments : dict
        ``t`` (n+1,), ``A`` (n, 5, 5), ``z`` (n, 5), ``cu`` (n, 5), ``mode`` (n,):
        segment start times (and the end time), closed-loop matrices, start
        states, control functionals and ground modes.
    """
    args = (packed_model(mats), (_f64(Kf), float(umax), _f64(sched_t), _gain_rows(sched_u)),
            _f64(x0), (float(s_lim), float(t_max), int(max_seg), bool(energy), float(max_steps)))
    # this thread's records, taken while in use (a landing run meanwhile, by a signal
    # handler, makes its own)
    first = _RECORDS.__dict__.pop("rec", None) or _new_records(RECORDS_FIRST)
    first[0][0] = np.nan  # the end time of a landing not simulated (the other rows used are set)
    rec, out, proofs = first, np.zeros(N_OUT), None
    with first_compile("affine"):  # the lite kernel (.landing): no creep or hop proof
        simulate_one(*args, out, rec, proofs)
    if out[O_STATUS] == NEEDS_PROOFS:  # it needs one: the whole kernel, from the start
        proofs = True
        with first_compile("proofs"):
            simulate_one(*args, out, rec, proofs)
    n = int(out[O_NSEG])
    if n > RECORDS_FIRST:  # more segments than records: once more, with room for all
        rec, out = _new_records(n), np.zeros(N_OUT)
        simulate_one(*args, out, rec, proofs)
    seg = _segments(rec, n)
    _RECORDS.rec = first
    return out, seg


def _segments(rec: tuple, n: int) -> dict[str, np.ndarray]:
    """The first ``n`` segments of the records ``rec`` (:func:`_new_records`), copied, by
    field: ``t`` (n+1,), ``A``, ``z``, ``cu``, ``mode``."""
    return {"t": rec[0][:n + 1].copy(), "A": rec[1][:n].copy(), "z": rec[2][:n].copy(),
            "cu": rec[3][:n].copy(), "mode": rec[4][:n].copy()}


def _new_records(n: int) -> tuple:
    """Segment records for ``n`` segments (start times and the end time, closed-loop
    matrices, start states, control functionals, modes)."""
    return (np.full(n + 1, np.nan), np.empty((n, 5, 5)), np.empty((n, 5)), np.empty((n, 5)),
            np.empty(n, dtype=np.int64))


def _pool(threads: int):
    if not _POOL or _POOL[1] != threads:
        from concurrent.futures import ThreadPoolExecutor

        if _POOL:
            _POOL[0].shutdown(wait=False)
        _POOL[:] = [ThreadPoolExecutor(threads, thread_name_prefix="softlanding"), threads]
    return _POOL[0]


def default_threads() -> int:
    """Worker threads of a batch: ``NUMBA_NUM_THREADS`` (default: the number of cores)."""
    import numba

    return max(1, int(numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]


def _in_chunks(run_range, args: tuple, n: int, out: np.ndarray, threads: int | None,
               chunk: int | None, chunk_range: tuple[int, int]) -> None:
    """``run_range(*args, out, a, b)`` over ``[0, n)`` in chunks taken by ``threads``
    workers as they finish the previous one (default chunk: n / (16 threads) within
    ``chunk_range``), so a busy core or a run of long landings delays no one else."""
    import itertools

    res = out if (out.flags.c_contiguous and out.dtype == np.float64) else _f64(out)
    threads = default_threads() if threads is None else max(1, int(threads))
    lo, hi = chunk_range
    chunk = int(chunk) if chunk else min(hi, max(lo, n // (16 * threads)))
    if threads == 1 or n <= chunk:
        run_range(*args, res, 0, n)
    else:
        counter = itertools.count()

        def work():
            while (a := next(counter) * chunk) < n:
                run_range(*args, res, a, min(n, a + chunk))

        futures = [_pool(threads).submit(work) for _ in range(threads)]
        for f in futures:
            f.result()
    if res is not out:
        out[...] = res


def run_batch(mats_list, ridx, Kf, umax, x0, s_lim, t_max, max_seg, energy, out, *,
              threads=None, chunk=None, max_steps=DEFAULT_MAX_STEPS):
    """Feedback landings in parallel; row ``i`` uses ``mats_list[ridx[i]]``.

    ``Kf`` (n, 3, 5), ``umax`` (n,), ``x0`` (n, 4), ``s_lim`` (n,); fills ``out`` (n, N_OUT).
    ``threads`` workers (default :func:`default_threads`) take chunks of ``chunk``
    landings (default: n / (16 threads), between 16 and 1024) as they finish the
    previous one, so a busy core or a run of long landings delays no one else.
    ``max_steps`` bounds each landing's work as in :func:`run_landing`.

    Parameters
    ----------
    mats_list : list of dict
        :func:`softlanding.model.dynamics.mode_matrices` of each robot in the batch.
    ridx : (n,) int array
        Which entry of ``mats_list`` each landing uses.
    Kf : (n, 3, 5) array
        Feedback gains per landing and ground mode.
    umax : (n,) array
        Force limits (``inf`` for none).
    x0 : (n, 4) array
        Initial states.
    s_lim : (n,) array
        Strokes.
    t_max, max_seg, energy
        Horizon, segment limit, whether to compute the energy ledger.
    out : (n, N_OUT) array
        Filled with one output row per landing.
    threads : int, optional
        Worker threads (default :func:`default_threads`).
    chunk : int, optional
        Landings per chunk (default n / (16 threads), 16 to 1024).
    max_steps : int
        Work budget per landing, as in :func:`run_landing`.
    """
    Ps = np.stack([packed_model(m) for m in mats_list])
    args = (Ps, np.ascontiguousarray(ridx, dtype=np.int64), _f64(Kf), _f64(umax), _f64(x0),
            _f64(s_lim), float(t_max), int(max_seg), bool(energy), float(max_steps))
    with first_compile("batch"):
        _in_chunks(batch_range, args, len(args[4]), out, threads, chunk, (16, 1024))


@njit(**ENTRY)
def _sample(ts, A, z, grid, idx, out):
    for i in range(grid.shape[0]):
        k = idx[i]
        Ak = flat25(A[k])
        zk = prop4_t(Ak, norm_rows4(Ak), row5(z[k]), grid[i] - ts[k])
        for j in range(5):
            out[i, j] = zk[j]


def sample_segments(segments: Segments, grid: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact solution at the times ``grid`` (non-decreasing), from the segment records,
    with the kernel's own propagator (a pinned foot keeps exactly zero velocity).

    Returns the augmented states ``z`` (n, 5), the controls ``u`` (n,) and the modes (n,).

    Parameters
    ----------
    segments : dict
        The segment records a landing returned.
    grid : ndarray
        Times to sample at (non-decreasing).
    """
    grid, idx = _segment_of(segments, grid)
    z = np.empty((len(grid), 5))
    _sample(segments["t"], segments["A"], segments["z"], grid, idx.astype(np.int64), z)
    u = np.einsum("ij,ij->i", segments["cu"][idx], z)
    return z, u, segments["mode"][idx]


def _segment_of(segments: Segments, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``grid`` as floats, and the segment each of its times falls in (the last one for a
    time past the records' end)."""
    ts = segments["t"]
    nseg = len(ts) - 1
    grid = np.asarray(grid, float)
    return grid, np.clip(np.searchsorted(ts[:nseg], grid, side="right") - 1, 0, nseg - 1)


# ------------------------------------------------- non-affine grounds (integrated yielding)
DEFAULT_RTOL = 1e-12
"""Relative (and absolute) tolerance of the DOP853 yielding segments of a non-affine ground."""


def run_landing_nl(mats, law, Kf, umax, sched_t, sched_u, x0, s_lim, t_max, max_seg, energy,
                   rtol=DEFAULT_RTOL, *, max_steps=DEFAULT_MAX_STEPS):
    """One landing on a non-affine ground (:mod:`softlanding.simulation.kernel.nonaffine`).

    As :func:`run_landing`, with ``law = (G, fp)`` from
    :func:`softlanding.simulation.groundcode.kernel_law` and the integrator's tolerance ``rtol``;
    ``mats`` are the mode matrices of the robot on the linear ground (their static and
    flight modes and body rows are every ground's). The output row has
    ``N_OUT_NL`` columns (``O_EDRAG``, ``O_EGRAIN`` added).

    Parameters
    ----------
    mats, Kf, umax, sched_t, sched_u, x0, s_lim, t_max, max_seg, energy, max_steps
        As :func:`run_landing`.
    law : tuple
        The ground's law as the kernel takes it
        (:func:`softlanding.simulation.groundcode.kernel_law`).
    rtol : float
        Relative tolerance of the integrator of the yielding segments.
    """
    from softlanding.simulation.kernel.nonaffine import N_OUT_NL, simulate_one_nl

    G, fp = law
    # the compiled loop called as it is (records allocated here): a compiled entry wrapping
    # it was a second compile of the whole loop, as for :func:`run_landing`
    args = (packed_model(mats), (_f64(G), fp, np.zeros(5)),
            (_f64(Kf), float(umax), _f64(sched_t), _gain_rows(sched_u)), _f64(x0),
            (float(s_lim), float(t_max), int(max_seg), bool(energy), float(max_steps),
             float(rtol)))
    nrec = RECORDS_FIRST
    while True:
        out, rec = np.zeros(N_OUT_NL), _new_records(nrec)
        with first_compile("non-affine"):
            simulate_one_nl(*args, out, rec)
        n = int(out[O_NSEG])
        if n <= nrec:
            break
        nrec = n
    return out, {**_segments(rec, n), "law": (G, fp, float(rtol))}


def run_batch_nl(mats_list, ridx, law, Kf, umax, x0, s_lim, t_max, max_seg, energy, out,
                 rtol=DEFAULT_RTOL, *, threads=None, chunk=None, max_steps=DEFAULT_MAX_STEPS):
    """Feedback landings on one non-affine ground in parallel (as :func:`run_batch`;
    ``out`` has ``N_OUT_NL`` columns).

    Parameters
    ----------
    mats_list, ridx, Kf, umax, x0, s_lim, t_max, max_seg, energy, out, threads, chunk, max_steps
        As :func:`run_batch`.
    law, rtol
        As :func:`run_landing_nl` (the ground's law, the integrator's tolerance).
    """

    from softlanding.simulation.kernel.nonaffine import batch_range_nl

    G, fp = law
    Ps = np.stack([packed_model(m) for m in mats_list])
    args = (Ps, np.ascontiguousarray(ridx, dtype=np.int64), _f64(G), fp, _f64(Kf), _f64(umax),
            _f64(x0), _f64(s_lim), float(t_max), int(max_seg), bool(energy), float(max_steps),
            float(rtol))
    with first_compile("non-affine batch"):
        _in_chunks(batch_range_nl, args, len(args[6]), out, threads, chunk, (4, 256))


def sample_segments_nl(segments: Segments, grid: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`sample_segments` for a non-affine landing: its yielding segments are integrated
    again from their recorded starts (same integrator and tolerance).

    Parameters
    ----------
    segments, grid
        As for :func:`sample_segments`: the landing's segment records, the times.
    """
    from softlanding.simulation.kernel.nonaffine import sample_nl

    G, fp, rtol = segments["law"]
    grid, idx = _segment_of(segments, grid)
    z = np.empty((len(grid), 5))
    u = np.empty(len(grid))
    sample_nl(np.zeros(1), _f64(G), fp, rtol, segments["t"], segments["A"], segments["z"],
              segments["cu"], segments["mode"], grid, idx.astype(np.int64), z, u)
    return z, u, segments["mode"][idx]
