"""The compiled landing controller (:mod:`softlanding.control.bangbang`) and its foot filter
(:mod:`softlanding.control.foot_filter`) exported as C.

Modules: :mod:`.layout` (the numbers the C takes from the Python modules: the layout of
``P``, ``M`` and the filter's ``F``, statuses, tolerances, the filter's constants,
Dormand-Prince coefficients), :mod:`.writer` (the hand-written templates
``controller.c.in``, ``controller.h.in``, ``README.txt.in`` of this folder filled in and
written), :mod:`.binding` (the export compiled with the system's C compiler and called
through :mod:`ctypes`), :mod:`.samples` (the recorded calls of random landings),
:mod:`.reference` (the Python side's plan force and its integrals), :mod:`.filter_check`
(the C filter against the Python one on noisy filtered landings) and :mod:`.check` (the C
against the Python controller, and the filter's check).
"""
