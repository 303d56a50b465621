"""One landing on a non-affine ground: the hybrid segment loop of :mod:`.landing`, with the
yielding segments integrated by :func:`.yielding.march_yield`.

The static and flight modes are affine for every ground model (drag and added mass act
only while the foot yields), so they keep the exact propagation, the exact event location
and the rest proof of :mod:`.landing`; this loop reuses those parts unchanged. What differs:

* the crater's static hold is the law's ``f(d, 0)`` (``d`` for the built-in laws);
* an added-mass ground gets an event where the cone completes (``d = d_c``: the law's
  slope is discontinuous there, so the integrator restarts on it);
* a foot landing at speed on the crater bottom meets the cone's grains at rest: a perfectly
  inelastic collision, ``v+ = m_f v / (m_f + m_a(d))``, whose loss goes to the grain ledger;
* the energy ledger gains the drag and grain losses, and the plastic work is integrated
  (``int f(d, 0) dd``) rather than read off ``d^2 / 2``;
* no creep proof (it needs the yielding mode affine): such landings end at the horizon
  or the step budget, with rest not proven.

Output rows have :data:`N_OUT_NL` columns: the exact kernel's layout plus ``O_EDRAG`` and
``O_EGRAIN``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import (
    ENTRY,
    EV_LAND,
    EV_LIFT,
    EV_SAT_HIGH,
    EV_SAT_LOW,
    EV_STOP,
    EV_YIELD,
    FLIGHT,
    JIT,
    LINEAR,
    N_OUT,
    O_EGND,
    O_ET,
    REST_PROVEN,
    SAT_HIGH,
    SAT_LOW,
    STATIC,
    STEP_BUDGET,
    TOO_MANY_SEGMENTS,
    YIELDING,
)
from softlanding.simulation.kernel.events import build_events, contact_mode, due_event
from softlanding.simulation.kernel.groundlaw import (
    G_DC,
    G_LOCK,
    G_MF,
    NY,
    added_mass_at,
    control_at,
    hold_force,
    yield_rhs,
)
from softlanding.simulation.kernel.landing import (
    B_TSTOP,
    X_UMAX,
    X_UMIN,
    X_WORK,
    begin_segment,
    derivative_functionals,
    energy_form,
    final_status,
    fresh_landing,
    in_range,
    initial_mode,
    march,
    mode_changed,
    record_segment,
    reject,
    rest_proof,
    schedule_switch,
    workspace,
    write_output,
)
from softlanding.simulation.kernel.linalg import dot, flat25, norm_rows4, prop4_t, row, row5
from softlanding.simulation.kernel.model import energy_rel
from softlanding.simulation.kernel.yielding import (
    A_DRAG,
    A_GRAIN,
    A_PLAST,
    advance,
    march_yield,
    workspace_nl,
)

EV_CONE = 7  # the added-mass cone completes (d = d_c): the integrator restarts
O_EDRAG, O_EGRAIN = N_OUT, N_OUT + 1
N_OUT_NL = N_OUT + 2


@njit(**JIT)
def cone_event(G, z, C, codes, ne):
    """Add the cone-completion event ``-x_f - d_c`` to a yielding segment still above it."""
    dc = G[G_DC]
    if dc < np.inf and -z[2] < dc and ne < C.shape[0]:
        C[ne, :] = 0.0
        C[ne, 2] = -1.0
        C[ne, 4] = -dc
        codes[ne] = EV_CONE
        ne += 1
    return ne


@njit(**JIT)
def collide(G, fp, buf, z, d, acc):
    """A foot landing at ``z[3] < 0`` on the cone's grains at rest: inelastic collision."""
    ma = added_mass_at(G, fp, buf, d)
    if ma > 0.0:
        mf = G[G_MF]
        v = z[3]
        vp = mf * v / (mf + ma)
        acc[A_GRAIN] += 0.5 * mf * v * v - 0.5 * (mf + ma) * vp * vp
        z[3] = vp


@njit(**JIT)
def apply_event_nl(P, law_args, code, z, z0, t, d, shift, mode, regime, steps, Kf, umax,
                   open_loop, k_ol, ext, bk, acc):
    """The transition at an event (as :func:`.landing.apply_event`, with the law's hold and
    the grain collision). Returns ``(mode, regime, d, shift, steps)``."""
    G, fp, buf = law_args
    prev = mode
    if code == EV_STOP:
        z[3] = 0.0
        d = max(d, -z[2])
        if bk[B_TSTOP] != bk[B_TSTOP]:
            bk[B_TSTOP] = t
        mode = contact_mode(P, z, hold_force(G, fp, buf, d), Kf, umax, open_loop, k_ol)
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
            collide(G, fp, buf, z, d, acc)
        else:
            z[3] = 0.0
            mode = contact_mode(P, z, hold_force(G, fp, buf, d), Kf, umax, open_loop, k_ol)
    elif code == EV_SAT_HIGH:
        regime = SAT_HIGH
    elif code == EV_SAT_LOW:
        regime = SAT_LOW
    elif code != EV_CONE:
        regime = LINEAR
    steps, regime = mode_changed(P, mode, prev, z, z0, t, steps, regime, Kf, umax, open_loop,
                                 ext, bk)
    return mode, regime, d, shift, steps


@njit(**JIT)
def initial_grains(G, fp, buf, z, acc):
    """Grains already moving with a foot that starts below the surface: their kinetic energy
    is an input to the ledger (counted against the grain loss)."""
    if z[3] < 0.0 and z[2] < 0.0:
        acc[A_GRAIN] -= 0.5 * added_mass_at(G, fp, buf, -z[2]) * z[3] * z[3]


@njit(**JIT)
def _segment_events(P, G, mode, regime, cu, d, hold, shift, Kf, umax, open_loop, z, C, codes):
    """Event functionals of a segment (the hold in the static mode, the cone if yielding)."""
    ne = build_events(P, mode, regime, cu, d, hold, shift, Kf, umax, open_loop, C, codes)
    if mode == YIELDING:
        ne = cone_event(G, z, C, codes, ne)
    return ne


@njit(**JIT)
def due_event_yield(A, cu, G, fp, buf, C, ne, z, K):
    """Index of an event already due at the start of a yielding segment (slopes from the
    non-affine vector field), or -1."""
    y = np.zeros(NY)
    for i in range(5):
        y[i] = z[i]
    yield_rhs(flat25(A), row5(cu), G, fp, buf, y, K, 0)
    for k in range(ne):
        g0 = dot(row(C, k), z)
        if g0 > 0.0 or (g0 == 0.0 and dot(row(C, k), K[0]) > 0.0):
            return k
    return -1


@njit(**ENTRY, nogil=True)
def simulate_one_nl(P, law_args, pol, x0, lim, out, rec):
    """Simulate one landing on a non-affine ground; fill ``out`` (:data:`N_OUT_NL` columns)
    and the segment records ``rec`` (as :func:`.landing.simulate_one`).

    ``law_args = (G, fp, buf)``; ``pol``, ``lim`` as :func:`.landing.simulate_one`, and
    ``lim`` ends with the integrator's relative tolerance. Python calls it for one landing
    (:func:`softlanding.simulation.kernel.run_landing_nl`), :func:`batch_range_nl` for each
    landing of a batch. Releases the GIL.
    """
    Kf, umax, sched_t, sched_K = pol
    s_lim, t_max, max_seg, energy, max_steps, rtol = lim
    if not in_range(x0, s_lim):
        reject(out)
        out[O_EDRAG] = out[O_EGRAIN] = np.nan
        return
    G, fp, buf = law_args
    z, z0, open_loop, k_ol, ext, bk = fresh_landing(x0, sched_K)
    t, d, shift, sidx, nseg = 0.0, max(0.0, -z[2]), 0.0, 0, 0
    status = TOO_MANY_SEGMENTS
    acc = np.zeros(3)
    initial_grains(G, fp, buf, z, acc)
    mode, regime, steps = initial_mode(P, z, hold_force(G, fp, buf, d), Kf, umax, open_loop,
                                       k_ol, bk, energy_rel(P, z, z0))
    ws, wsn = workspace(), workspace_nl(rtol)
    cs, C, dC, codes, cdata, cres = ws[0], ws[1], ws[2], ws[3], ws[4], ws[5]
    while nseg < max_seg:
        ext[X_WORK] += 1.0
        if ext[X_WORK] > max_steps:
            status = STEP_BUDGET
            break
        locked = mode == YIELDING and G[G_LOCK] == 1.0
        if locked:
            regime = LINEAR  # the lock's own force, saturated in the vector field
        cu, A, shift = begin_segment(P, mode, regime, Kf, umax, k_ol, z, d, shift)
        nseg += 1
        record_segment(rec, nseg - 1, t, mode, z, cu, A, shift)
        u_now = control_at(G, fp, buf, cu, z) if mode == YIELDING else dot(cu, z)
        ext[X_UMIN], ext[X_UMAX] = min(ext[X_UMIN], u_now), max(ext[X_UMAX], u_now)
        t_next = sched_t[sidx] if (open_loop and sidx < sched_t.shape[0]) else np.inf
        hold = hold_force(G, fp, buf, d)
        ne = _segment_events(P, G, mode, regime, cu, d, hold, shift, Kf,
                             np.inf if locked else umax, open_loop, z, C, codes)
        if mode == STATIC and t_next == np.inf and rest_proof(A, z, C, ne, cs, cu, ext):
            status = REST_PROVEN
            break
        derivative_functionals(C, A, ne, dC)
        if mode == YIELDING:
            hit = due_event_yield(A, cu, G, fp, buf, C, ne, z, wsn[0])
        else:
            hit = due_event(C, dC, ne, z)
        if hit < 0:
            if mode == YIELDING:
                sysd = (flat25(A), row5(cu), G, fp, buf)
                t, hit, time_event, stop = march_yield(sysd, z, t, t_next, t_max, max_steps,
                                                       C, ne, ext, acc, wsn)
            else:
                key = -1 if open_loop else 4 * mode + regime
                t, hit, time_event, stop = march(A, mode, key, z, t, t_next, t_max, max_steps,
                                                 ne, cu, energy_form(cu, energy), energy, ext,
                                                 False, ws, None)
            if stop >= 0:
                status = stop
                break
            if time_event:
                sidx += 1
                k_ol = sched_K[sidx]
                mode, steps = schedule_switch(P, z, hold, mode, steps, Kf, umax, open_loop,
                                              k_ol)
                continue
        mode, regime, d, shift, steps = apply_event_nl(P, law_args, codes[hit], z, z0, t, d,
                                                       shift, mode, regime, steps, Kf, umax,
                                                       open_loop, k_ol, ext, bk, acc)
    z[0], z[2] = z[0] - shift, z[2] - shift
    if nseg < rec[0].shape[0]:
        rec[0][nseg] = t
    status, d = final_status(status, d, ext, cdata, cres)
    write_output_nl(P, out, status, z, z0, d, steps, nseg, s_lim, energy, ext, bk, acc)


@njit(**JIT)
def write_output_nl(P, out, status, z, z0, d, steps, nseg, s_lim, energy, ext, bk, acc):
    """:func:`.landing.write_output`, with the integrated plastic work and the drag and grain
    losses (NaN unless the foot's rest is proven)."""
    write_output(P, out, status, z, z0, d, steps, nseg, s_lim, energy, ext, bk)
    foot_rests = out[O_ET] == out[O_ET]
    out[O_EGND] = acc[A_PLAST] if foot_rests else np.nan
    out[O_EDRAG] = acc[A_DRAG] if foot_rests else np.nan
    out[O_EGRAIN] = acc[A_GRAIN] if foot_rests else np.nan


@njit(**ENTRY, nogil=True)
def batch_range_nl(Ps, ridx, G, fp, Kfs, umaxs, x0s, s_lims, t_max, max_seg, energy, max_steps,
                   rtol, out, i0, i1):
    """Feedback landings ``i0 <= i < i1`` on one non-affine ground (as
    :func:`.landing.batch_range`)."""
    empty_t = np.zeros(0)
    empty_K = np.zeros((0, 5))
    buf = np.zeros(5)
    rec = (np.zeros(0), np.zeros((0, 5, 5)), np.zeros((0, 5)), np.zeros((0, 5)),
           np.zeros(0, dtype=np.int64))
    for i in range(i0, i1):
        simulate_one_nl(Ps[ridx[i]], (G, fp, buf), (Kfs[i], umaxs[i], empty_t, empty_K),
                        x0s[i], (s_lims[i], t_max, max_seg, energy, max_steps, rtol), out[i],
                        rec)


@njit(**ENTRY)
def sample_nl(P, G, fp, rtol, ts, A, z, cu, mode, grid, idx, out, uout):
    """States ``out`` (n, 5) and forces ``uout`` at the sorted times ``grid`` (segment
    ``idx[i]``): exact propagation in the affine modes, DOP853 in the yielding ones."""
    buf = np.zeros(5)
    wsn = workspace_nl(rtol)
    y = np.zeros(NY)
    cur = -1
    tcur = 0.0
    for i in range(grid.shape[0]):
        k = idx[i]
        if mode[k] == YIELDING:
            sysd = (flat25(A[k]), row5(cu[k]), G, fp, buf)
            if k != cur or grid[i] < tcur:
                for j in range(5):
                    y[j] = z[k, j]
                for j in range(5, NY):
                    y[j] = 0.0
                cur, tcur = k, ts[k]
            advance(sysd, y, grid[i] - tcur, wsn)
            tcur = grid[i]
            for j in range(5):
                out[i, j] = y[j]
            uout[i] = control_at(G, fp, buf, cu[k], y)
        else:
            Ak = flat25(A[k])
            zk = prop4_t(Ak, norm_rows4(Ak), row5(z[k]), grid[i] - ts[k])
            for j in range(5):
                out[i, j] = zk[j]
            uout[i] = dot(cu[k], zk)
