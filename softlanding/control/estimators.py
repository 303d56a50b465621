"""The loop's estimators: what a sample's measurements become before a controller uses them.

A :class:`Reading` is one sample as the controller receives it. The estimator makes it
(:meth:`MeasuredEstimator.reading`) and updates the ground estimate from it
(:meth:`MeasuredEstimator.update`, recursive least squares:
:class:`~softlanding.control.estimation.GroundEstimator`):

* :class:`MeasuredEstimator` regresses the measured foot position, velocity, acceleration and
  force as they come (a noisy ``v_f`` that reads the foot as stopped is clipped: the loop
  runs while the foot yields, as a contact sensor says);
* :class:`FilteredEstimator` regresses the force the controller applied (it commanded it;
  the plant applies it exactly) and the foot's position and velocity filtered with its
  measured acceleration (:mod:`softlanding.control.foot_filter`; the plans start from the
  filtered state too), each sample weighed by the filtered state's error in its force
  (:func:`~softlanding.control.estimation.filtered_weight`).

The compiled controller (:class:`~softlanding.control.compiled.CompiledController`) runs the
same estimate inside its compiled step (the filter's step included); it reads the
estimator's arrays and hands its estimate back when it falls back.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.commands import Command, Schedule, force_integrals
from softlanding.control.estimation import GroundEstimate, GroundEstimator, filtered_weight
from softlanding.control.foot_filter import PROVISIONAL, covariance, filter_step, new_filter
from softlanding.control.state_landing import ground_numbers
from softlanding.model.ground import Ground
from softlanding.model.robot import Robot


@dataclass
class Reading:
    """One sample as a controller receives it.

    Attributes
    ----------
    sample : int
        The samples taken so far (1 at the first).
    t : float
        The time of the measurement (since impact).
    h : float
        The sample's length (the period, or less where the plan had the foot stop).
    x : ndarray of 4
        The measured state (a filtered estimator filters its foot's entries in place).
    a_f : float
        The foot's measured acceleration.
    u : float
        The force the estimate regresses (measured; as applied with :class:`FilteredEstimator`).
    x_before : ndarray of 4
        The last sample's reading of the state (at the first: the impact's).
    applied : ForceSchedule or FeedbackSchedule
        The force over the sample (its time from the sample's start).
    acting : Command
        The command that acted over the sample.
    issued : list of Command
        Every command issued so far (the last ``delay`` still in flight).
    g, U1, U2 : float
        :class:`FilteredEstimator` only: the foot's continuous acceleration at the sample's
        end and the applied force's integrals over it
        (:func:`~softlanding.control.foot_filter.filter_step`'s inputs).
    """

    sample: int
    t: float
    h: float
    x: np.ndarray
    a_f: float
    u: float
    x_before: np.ndarray
    applied: Schedule
    acting: Command
    issued: list[Command]
    g: float = 0.0
    U1: float = 0.0
    U2: float = 0.0


class MeasuredEstimator:
    """The ground estimate from the measurements as they come.

    Parameters
    ----------
    robot : Robot
        The robot.
    model : Ground
        The prior ground (the first plan's).
    noise : float
        The sensor's noise (its standard deviation).
    enabled : bool
        Update the estimate (else the prior stays).
    stop : float
        The foot's speed below which it counts as stopped.

    Attributes
    ----------
    rls : GroundEstimator
        The recursive least squares.
    F : ndarray or None
        The foot filter's memory (:class:`FilteredEstimator` only).
    """

    name = "measured"
    F: np.ndarray | None = None

    def __init__(self, robot: Robot, model: Ground, noise: float, enabled: bool,
                 stop: float) -> None:
        self.robot, self.noise, self.enabled, self.stop = robot, noise, enabled, stop
        self.rls = GroundEstimator(robot, drag=True, prior=ground_numbers(model),
                                   noise_std=self.force_noise())

    def force_noise(self) -> float:
        """The standard deviation of one sample's ground force (the estimator's noise)."""
        return max(self.noise, 1e-6)

    def reading(self, r: Reading, u_end: float) -> Reading:
        """The sample's reading completed: a noisy ``v_f`` clipped at ``-stop``.

        Parameters
        ----------
        r : Reading
            As measured.
        u_end : float
            The force the sample ended under, as applied (unused here).
        """
        r.x[3] = min(r.x[3], -self.stop)
        return r

    def filter(self, r: Reading) -> None:
        """The reading's state filtered in place (nothing here).

        Parameters
        ----------
        r : Reading
            The sample.
        """

    def fits(self, sample: int) -> bool:
        """Whether sample number ``sample`` updates the estimate.

        Parameters
        ----------
        sample : int
            The samples taken so far.
        """
        return self.enabled

    def weight(self, r: Reading) -> float:
        """The sample's weight in the regression (1).

        Parameters
        ----------
        r : Reading
            The sample.
        """
        return 1.0

    def update(self, r: Reading) -> GroundEstimate | None:
        """The estimate after the sample (None: the sample does not fit: the estimate is
        off, the foot's measured ``v_f`` is not negative, or the filter is provisional).

        Parameters
        ----------
        r : Reading
            The sample (filtered).
        """
        if not (self.fits(r.sample) and r.x[3] < 0):
            return None
        return self.rls.update(r.x, r.a_f, r.u, self.weight(r))

    @property
    def estimate(self) -> GroundEstimate:
        """The current fit."""
        return self.rls.estimate


class FilteredEstimator(MeasuredEstimator):
    """The ground estimate from the applied force and the filtered foot state.

    Parameters
    ----------
    robot, model, noise, enabled, stop
        As :class:`MeasuredEstimator`'s.
    x0 : array of 4
        The impact state (the filter's start).
    """

    name = "filtered"

    def __init__(self, robot: Robot, model: Ground, noise: float, enabled: bool, stop: float,
                 x0: np.ndarray) -> None:
        super().__init__(robot, model, noise, enabled, stop)
        self.F = new_filter(x0)
        self.beta = bb.force_coefficients(robot.r_m)[0]
        # one force's variance from the acceleration's noise, and the filtered state's
        # error the estimator's noise allows for (both in units of the sensor's noise
        # variance)
        self.force_var = 1.0 / bb.force_coefficients(robot.r_m)[1] ** 2
        self.allowance = bb.FILTERED_REGRESSOR

    def force_noise(self) -> float:
        """The standard deviation of one sample's ground force (the estimator's noise)."""
        return bb.ground_force_noise(self.robot.r_m, self.noise, True)

    def reading(self, r: Reading, u_end: float) -> Reading:
        """The sample's reading completed: the force as applied, the foot's continuous
        acceleration and the force's integrals over the sample (the actuator's: inputs of
        the estimate, as the measurements are).

        Parameters
        ----------
        r : Reading
            As measured.
        u_end : float
            The force the sample ended under, as applied.
        """
        r.u, r.g = u_end, r.a_f - self.beta * u_end
        r.U1, r.U2 = force_integrals(r.applied, r.h)
        return r

    def filter(self, r: Reading) -> None:
        """The foot's filter step, in place: the reading's foot position and velocity become
        the filtered ones (``v_f`` clipped at ``-stop``, the plans start from a yielding
        foot).

        Parameters
        ----------
        r : Reading
            The sample.
        """
        assert self.F is not None
        filter_step(self.F, r.x, r.g, r.U1, r.U2, r.h, self.beta, self.noise)
        r.x[3] = min(r.x[3], -self.stop)

    def fits(self, sample: int) -> bool:
        """Whether sample number ``sample`` updates the estimate (the filter's first states
        are provisional: no fit from them).

        Parameters
        ----------
        sample : int
            The samples taken so far.
        """
        return self.enabled and sample > PROVISIONAL

    def weight(self, r: Reading) -> float:
        """The sample's weight (:func:`~softlanding.control.estimation.filtered_weight`).

        Parameters
        ----------
        r : Reading
            The sample (filtered).
        """
        assert self.F is not None
        e = self.rls.estimate
        return filtered_weight(r.x, self.rls.ground_force(r.a_f, r.u), (e.stiffness, e.c_d),
                               covariance(self.F), self.force_var, self.allowance)


def make_estimator(kind: str, robot: Robot, model: Ground, noise: float, enabled: bool,
                   stop: float, x0: np.ndarray) -> MeasuredEstimator:
    """The estimator ``kind`` (``"measured"`` or ``"filtered"``) for a sensor of noise
    ``noise``; exact measurements need no filter (``"measured"`` then).

    Parameters
    ----------
    kind : str
        ``"measured"`` or ``"filtered"``.
    robot, model, noise, enabled, stop
        As :class:`MeasuredEstimator`'s.
    x0 : array of 4
        The impact state.
    """
    if kind == "filtered" and noise > 0:
        return FilteredEstimator(robot, model, noise, enabled, stop, x0)
    return MeasuredEstimator(robot, model, noise, enabled, stop)


__all__ = ["FilteredEstimator", "MeasuredEstimator", "Reading", "make_estimator"]
