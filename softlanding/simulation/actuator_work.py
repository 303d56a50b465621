"""The actuator's positive and negative work along exact (affine) trajectory segments.

On a segment the augmented state is ``z(tau) = expm(A tau) z0`` and the force is
``u = c . z``, so the power the actuator puts into the robot, ``P = u (v_b - v_f)``,
is an exact function of time, a quadratic form ``P = z' M z``. Its positive and negative
parts are integrated between its sign changes (located by bracketing and Brent's method on
the exact solution) in closed form: ``int_0^h z(s)' M z(s) ds = z(0)' G(h) z(0)`` with the
Gramian ``G(h) = int_0^h e^(A's) M e^(As) ds`` from Van Loan's block exponential, on
sub-intervals of ``||A|| h <= 1`` (on a long decaying piece the block exponential of the whole
piece would lose the digits its growing half cancels). An independent check of the
optimiser's energy, which it computes from a slack variable on a grid
(``tests/softlanding/simulation/test_actuator_work.py`` checks it against adaptive
quadrature).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ocp.structure.flows import expm
from softlanding.model.dynamics import VB, VF


@dataclass
class Work:
    """Work the actuator does on the robot.

    Attributes
    ----------
    positive, negative : float
        ``int max(P, 0) dt`` and ``int max(-P, 0) dt`` (both >= 0).
    """

    positive: float = 0.0
    negative: float = 0.0

    @property
    def net(self) -> float:
        """``positive - negative``: the actuator's net work on the robot."""
        return self.positive - self.negative

    def drawn(self, eta: float) -> float:
        """Energy drawn with regenerative efficiency ``eta``: ``positive - eta negative``.

        Parameters
        ----------
        eta : float
            Fraction of the absorbed energy recovered.
        """
        return self.positive - eta * self.negative

    def __add__(self, other: Work) -> Work:
        return Work(self.positive + other.positive, self.negative + other.negative)


def segment_work(A: np.ndarray, z0: np.ndarray, c: np.ndarray, duration: float,
                 probes: int = 64) -> Work:
    """Positive and negative work on one exact segment ``z' = A z``, ``u = c . z``.

    Parameters
    ----------
    A : ndarray (5, 5)
        Closed-loop matrix of the augmented state ``[x_b, v_b, x_f, v_f, 1]``.
    z0 : ndarray (5,)
        Augmented state at the segment's start.
    c : ndarray (5,)
        Force functional.
    duration : float
        Segment length.
    probes : int
        Samples used to bracket the sign changes of ``P``.
    """
    if duration <= 0:
        return Work()

    def power(t: float) -> float:
        z = expm(A * t) @ z0
        return float(c @ z) * float(z[VB] - z[VF])

    # the probes by one step's exact flow, applied probe to probe (one matrix exponential,
    # not one per probe: the probes only bracket; a bracket is checked on the exact power)
    ts = np.linspace(0.0, duration, probes + 1)
    step = expm(A * (duration / probes))
    zs = np.empty((probes + 1, len(z0)))
    zs[0] = z0
    for k in range(probes):
        zs[k + 1] = step @ zs[k]
    ps = (zs @ c) * (zs[:, VB] - zs[:, VF])
    cuts = [0.0]
    for j in np.flatnonzero(ps[:-1] * ps[1:] < 0):
        a, b = float(ts[j]), float(ts[j + 1])
        if power(a) * power(b) < 0:
            cuts.append(brentq(power, a, b, xtol=1e-15, rtol=1e-15))
    cuts.append(duration)
    e = np.zeros(len(z0))
    e[VB], e[VF] = 1.0, -1.0
    M = 0.5 * (np.outer(c, e) + np.outer(e, c))  # P = z' M z
    out = Work()
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        if b <= a:
            continue
        val = _integral(A, M, expm(A * a) @ z0, b - a)
        if val >= 0:
            out.positive += val
        else:
            out.negative -= val
    return out


def _integral(A: np.ndarray, M: np.ndarray, za: np.ndarray, h: float) -> float:
    """``int_0^h z(s)' M z(s) ds`` along ``z' = A z`` from ``za``: the Gramian of equal
    sub-intervals of ``||A|| dt <= 1`` (Van Loan), the state carried by their exact flow."""
    n = len(za)
    parts = max(1, math.ceil(float(np.abs(A).sum(axis=0).max()) * h))
    dt = h / parts
    F = expm(np.block([[-A.T, M], [np.zeros((n, n)), A]]) * dt)
    flow = F[n:, n:]
    gram = flow.T @ F[:n, n:]
    gram = 0.5 * (gram + gram.T)
    total, z = 0.0, za
    for _ in range(parts):
        total += float(z @ gram @ z)
        z = flow @ z
    return total


def result_work(res, t_end: float) -> Work:
    """Work along an exact simulation up to ``t_end`` (its recorded segments).

    Parameters
    ----------
    res : LandingResult
        A simulation (:func:`softlanding.simulation.simulator.simulate`).
    t_end : float
        Where to stop.
    """
    seg = res.segments
    out = Work()
    for k in range(len(seg["t"]) - 1):
        t0, t1 = float(seg["t"][k]), min(float(seg["t"][k + 1]), t_end)
        if t1 <= t0:
            break
        out = out + segment_work(seg["A"][k], seg["z"][k], seg["cu"][k], t1 - t0)
    return out


def state_at(res, t: float) -> np.ndarray:
    """The exact state of a simulation at time ``t`` (within its segments).

    Parameters
    ----------
    res : LandingResult
        A simulation.
    t : float
        Time.
    """
    seg = res.segments
    k = int(np.clip(np.searchsorted(seg["t"][:-1], t, side="right") - 1, 0,
                    len(seg["t"]) - 2))
    return (expm(seg["A"][k] * (t - seg["t"][k])) @ seg["z"][k])[:4]


__all__ = ["Work", "result_work", "segment_work", "state_at"]
