"""One landing: the hybrid segment loop, split into its parts.

* :func:`begin_segment` -- closed-loop matrix of the current mode and regime;
* :func:`rest_proof` -- the static mode's exact future ranges (rest proven?);
* :func:`march` -- propagation on the exact step map, event search on each step,
  stroke and force extrema and the actuator's work on the way;
* :func:`apply_event` -- the finite state machine's transition at an event;
* :func:`simulate_one` -- the loop over segments (Python's entry for one landing), and
  :func:`batch_range`.

The loop is compiled twice, from the same source, by the type of its argument ``proofs``:
with ``proofs=True`` it is the whole kernel; with ``proofs=None`` the **lite** kernel, in
which numba prunes the branches ``if proofs is None`` select (at compile time, by the
argument's type) and so never compiles the proof that a foot creeps forever
(:mod:`.creep`'s eigen-decomposition past its first checks, and the proof tried after
every step) nor the proof that an undamped leg's hops settle (:mod:`.hops` past its first
check). Where a landing would need one, the lite kernel ends it with the code
``NEEDS_PROOFS`` and the landing is run again, from the start, by the whole kernel: every
landing's numbers are the whole kernel's (the two share every operation up to that point).
A landing that never needs the proofs (the demo's, most of a study's) compiles only the
lite kernel: about a third less to compile on a fresh install.

Per-landing bookkeeping lives in two small arrays: ``ext`` (extrema of the
stroke and the force, the actuator work) and ``bk`` (first stop time, rest
time, energy and actuator work at the start of the final static phase).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import (
    BODY_FLIES_OFF,
    BODY_THROUGH_FOOT,
    ENTRY,
    EV_LAND,
    EV_LIFT,
    EV_SAT_HIGH,
    EV_SAT_LOW,
    EV_STOP,
    EV_YIELD,
    FEAS_TOL,
    FLIGHT,
    HOPS_TO_LIMIT,
    HORIZON,
    JIT,
    LINEAR,
    NEEDS_PROOFS,
    NEVER_RESTS_CREEP,
    O_DEPTH,
    O_DLIM,
    O_E0,
    O_EACT,
    O_EGND,
    O_ET,
    O_FEAS,
    O_FOOT_REST,
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
    OUT_OF_RANGE,
    REST_PROVEN,
    SAT_HIGH,
    SAT_LOW,
    SCALE_MAX,
    STATIC,
    STEP_BUDGET,
    THETA,
    TOO_MANY_SEGMENTS,
    YIELDING,
)
from softlanding.simulation.kernel.creep import (
    creep_candidate,
    creep_limit_depth,
    creep_proof,
    creep_setup,
)
from softlanding.simulation.kernel.events import (
    build_events,
    classify,
    contact_mode,
    control_vector,
    due_event,
    earliest_event,
    rows4,
    step_to,
)
from softlanding.simulation.kernel.hops import (
    H_DLIM,
    hop_eligible,
    hop_event,
    hop_state,
    hops_pending,
    hops_settled,
)
from softlanding.simulation.kernel.linalg import (
    covector_t,
    dot,
    expm,
    flat25,
    gram,
    interior_extremum_t,
    matvec_t,
    norm_inf4,
    norm_rows4,
    prop4_t,
    quad_t,
    row,
    row5,
)
from softlanding.simulation.kernel.model import closed_loop, crater_hold, energy_rel, ground_work
from softlanding.simulation.kernel.rest import future_range

# ext: extrema and actuator work
X_SMIN, X_SMAX, X_UMIN, X_UMAX, X_ACT, X_WORK = range(6)
# bk: first stop time, rest time, energy and actuator work at rest
B_TSTOP, B_T, B_ET, B_ACT = range(4)


@njit(**JIT)
def begin_segment(P, mode, regime, Kf, umax, k_ol, z, d, shift):
    """Control functional and closed-loop matrix of a segment; in flight, shift heights.

    Without ground force the dynamics depend on heights only through the stroke,
    so in flight heights are measured from the crater bottom: the landing
    function ``x_f + d`` is then computed without cancellation, which matters
    at a grazing landing (its time error is sqrt(rounding of ``x_f``)).
    Returns ``(cu, A, shift)``.
    """
    cu = control_vector(mode, regime, Kf, umax, k_ol)
    A = closed_loop(P, mode, cu)
    if mode == FLIGHT and shift == 0.0 and d > 0.0:
        invariant = True
        for i in range(4):
            if A[i, 0] + A[i, 2] != 0.0:
                invariant = False
        if invariant:
            shift = d
            z[0] += shift
            z[2] += shift
    return cu, A, shift


@njit(**JIT)
def record_segment(rec, n, t, mode, z, cu, A, shift):
    """Store segment ``n`` (start time, mode, start state, control, matrix) if room."""
    rec_t, rec_A, rec_z, rec_cu, rec_mode = rec
    if n >= rec_t.shape[0] - 1:
        return
    rec_t[n] = t
    rec_mode[n] = mode
    for i in range(5):
        rec_z[n, i] = z[i]
        rec_cu[n, i] = cu[i]
        for j in range(5):
            rec_A[n, i, j] = A[i, j]
    rec_z[n, 0] -= shift
    rec_z[n, 2] -= shift


@njit(**JIT)
def rest_proof(A, z, C, ne, cs, cu, ext):
    """Static mode, no schedule switch ahead: True if no event can ever fire.

    Then the future extrema of the stroke and the force are folded into ``ext``.
    """
    for k in range(ne):
        lo, hi = future_range(A, z, row(C, k))
        if hi > 0.0:
            return False
    lo, hi = future_range(A, z, row5(cs))
    ext[X_SMIN], ext[X_SMAX] = min(ext[X_SMIN], lo), max(ext[X_SMAX], hi)
    lo, hi = future_range(A, z, row5(cu))
    ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], lo), max(ext[X_UMAX], hi)
    return True


@njit(**JIT)
def step_size(A, mode):
    """Marching step: ``||A|| h <= THETA`` (in the static mode ``omega h <= THETA``).

    In the static mode only the body moves: event functions are sums of two
    exponentials, whose derivative has at most one zero per step when omega h < pi.
    """
    if mode == STATIC:
        rho = math.sqrt(abs(A[1, 0])) + abs(A[1, 1])
        return THETA / max(rho, 1e-2)
    return THETA / max(norm_inf4(A), 1e-3)


@njit(**JIT, forceinline=True)
def _fold_step(A, nrm, z, z1, h, cs, dcs, ddcs, cu, dcu, ddcu, ext):
    """Fold the stroke and force extrema over (0, h] into ``ext`` (tuples, see march)."""
    se_v = interior_extremum_t(A, nrm, z, z1, h, cs, dcs, ddcs)
    if se_v == se_v:
        ext[X_SMIN], ext[X_SMAX] = min(ext[X_SMIN], se_v), max(ext[X_SMAX], se_v)
    ue = interior_extremum_t(A, nrm, z, z1, h, cu, dcu, ddcu)
    if ue == ue:
        ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], ue), max(ext[X_UMAX], ue)
    sv = dot(cs, z1)
    ext[X_SMIN], ext[X_SMAX] = min(ext[X_SMIN], sv), max(ext[X_SMAX], sv)
    uv = dot(cu, z1)
    ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], uv), max(ext[X_UMAX], uv)


@njit(**JIT)
def step_map(A, mode, key, Qe, energy, phic, gc, hc):
    """Marching step ``h``, ``exp(A h)`` and the Gramian of ``Qe`` over ``h`` (``Qe`` itself
    if no energy), from the cache slot ``key`` if filled (a closed loop is fixed by
    its mode and regime in a feedback landing)."""
    if key >= 0 and hc[key] == hc[key]:
        return hc[key], phic[key], gc[key]
    hstep = step_size(A, mode)
    Phi = expm(A, hstep)
    G = gram(A, Qe, hstep) if energy else Qe
    if key >= 0:
        hc[key] = hstep
        for i in range(5):
            for j in range(5):
                phic[key, i, j] = Phi[i, j]
                gc[key, i, j] = G[i, j]
    return hstep, Phi, G


@njit(**JIT, inline="always")
def march(A, mode, key, z, t, t_next, t_max, max_steps, ne, cu, Qe, energy, ext, creep, ws,
          proofs):
    """Propagate ``z`` in place to the segment's first event, schedule switch or horizon.

    Inlined (numba's IR) into each segment loop: as a compiled function of its own, every
    library above it optimised and emitted its machine code once more (0.5-2 s of the first
    compile); it is typed once per loop instead.

    ``ws`` is the landing's :func:`workspace`. The step map ``exp(A h)`` (and the
    energy Gramian) of a closed loop are cached under ``key`` (mode and regime;
    -1: no caching). With ``creep`` (see :mod:`.creep`) the proof that the foot
    creeps forever is tried after every step (``proofs`` None: never, not compiled).
    Returns ``(t, hit, time_event, stop)``: the new time, the index of the event that
    fired (-1 if none), whether a schedule switch ended the segment, and a status code that
    ends the landing (``HORIZON``, ``NEVER_RESTS_CREEP``, ``STEP_BUDGET`` once ``ext[X_WORK]``, the
    landing's count of steps and segments, reaches ``max_steps``) or -1.
    """
    cs, C, dC, _, cdata, cres, phic, gc, hc = ws
    hstep, Phi, G = step_map(A, mode, key, Qe, energy, phic, gc, hc)
    At, Pt, Gt = flat25(A), flat25(Phi), flat25(G)
    nrm = norm_rows4(At)
    Ct, dCt = rows4(C), rows4(dC)
    cst, cut = row5(cs), row5(cu)
    dcs = covector_t(cst, At)
    ddcs = covector_t(dcs, At)
    dcu = covector_t(cut, At)
    ddcu = covector_t(dcu, At)
    zt = row5(z)
    while True:
        h, time_event = step_to(t, hstep, t_next)
        if time_event or h != hstep:
            z1 = prop4_t(At, nrm, zt, h)
        else:
            z1 = matvec_t(Pt, zt)
        sbest, hit = earliest_event(At, nrm, zt, z1, h, Ct, dCt, ne)
        if hit >= 0:
            h = sbest
            z1 = prop4_t(At, nrm, zt, h)
            time_event = False
        _fold_step(At, nrm, zt, z1, h, cst, dcs, ddcs, cut, dcu, ddcu, ext)
        if energy:
            ext[X_ACT] -= quad_t(Gt if h == hstep else flat25(gram(A, Qe, h)), zt)
        t += h
        zt = z1
        ext[X_WORK] += 1.0
        stop = -1
        if hit < 0 and not time_event:
            if creep_proven(proofs, creep, cdata, zt, C, ne, cu, ext, cres):
                stop = NEVER_RESTS_CREEP
            elif t > t_max:
                stop = HORIZON
            elif ext[X_WORK] >= max_steps:
                stop = STEP_BUDGET
        if hit >= 0 or time_event or stop >= 0:
            for i in range(5):
                z[i] = zt[i]
            return t, hit, time_event, stop


@njit(**JIT)
def creep_proven(proofs, creep, cdata, z, C, ne, cu, ext, cres):
    """:func:`.creep.creep_proof` after a step if ``creep``; never in the lite kernel
    (``proofs`` None: the proof is not compiled)."""
    if proofs is None:
        return False
    return creep and creep_proof(cdata, z, C, ne, cu, (ext[X_UMIN], ext[X_UMAX]), cres)


@njit(**JIT)
def creep_start(proofs, A, cu, C, ne, cdata):
    """A yielding segment: ``(creep, needs_proofs)``. ``creep``: the creep proof applies
    (:func:`.creep.creep_setup` filled ``cdata``). The lite kernel (``proofs`` None) runs
    only the first checks (:func:`.creep.creep_candidate`): ``needs_proofs`` if they pass."""
    if proofs is None:
        return False, creep_candidate(A, cu, C, ne)[0]
    return creep_setup(A, cu, C, ne, cdata), False


@njit(**JIT)
def hops_end(proofs, P, A, z, z0, d, C, cu, hk):
    """A stance entry of an eligible landing: ``(settled, needs_proofs)``, as
    :func:`.hops.hops_settled`; the lite kernel (``proofs`` None) stops where that would
    go past its first check (:func:`.hops.hops_pending`)."""
    if proofs is None:
        return False, hops_pending(hk)
    return hops_settled(P, A, z, z0, d, C, cu, hk), False


@njit(**JIT)
def apply_event(P, code, z, z0, t, d, shift, mode, regime, steps, Kf, umax, open_loop, k_ol,
                ext, bk):
    """The transition at an event; updates ``z`` and ``bk`` in place.

    Returns ``(mode, regime, d, shift, steps)``.
    """
    prev = mode
    if code == EV_STOP:
        z[3] = 0.0
        d = max(d, -z[2])
        if bk[B_TSTOP] != bk[B_TSTOP]:
            bk[B_TSTOP] = t
        mode = contact_mode(P, z, crater_hold(P, d), Kf, umax, open_loop, k_ol)
    elif code == EV_YIELD:
        mode = YIELDING
    elif code == EV_LIFT:
        mode = FLIGHT
    elif code == EV_LAND:
        z[0] -= shift
        z[2] = -d
        shift = 0.0
        if z[3] < 0.0:
            mode = YIELDING
        else:
            z[3] = 0.0
            mode = contact_mode(P, z, crater_hold(P, d), Kf, umax, open_loop, k_ol)
    elif code == EV_SAT_HIGH:
        regime = SAT_HIGH
    elif code == EV_SAT_LOW:
        regime = SAT_LOW
    else:
        regime = LINEAR
    steps, regime = mode_changed(P, mode, prev, z, z0, t, steps, regime, Kf, umax, open_loop,
                                 ext, bk)
    return mode, regime, d, shift, steps


@njit(**JIT)
def mode_changed(P, mode, prev, z, z0, t, steps, regime, Kf, umax, open_loop, ext, bk):
    """Bookkeeping of a ground-mode change: count a new intrusion step, note the foot's
    (latest) rest, re-classify the feedback's regime. Returns ``(steps, regime)``."""
    if mode != prev:
        if mode == YIELDING:
            steps += 1
        elif mode == STATIC:
            bk[B_T] = t
            bk[B_ET] = energy_rel(P, z, z0)
            bk[B_ACT] = ext[X_ACT]
        if not open_loop:
            regime = classify(mode, z, Kf, umax)
    return steps, regime


@njit(**JIT)
def initial_mode(P, z, hold, Kf, umax, open_loop, k_ol, bk, E0):
    """Ground mode at impact (from the foot's velocity; at rest, from the support force
    against the crater's ``hold``); returns ``(mode, regime, steps)``."""
    if z[3] < 0.0:
        mode = YIELDING
    elif z[3] > 0.0:
        mode = FLIGHT
    else:
        mode = contact_mode(P, z, hold, Kf, umax, open_loop, k_ol)
    steps = 0
    if mode == YIELDING:
        steps = 1
    elif mode == STATIC:
        bk[B_T] = 0.0
        bk[B_ET] = E0
        bk[B_ACT] = 0.0
    regime = OPEN_LOOP if open_loop else classify(mode, z, Kf, umax)
    return mode, regime, steps


@njit(**JIT)
def energy_form(cu, energy):
    """Symmetric form of the actuator power ``u (v_b - v_f)`` (zero if not wanted)."""
    Qe = np.zeros((5, 5))
    if energy:
        cv = np.zeros(5)  # stroke rate v_b - v_f
        cv[1], cv[3] = 1.0, -1.0
        for i in range(5):
            for j in range(5):
                Qe[i, j] = 0.5 * (cu[i] * cv[j] + cv[i] * cu[j])
    return Qe


@njit(**JIT)
def write_output(P, out, status, z, z0, d, steps, nseg, s_lim, energy, ext, bk):
    """Fill the output row (layout ``O_*``)."""
    # the foot may still be creeping down if rest is unproven; a proven creep's d is its
    # limit, and so is settled hops' (energy balance, see .hops)
    at_limit = status == NEVER_RESTS_CREEP or status == HOPS_TO_LIMIT
    out[O_DEPTH] = d if at_limit else max(d, -z[2])
    out[O_STEPS] = steps
    out[O_TSTOP] = bk[B_TSTOP]
    out[O_T] = bk[B_T]
    out[O_UPEAK] = max(abs(ext[X_UMIN]), abs(ext[X_UMAX]))
    out[O_SMIN] = ext[X_SMIN]
    out[O_SMAX] = ext[X_SMAX]
    ftol = FEAS_TOL * max(1.0, s_lim)
    feas = status == REST_PROVEN and ext[X_SMIN] >= -ftol and ext[X_SMAX] <= s_lim + ftol
    out[O_FEAS] = 1.0 if feas else 0.0
    out[O_STATUS] = status
    out[O_E0] = energy_rel(P, z0, z0)
    foot_rests = status in (REST_PROVEN, BODY_THROUGH_FOOT, BODY_FLIES_OFF)
    out[O_ET] = bk[B_ET] if foot_rests else np.nan
    out[O_EGND] = ground_work(P, d)
    out[O_EACT] = bk[B_ACT] if (energy and foot_rests) else np.nan
    out[O_NSEG] = nseg
    out[O_UMIN] = ext[X_UMIN]
    out[O_UMAX] = ext[X_UMAX]
    out[O_DLIM] = out[O_DEPTH] if (foot_rests or at_limit) else np.nan
    out[O_FOOT_REST] = 1.0 if foot_rests else 0.0


@njit(**JIT)
def final_status(status, d, ext, cdata, cres):
    """A proven creep's limits; a proven rest of the foot under a body that does not rest
    (stroke without bound) is not a rest. Returns ``(status, d)``."""
    if status == NEVER_RESTS_CREEP:
        fold_creep(ext, cres)
        d = creep_limit_depth(cdata)
    elif status == REST_PROVEN and ext[X_SMIN] == -np.inf:
        status = BODY_THROUGH_FOOT
    elif status == REST_PROVEN and ext[X_SMAX] == np.inf:
        status = BODY_FLIES_OFF
    return status, d


@njit(**JIT)
def fold_creep(ext, cres):
    """Fold a proven creep's future stroke range and force limit into ``ext``."""
    if cres[0] == cres[0]:
        ext[X_SMIN] = min(ext[X_SMIN], cres[0])
    if cres[1] == cres[1]:
        ext[X_SMAX] = max(ext[X_SMAX], cres[1])
    ext[X_UMIN] = min(ext[X_UMIN], cres[2])
    ext[X_UMAX] = max(ext[X_UMAX], cres[2])


@njit(**JIT)
def in_range(x0, s_lim):
    """False if an initial state component or the stroke is not finite or exceeds
    ``SCALE_MAX``: in double precision the events of such a landing (foot speeds of
    order 1 against positions beyond 1e8) cannot be resolved, and a run would
    report rounding as physics."""
    if not abs(s_lim) <= SCALE_MAX:
        return False
    for i in range(4):
        if not abs(x0[i]) <= SCALE_MAX:
            return False
    return True


@njit(**JIT)
def reject(out):
    """Output row of a landing not simulated (``OUT_OF_RANGE``): NaN but the counts."""
    out[:] = np.nan
    out[O_STATUS] = OUT_OF_RANGE
    out[O_STEPS] = out[O_NSEG] = out[O_FEAS] = out[O_FOOT_REST] = 0.0


@njit(**JIT)
def workspace():
    """Per-landing work arrays: the stroke functional, event functionals and their
    derivatives, event codes, a creep proof's eigen-data and results, and the cache of
    step maps and Gramians per (mode, regime)."""
    cs = np.zeros(5)  # stroke x_b - x_f
    cs[0], cs[2] = 1.0, -1.0
    return (cs, np.zeros((4, 5)), np.zeros((4, 5)), np.zeros(4, dtype=np.int64),
            np.zeros((3, 8), dtype=np.complex128), np.full(3, np.nan), np.empty((12, 5, 5)),
            np.empty((12, 5, 5)), np.full(12, np.nan))


@njit(**JIT)
def derivative_functionals(C, A, ne, dC):
    """``dC[k] = C[k] A``: d/dt of each event function."""
    for k in range(ne):
        dk = covector_t(row(C, k), flat25(A))
        for j in range(5):
            dC[k, j] = dk[j]


@njit(**JIT)
def schedule_switch(P, z, hold, mode, steps, Kf, umax, open_loop, k_ol):
    """An open-loop schedule switch (``open_loop`` is then true): a pinned foot may yield
    (beyond the crater's ``hold``) or lift off under the new force."""
    if mode == STATIC:
        mode = contact_mode(P, z, hold, Kf, umax, open_loop, k_ol)
        if mode == YIELDING:
            steps += 1
    return mode, steps


@njit(**JIT)
def fresh_landing(x0, sched_K):
    """The start of a landing: the augmented state ``z`` and a copy ``z0``, whether the
    control is an open-loop schedule and its first gain row, the extrema ``ext`` and the
    bookkeeping ``bk``."""
    z = np.empty(5)
    for i in range(4):
        z[i] = x0[i]
    z[4] = 1.0
    open_loop = sched_K.shape[0] > 0
    k_ol = sched_K[0] if open_loop else np.zeros(5)
    ext = np.array([z[0] - z[2], z[0] - z[2], np.inf, -np.inf, 0.0, 0.0])
    return z, z.copy(), open_loop, k_ol, ext, np.full(4, np.nan)


@njit(**ENTRY, nogil=True)
def simulate_one(P, pol, x0, lim, out, rec, proofs):
    """Simulate one landing; fill ``out`` (layout ``O_*``) and the segment records.

    Python calls it for one landing (:func:`softlanding.simulation.kernel.run_landing`:
    records allocated there, trimmed there; a compiled entry wrapping it was a second
    compile of the whole loop, about 2 s of the first one), :func:`batch_range` for each
    landing of a batch. Releases the GIL.

    Parameters
    ----------
    P : (N_MODEL,) array
        Packed mode data (:func:`softlanding.simulation.kernel.model.pack_model`).
    pol : tuple ``(Kf, umax, sched_t, sched_K)``
        Feedback ``u = Kf[mode] . z`` per ground mode (3, 5), its saturation
        (``inf`` for none), and the open-loop schedule ``u = sched_K[i] . z`` on
        ``[sched_t[i-1], sched_t[i])`` ((m + 1, 5); a constant force is the row
        ``[0, 0, 0, 0, u]``; no rows means feedback).
    x0 : (4,) array
        Initial state.
    lim : tuple ``(s_lim, t_max, max_seg, energy, max_steps)``
        Stroke, horizon, segment limit, whether to integrate the actuator work, and
        the budget of marching steps plus segments (bounded work for any input).
    out : (N_OUT,) array
    rec : tuple ``(t, A, z, cu, mode)`` of arrays with ``len(t) - 1`` rows (or 0)
        Segment records; the row after the last holds the end time.
    proofs : None or True
        True: the whole kernel. None: the lite kernel, which ends a landing that needs the
        creep or hop proof with ``out[O_STATUS] = NEEDS_PROOFS`` (see the module's notes).
    """
    Kf, umax, sched_t, sched_K = pol
    s_lim, t_max, max_seg, energy, max_steps = lim
    if not in_range(x0, s_lim):
        return reject(out)
    z, z0, open_loop, k_ol, ext, bk = fresh_landing(x0, sched_K)
    t, d, shift, sidx, nseg = 0.0, max(0.0, -z[2]), 0.0, 0, 0
    status = TOO_MANY_SEGMENTS
    mode, regime, steps = initial_mode(P, z, crater_hold(P, d), Kf, umax, open_loop, k_ol, bk,
                                       energy_rel(P, z, z0))
    ws = workspace()
    cs, C, dC, codes, cdata, cres = ws[0], ws[1], ws[2], ws[3], ws[4], ws[5]
    hops, hk = hop_eligible(Kf, umax, open_loop), hop_state()
    while nseg < max_seg:
        ext[X_WORK] += 1.0
        if ext[X_WORK] > max_steps:
            status = STEP_BUDGET
            break
        cu, A, shift = begin_segment(P, mode, regime, Kf, umax, k_ol, z, d, shift)
        nseg += 1
        record_segment(rec, nseg - 1, t, mode, z, cu, A, shift)
        u_now = dot(cu, z)
        ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], u_now), max(ext[X_UMAX], u_now)
        t_next = sched_t[sidx] if (open_loop and sidx < sched_t.shape[0]) else np.inf
        ne = build_events(P, mode, regime, cu, d, crater_hold(P, d), shift, Kf, umax, open_loop,
                          C, codes)
        if mode == STATIC and t_next == np.inf and rest_proof(A, z, C, ne, cs, cu, ext):
            status = REST_PROVEN
            break
        if hops and mode == STATIC:
            settled, needs_proofs = hops_end(proofs, P, A, z, z0, d, C, cu, hk)
            if needs_proofs:
                status = NEEDS_PROOFS
                break
            if settled:
                status = HOPS_TO_LIMIT
                d = hk[H_DLIM]
                break
        derivative_functionals(C, A, ne, dC)
        hit = due_event(C, dC, ne, z)
        if hit < 0:
            creep = False
            if mode == YIELDING and t_next == np.inf:
                creep, needs_proofs = creep_start(proofs, A, cu, C, ne, cdata)
                if needs_proofs:
                    status = NEEDS_PROOFS
                    break
            key = -1 if open_loop else 4 * mode + regime
            t, hit, time_event, stop = march(A, mode, key, z, t, t_next, t_max, max_steps, ne, cu,
                                             energy_form(cu, energy), energy, ext, creep, ws,
                                             proofs)
            if stop >= 0:
                status = stop
                break
            if time_event:
                sidx += 1
                k_ol = sched_K[sidx]
                mode, steps = schedule_switch(P, z, crater_hold(P, d), mode, steps, Kf, umax,
                                              open_loop, k_ol)
                continue
        if hops:
            hop_event(codes[hit], z, t, hk)
        mode, regime, d, shift, steps = apply_event(P, codes[hit], z, z0, t, d, shift, mode,
                                                    regime, steps, Kf, umax, open_loop, k_ol,
                                                    ext, bk)
    z[0] -= shift
    z[2] -= shift
    if nseg < rec[0].shape[0]:
        rec[0][nseg] = t
    status, d = final_status(status, d, ext, cdata, cres)
    write_output(P, out, status, z, z0, d, steps, nseg, s_lim, energy, ext, bk)


@njit(**ENTRY, nogil=True)
def batch_range(Ps, ridx, Kfs, umaxs, x0s, s_lims, t_max, max_seg, energy, max_steps, out, i0,
                i1):
    """Feedback-policy landings ``i0 <= i < i1``; row i uses the packed model ``Ps[ridx[i]]``.

    The whole kernel (``proofs=True``): a batch is many landings, some of which may need
    the proofs. Serial and GIL-free: :func:`softlanding.simulation.kernel.run_batch` runs
    chunks of a batch on a pool of threads that take the next chunk when done (dynamic
    scheduling: no spinning, no idle core behind a busy one).
    """
    empty_t = np.zeros(0)
    empty_K = np.zeros((0, 5))
    rec = (np.zeros(0), np.zeros((0, 5, 5)), np.zeros((0, 5)), np.zeros((0, 5)),
           np.zeros(0, dtype=np.int64))
    for i in range(i0, i1):
        simulate_one(Ps[ridx[i]], (Kfs[i], umaxs[i], empty_t, empty_K), x0s[i],
                     (s_lims[i], t_max, max_seg, energy, max_steps), out[i], rec,
                     np.bool_(True))  # (not the literal True: one compile, the one Python's
                     # run_landing makes, not a second of the whole loop)
