"""Compiled core of the exact event-driven hybrid simulator, in parts.

* :mod:`.const` -- codes, the output layout, tolerances;
* :mod:`.model` -- the mode data packed in one flat array; energy and ground work;
* :mod:`.linalg` -- matrix exponential, propagation, event-time refinement, Gramians;
* :mod:`.events` -- control regimes, the ground's mode logic, event functionals and search;
* :mod:`.rest` -- exact future ranges in the static mode (the rest proof);
* :mod:`.creep` -- the proof that a yielding foot creeps toward a limit depth forever;
* :mod:`.landing` -- the segment loop of one landing, its GIL-free entry points.

The Python-level entry points are in :mod:`softlanding._kernel`.
"""
