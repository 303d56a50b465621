"""Optimal landings: one pipeline, one module per variant.

* :mod:`.landing` -- the paper's single-phase landing (:func:`solve_landing`,
  :func:`sweep_landing`, :class:`BangBangLanding`), problem in :mod:`.landing_problem`, its
  open-loop schedules in :mod:`.landing_schedule`;
* :mod:`.two_phase` -- the body's arrest optimised too (:func:`solve_two_phase`,
  :func:`sweep_two_phase`, :func:`two_step_check`), problem in :mod:`.two_phase_problem`;
* :mod:`.leg_extension` -- the touchdown leg state optimised (:func:`solve_leg_extension`),
  problem in :mod:`.leg_extension_problem`;
* :mod:`.hopping` -- the minimum-energy hop cycle (:func:`solve_hop`), problem in
  :mod:`.hopping_problem`, its record and replay checks in :mod:`.hop_cycle`, its exact
  arcs in :mod:`.hop_arcs`, the impedance leg in :mod:`.hop_impedance`;
* :mod:`.pipeline` -- what every variant shares: :class:`PhasedVariant` (the hooks a
  variant fills), :func:`solve_phased`, :func:`continuation` (the single-phase landing and
  the MPC's state-started solve run on it too, with one-phase refinement hooks);
* :mod:`.result` -- :class:`PhasedLanding`, the result every phased variant extends;
* :mod:`.stance_phases` -- the ground modes as phases of an ``ocp.MultiPhaseProblem``;
* :mod:`.smooth` -- a smooth optimum (a continuous force, interior arcs): converged on a
  refined collocation mesh, certified arc by arc;
* :mod:`.phase_solve`, :mod:`.phase_schedule`, :mod:`.verification` -- transcribe, refine,
  re-solve; refined arcs to a simulator controller; the checks every result states.

* :mod:`.variants` -- what a variant declares (:class:`Variant`, :class:`Option`), the
  result protocol (:class:`VariantResult`), where variants are found (built in,
  ``module:attribute``, the entry-point group ``softlanding.variants``), and
  :func:`sweep_variant`; :mod:`.builtin_variants` declares the built-in ones.

A new variant is one module: its problem, a :class:`PhasedVariant` subclass, a
:class:`PhasedLanding` subclass and a :class:`Variant` (see :mod:`.min_peak_force`, the
least peak force within a depth budget, and ``docs/examples/min_energy.py``, the least
actuator energy, a smooth optimum).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
