"""The mode data of one robot and ground, packed in one flat array.

:func:`pack_model` lays out the dict of :func:`softlanding.model.dynamics.mode_matrices`
in a contiguous float64 vector; the compiled code reads views of it (no
copies). Energies are read off the quadratic form ``E(z) = z . EQ z / 2 + Ec . z``
and the ground work off ``Wg d^2``, as :mod:`softlanding.model.dynamics` defines them; the
crater's hold off ``hold d`` (the ground's stiffness ``K``: 1 for the paper's ground).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import JIT

# layout of the packed model
M_A = 0  # (3, 5, 5) open-loop mode matrices: yielding, static, flight
M_B = 75  # (3, 5) control columns
M_FZ = 90  # (5,) static support force F_req = Fz . z + Fu u
M_FU = 95
M_EQ = 96  # (5, 5) Hessian of the mechanical energy
M_EC = 121  # (5,) gradient of the mechanical energy at z = 0
M_WG = 126  # ground work Wg d^2
M_HOLD = 127  # the crater holds support forces up to hold * d (apart from Wg: the ledger's)
N_MODEL = 128


def pack_model(mats: dict) -> np.ndarray:
    """The flat model vector of a :func:`~softlanding.model.dynamics.mode_matrices` dict.

    Parameters
    ----------
    mats : dict
        :func:`~softlanding.model.dynamics.mode_matrices` output.
    """
    P = np.empty(N_MODEL)
    P[M_A:M_B] = np.asarray(mats["A"], dtype=float).reshape(75)
    P[M_B:M_FZ] = np.asarray(mats["B"], dtype=float).reshape(15)
    P[M_FZ:M_FU] = mats["Fz"]
    P[M_FU] = mats["Fu"]
    P[M_EQ:M_EC] = np.asarray(mats["EQ"], dtype=float).reshape(25)
    P[M_EC:M_WG] = mats["Ec"]
    P[M_WG] = mats["Wg"]
    P[M_HOLD] = mats["hold"]
    return P


@njit(**JIT)
def closed_loop(P, mode, cu):
    """``A + B cu^T`` of a ground mode: the affine closed loop for ``u = cu . z``."""
    A = np.empty((5, 5))
    a, b = M_A + 25 * mode, M_B + 5 * mode
    for i in range(5):
        for j in range(5):
            A[i, j] = P[a + 5 * i + j] + P[b + i] * cu[j]
    return A


@njit(**JIT)
def support_Fz(P):
    """View of ``Fz`` (support force ``Fz . z + Fu u`` of the static mode)."""
    return P[M_FZ:M_FU]


@njit(**JIT)
def energy_rel(P, z, z0):
    """Mechanical energy at ``z`` relative to the potential energy at ``z0``.

    ``z . EQ z / 2 + Ec . (z - z0)``; zero entries of the form are skipped (the
    sum is the same, and an infinite state gives no ``inf * 0``).
    """
    q = 0.0
    for i in range(5):
        for j in range(5):
            e = P[M_EQ + 5 * i + j]
            if e != 0.0:
                q += z[i] * z[j] * e
    acc = 0.5 * q
    for i in range(5):
        e = P[M_EC + i]
        if e != 0.0:
            acc += e * (z[i] - z0[i])
    return acc


@njit(**JIT)
def crater_hold(P, d):
    """The largest support force a crater of depth ``d`` takes without yielding, ``K d``
    (``d`` itself, bit for bit, on the paper's ground ``K = 1``)."""
    return P[M_HOLD] * d


@njit(**JIT)
def ground_work(P, d):
    """Work done on the ground by a foot that dug to depth ``d`` (from the surface)."""
    return P[M_WG] * d * d
