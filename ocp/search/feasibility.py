"""What a start would cost Ipopt, measured before it is solved: how far it violates the
path constraints and state bounds, and the dynamics' rates along it.

Both kinds of starts of :func:`ocp.multistart` (bang sequences and waypoint paths) pick,
of several cheap candidates, the one whose states violate the path constraints and
state bounds least: a start that runs through an obstacle or out of a bound costs Ipopt
hundreds of iterations and often ends on the wrong side. The violation is measured as
the check between nodes measures it (:mod:`ocp.transcriptions.verify`): each row's
largest excess relative to ``max(1, |bound|)``, summed over the rows.

The CasADi Functions (the check and the dynamics mapped over many points) are built once
per transcription and cached with its compiled phases.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..transcriptions.nlp import Transcription

__all__ = ["PathCheck", "mapped_rates"]


@dataclass
class PathCheck:
    """A phase's path constraints and bounded states on ``points`` points, and their bounds.

    Attributes
    ----------
    fn : casadi.Function
        ``(t, x, u, s) -> c``, mapped over the points.
    lo, hi : ndarray
        The rows' bounds at the parameter values.
    points : int
        How many points it is evaluated on at once.
    """

    fn: ca.Function
    lo: np.ndarray
    hi: np.ndarray
    points: int

    @classmethod
    def of(cls, tr: Transcription, i: int, pv: np.ndarray, points: int) -> PathCheck:
        """Phase ``i``'s check on ``points`` points (the Function cached).

        Parameters
        ----------
        tr : Transcription
            The transcription.
        i : int
            The phase.
        pv : ndarray
            The parameter values.
        points : int
            Number of points of a start's trajectory.
        """
        key = ("multistart_checker", i, points)
        cache = tr.grid_free.functions
        if key not in cache:
            cache[key] = tr.compiled[i].check.map(points)
        clo, chi = (np.array(v, dtype=float).ravel() for v in tr.compiled[i].bounds(pv)[6:8])
        return cls(cache[key], clo, chi, points)

    def violation(self, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                  static: np.ndarray) -> float:
        """The sum over the rows of their largest violation along a trajectory, each
        relative to ``max(1, |bound|)``; a row the trajectory makes non-finite counts 1.

        Parameters
        ----------
        t : ndarray
            The times, ``(points,)``.
        x, u : ndarray
            The states ``(points, nx)`` and controls ``(points, nu)``.
        static : ndarray
            The static vector ``[p; v; t0; T]``.
        """
        if self.lo.size == 0:
            return 0.0
        c = np.asarray(self.fn(t[None, :], x.T, u.T,
                               np.tile(static[:, None], (1, t.size))), dtype=float)
        lo, hi = self.lo[:, None], self.hi[:, None]
        with np.errstate(invalid="ignore"):
            below = (lo - c) / np.maximum(1.0, np.abs(np.where(np.isfinite(lo), lo, 0.0)))
            above = (c - hi) / np.maximum(1.0, np.abs(np.where(np.isfinite(hi), hi, 0.0)))
            rel = np.maximum(np.maximum(below, above), 0.0)
        rel[~np.isfinite(rel)] = 1.0
        return float(np.sum(np.max(rel, axis=1)))


def mapped_rates(tr: Transcription, i: int, points: int) -> ca.Function:
    """Phase ``i``'s dynamics ``(t, x, u, s) -> xdot`` mapped over ``points`` points (cached).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    i : int
        The phase.
    points : int
        Number of points evaluated at once.
    """
    key = ("multistart_rates", i, points)
    cache = tr.grid_free.functions
    if key not in cache:
        ode = tr.compiled[i].ode
        t, x = ca.MX.sym("t"), ca.MX.sym("x", ode.size1_in(1))
        u, s = ca.MX.sym("u", ode.size1_in(2)), ca.MX.sym("s", ode.size1_in(3))
        rate = ca.Function("rate", [t, x, u, s], [ode(t, x, u, s)[0]])
        cache[key] = rate.map(points)
    return cache[key]
