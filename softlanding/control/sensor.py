"""What the landing controller measures, and the body's arrest from its measurement once the
foot has stopped.

:class:`Sensor` adds Gaussian noise to the measured foot position, velocity, acceleration and
force, and carries the delay (samples) before a control acts; its :meth:`Sensor.arrest` is
the force from a stopped foot's measured state on (the constant force that stops the body in
the stroke left, less a reserve with noise, then a damped hold).
"""

from __future__ import annotations

import math

import numpy as np

from softlanding.control.commands import saturated
from softlanding.control.options import check_noise
from softlanding.errors import ParameterError, check_count
from softlanding.model.controllers import FeedbackSchedule, ForceSchedule
from softlanding.model.dynamics import VB, robot_rhs
from softlanding.optimal.landing import arrest_schedule


class Sensor:
    """What the controller measures: the state, the foot's acceleration and the force, with
    Gaussian noise of one standard deviation ``noise`` on the foot's position, velocity,
    acceleration and the force; and the delay (samples) before its control acts.

    Parameters
    ----------
    noise : float
        Standard deviation: 0 (exact), or within
        [:data:`~softlanding.control.options.MIN_NOISE`,
        :data:`~softlanding.control.options.MAX_NOISE`].
    delay : int
        Samples (>= 0).
    seed : int
        Random seed.
    """

    def __init__(self, noise: float = 0.0, delay: int = 0, seed: int = 0) -> None:
        self.noise = check_noise("noise", noise)
        if isinstance(delay, bool) or not isinstance(delay, int | np.integer):
            raise ParameterError("delay", f"must be a whole number of samples, got {delay!r}")
        self.delay = check_count("delay", int(delay), 0, 1000)
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ParameterError("seed", f"must be a whole number >= 0, got {seed!r}")
        self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)

    def measure(self, x: np.ndarray, a_f: float = 0.0,
                u: float = 0.0) -> tuple[np.ndarray, float, float]:
        """The measured state, foot acceleration and force.

        Parameters
        ----------
        x : array of 4
            The true state.
        a_f, u : float
            The true foot acceleration and force.
        """
        if self.noise == 0.0:
            return np.array(x, float), float(a_f), float(u)
        e = self.rng.normal(0.0, self.noise, 4)
        m = np.array(x, float)
        m[2] += e[0]
        m[3] += e[1]
        return m, float(a_f + e[2]), float(u + e[3])

    def arrest(self, x: np.ndarray, r_m: float, stroke_max: float = math.inf,
               u_max: float | None = None) -> ForceSchedule | FeedbackSchedule:
        """The body's arrest from the measured state of a stopped foot: exact measurements,
        the constant force that stops it in the stroke left, then its weight
        (:func:`~softlanding.optimal.landing.arrest_schedule`). Noisy ones: the stroke left
        less a reserve of ``ARREST_RESERVE`` standard deviations of the foot's position (a
        measured stroke may be long), then the weight with a damped hold of the stroke
        where the body stopped (the open-loop weight alone would let a velocity the noise
        left drift the body forever). A body that no longer descends (the end of a creep)
        coasts up at no force to its top, if that is within ``stroke_max``, and gets that
        damped hold there, with exact measurements too. A body so slow that braking over
        the whole stroke would outlast :data:`ARREST_TIME` brakes within it. The constant
        forces are saturated at ``u_max`` (the hold, affine in the state, is saturated by
        the plant that applies it).

        Parameters
        ----------
        x : ndarray
            The measured state ``[x_b, v_b, x_f, v_f]`` (the foot stopped).
        r_m : float
            The robot's mass ratio.
        stroke_max : float
            The stroke's limit (a noisy arrest lets a rising body coast up to its top, at
            no force, where that is within it).
        u_max : float, optional
            The force limit (None: none).

        Returns
        -------
        ForceSchedule or FeedbackSchedule
            The arrest's force from the sample on.
        """
        stroke = float(x[0] - x[2])
        # a body so slow that braking over the whole stroke outlasts ARREST_TIME brakes over
        # what it covers in that time (its force above the weight m_b |v_b| / ARREST_TIME:
        # 3e-4 of it at v_b = -0.02)
        brake = 0.5 * abs(float(x[1])) * ARREST_TIME
        if self.noise == 0.0 and x[1] < 0:
            x_e = np.array(x, float)
            x_e[0] = min(x_e[0], x_e[2] + brake)
            return saturated(arrest_schedule(x_e, r_m), u_max)
        reserve = min(ARREST_RESERVE * self.noise, 0.5 * stroke)
        x_r = np.array(x, float)
        x_r[0] -= reserve  # the arrest sees the stroke less the reserve
        x_r[0] = min(x_r[0], x_r[2] + brake) if x[1] < 0 else x_r[0]
        tail = arrest_schedule(x_r, r_m)
        assert isinstance(tail, ForceSchedule)
        w = r_m / (1 + r_m)
        # where the arrest stops the body (the reserve left), or where it is
        end = stroke - (x_r[0] - x_r[2]) if x[1] < 0 and stroke - reserve > 0 else stroke
        times, forces = tail.times, tail.values[:-1]
        if x[1] > 0:
            # a body still rising (a re-planned creep's pull may leave it so): no force until
            # its weight alone stops it, then the hold at that stroke (held where it is, the
            # damped hold would brake it by pushing the foot into ground at its capacity)
            a = float(robot_rhs(np.asarray(x, float), 0.0, 0.0, r_m)[VB])
            if a < 0 and stroke - 0.5 * x[1] ** 2 / a < stroke_max:
                times, forces, end = (-x[1] / a,), (0.0,), stroke - 0.5 * x[1] ** 2 / a
        hold = (-HOLD_GAINS[0], -HOLD_GAINS[1], HOLD_GAINS[0], HOLD_GAINS[1],
                w + HOLD_GAINS[0] * end)
        rows = [(0.0, 0.0, 0.0, 0.0, v) for v in forces] + [hold]
        return saturated(FeedbackSchedule(times, tuple(rows)), u_max)


#: Standard deviations of the foot's measured position kept as a stroke reserve by a noisy
#: arrest.
ARREST_RESERVE = 3.0
#: The longest braking of the arrest (paper time units, 26 s on the paper's rig): a tenth of
#: the simulation's horizon, within which its rest is proven. A body slower than
#: ``2 stroke / ARREST_TIME`` (0.04 over the paper's whole stroke) brakes over a part of it.
ARREST_TIME = 1000.0
#: ``k_p, k_d`` of the damped hold of the stroke after a noisy arrest (per unit of the
#: paper's force; critically damped for the body's mass ``r_m/(1+r_m)`` about 5/6).
HOLD_GAINS = (1.0, 2.0)


__all__ = ["ARREST_RESERVE", "ARREST_TIME", "HOLD_GAINS", "Sensor"]
