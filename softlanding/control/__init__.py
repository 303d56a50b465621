"""Closed-loop control of the landing on ground the robot does not know.

The loop's objects (:mod:`~softlanding.control.loop`, do-mpc's and python-control's shape):
:class:`SteppingPlant` (the exact simulator advanced sample by sample, the actuator
saturating at the force limit), :class:`Sensor` (noisy, delayed measurements), the
estimators (:class:`MeasuredEstimator`, :class:`FilteredEstimator`: recursive least squares
of the ground law, :class:`GroundEstimator`, from the foot's measured acceleration), the
controllers behind one protocol (:class:`LandingController`: prepare before the impact, one
step per sample from a :class:`Reading` to a :class:`Command`): :class:`CompiledController`
(the compiled real-time controller, :mod:`~softlanding.control.bangbang` with the creep law)
and :class:`ReplanController` (the re-planning MPC), and :func:`run_loop`, which runs any of
them. :func:`mpc_landing` composes them for one landing. :func:`robust_landing` and
:func:`two_stage_landing`: one plan for a set of grounds (open-loop, or shared until the
ground shows itself); and the state-started landing OCP they share.
"""

from pathlib import Path

import lazy_loader as _lazy

from softlanding.simulation.kernel_cache import KERNEL, drop_stale_cache

# before any compiled controller module is loaded: numba checks only a function's own file,
# and the controller's compiled functions inline the kernel's and the model's
drop_stale_cache(Path(__file__).parent, (KERNEL, KERNEL.parents[1] / "model"))

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
