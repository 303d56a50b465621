"""Compiled core of the exact event-driven hybrid simulator (entry points).

Each (ground mode, control regime) pair is an affine system ``z' = A z`` in the
augmented state ``z = [x_b, v_b, x_f, v_f, 1]``. Within a segment the solution
is ``z(t) = exp(A t) z0``; we march with the exact step map ``exp(A h)`` on a
grid fine enough (``||A|| h <= 1``) that no event can hide between two grid
points without a sign change of the event function or of its derivative, then
locate the event time by safeguarded Newton iteration on the exact solution.
There is no ODE tolerance anywhere: errors are rounding only.

The compiled parts live in :mod:`softlanding.kernel`; this module holds the
Python entry points :func:`run_landing` and :func:`run_batch` used by
:mod:`softlanding.simulate`, and re-exports the output layout and status codes.
The mode data are read from :func:`softlanding.dynamics.mode_matrices`
(matrices, support force, the energy's quadratic form and the ground work).
"""

from __future__ import annotations

import numpy as np

from .kernel.const import (  # noqa: F401  (re-exported)
    EV_LAND,
    EV_LIFT,
    EV_SAT_HIGH,
    EV_SAT_LOW,
    EV_STOP,
    EV_UNSAT,
    EV_YIELD,
    FEAS_TOL,
    FLIGHT,
    HORIZON,
    LINEAR,
    N_OUT,
    NEVER_RESTS_CREEP,
    O_DEPTH,
    O_DLIM,
    O_E0,
    O_EACT,
    O_EGND,
    O_ET,
    O_FEAS,
    O_NSEG,
    O_SMAX,
    O_SMIN,
    O_STATUS,
    O_STEPS,
    O_T,
    O_TSTOP,
    O_UMAX,
    O_UMIN,
    O_UPEAK,
    OPEN_LOOP,
    REST_PROVEN,
    SAT_HIGH,
    SAT_LOW,
    STATIC,
    TOO_MANY_SEGMENTS,
    YIELDING,
)
from .kernel.landing import simulate_batch, simulate_one
from .kernel.model import pack_model

# ------------------------------------------------------------ Python entry points
STATUS_NAMES = {
    REST_PROVEN: "rest proven",
    HORIZON: "horizon reached before rest could be proven",
    TOO_MANY_SEGMENTS: "segment limit reached before rest could be proven",
    NEVER_RESTS_CREEP: "never rests: the foot creeps toward a limit depth forever",
}
"""Human-readable name of each status code of ``out[O_STATUS]``."""


def run_landing(mats, Kf, umax, sched_t, sched_u, x0, s_lim, t_max, max_seg, energy):
    """One landing; returns the output row (layout ``O_*``) and the segment records.

    Parameters
    ----------
    mats : dict
        :func:`softlanding.dynamics.mode_matrices` of the robot and ground.
    Kf : (3, 5) array
        Feedback ``u = Kf[mode] . z`` per ground mode (ignored when open loop).
    umax : float
        Force limit (``inf`` for none).
    sched_t, sched_u : arrays (m,), (m + 1,)
        Open-loop schedule; empty ``sched_u`` means feedback.
    x0 : (4,) array
        Initial state.
    s_lim, t_max, max_seg, energy
        Stroke, horizon, segment limit, whether to compute the energy ledger.

    Returns
    -------
    out : (N_OUT,) array
    segments : dict
        ``t`` (n+1,), ``A`` (n, 5, 5), ``z`` (n, 5), ``cu`` (n, 5), ``mode`` (n,):
        segment start times (and the end time), closed-loop matrices, start
        states, control functionals and ground modes.
    """
    P = pack_model(mats)
    nrec = 32  # segment records; grown and re-run in the rare long case
    while True:
        out = np.zeros(N_OUT)
        rec_t = np.full(nrec + 1, np.nan)
        rec_A = np.empty((nrec, 5, 5))
        rec_z = np.empty((nrec, 5))
        rec_cu = np.empty((nrec, 5))
        rec_mode = np.empty(nrec, dtype=np.int64)
        simulate_one(P, (Kf, float(umax), sched_t, sched_u), x0,
                     (float(s_lim), float(t_max), int(max_seg), bool(energy)), out,
                     (rec_t, rec_A, rec_z, rec_cu, rec_mode))
        if out[O_NSEG] < nrec:
            break
        nrec = max_seg + 1
    n = int(out[O_NSEG])
    return out, {"t": rec_t[: n + 1].copy(), "A": rec_A[:n].copy(), "z": rec_z[:n].copy(),
                 "cu": rec_cu[:n].copy(), "mode": rec_mode[:n].copy()}


def run_batch(mats_list, ridx, Kf, umax, x0, s_lim, t_max, max_seg, energy, out):
    """Feedback landings in parallel; row ``i`` uses ``mats_list[ridx[i]]``.

    ``Kf`` (n, 3, 5), ``umax`` (n,), ``x0`` (n, 4), ``s_lim`` (n,); fills ``out`` (n, N_OUT).
    """
    Ps = np.stack([pack_model(m) for m in mats_list])
    simulate_batch(Ps, np.asarray(ridx, dtype=np.int64), Kf, umax, x0, s_lim, float(t_max),
                   int(max_seg), bool(energy), out)
