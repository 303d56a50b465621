"""Closed-loop control of the landing on ground the robot does not know.

:class:`SteppingPlant` (the exact simulator advanced sample by sample),
:class:`GroundEstimator` (recursive least squares of the ground law from the foot's
measured acceleration), :func:`mpc_landing` (model-predictive control re-planning from the
measured state with the current estimate, or the compiled bang-bang controller of
:mod:`~softlanding.control.bangbang`; :class:`Sensor`: noisy, delayed measurements),
:func:`robust_landing` and :func:`two_stage_landing` (one plan for a set of grounds:
open-loop, or shared until the ground shows itself) and the state-started landing OCP they share.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
