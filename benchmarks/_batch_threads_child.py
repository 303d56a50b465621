"""Child process of bench_batch_threads.py: one scheduling variant, timed once."""

import json
import sys
import time

import numba
import numpy as np
from numba import njit, prange

from softlanding.model.dynamics import mode_matrices
from softlanding.simulation import kernel as K
from softlanding.simulation.kernel.landing import simulate_one

how, every = sys.argv[1], int(sys.argv[2])
g = np.round(np.linspace(0, 1, 101), 12)
v = np.round(np.linspace(-10, 0, 21), 12)
KP, KD, V = (a.ravel()[::every] for a in np.meshgrid(g, g, v, indexing="ij"))
n = KP.size
Kf = np.empty((n, 3, 5))
Kf[:, :, 0], Kf[:, :, 1] = -KP[:, None], -KD[:, None]
Kf[:, :, 2], Kf[:, :, 3] = KP[:, None], KD[:, None]
Kf[:, :, 4] = (10.0 * KP)[:, None]
x0 = np.stack([np.full(n, 10.0), V, np.zeros(n), V], axis=1)
um, ss, ridx = np.full(n, np.inf), np.full(n, 20.0), np.zeros(n, dtype=np.int64)
mats = mode_matrices(5.0)
P = K.packed_model(mats)[None, :]
out = np.zeros((n, K.N_OUT))

@njit(parallel=True, cache=True)
def batch_prange(Ps, ridx, Kfs, umaxs, x0s, s_lims, t_max, max_seg, energy, max_steps, out):
    e = np.zeros(0)
    eK = np.zeros((0, 5))
    rec = (np.zeros(0), np.zeros((0, 5, 5)), np.zeros((0, 5)), np.zeros((0, 5)),
           np.zeros(0, dtype=np.int64))
    for i in prange(x0s.shape[0]):
        simulate_one(Ps[ridx[i]], (Kfs[i], umaxs[i], e, eK), x0s[i],
                     (s_lims[i], t_max, max_seg, energy, max_steps), out[i], rec,
                     np.bool_(True))  # the whole kernel, as run_batch's batch_range

def run():
    if how.startswith("pool"):
        K.run_batch([mats], ridx, Kf, um, x0, ss, 1e4, 500, False, out,
                    threads=int(how.split("-")[1]))
    else:
        batch_prange(P, ridx, Kf, um, x0, ss, 1e4, 500, False, 1e6, out)

if how == "omp-chunk":
    numba.set_parallel_chunksize(64)
run()  # compile / load
c, w = time.process_time(), time.perf_counter()
run()
print(json.dumps([time.process_time() - c, time.perf_counter() - w, n]))
