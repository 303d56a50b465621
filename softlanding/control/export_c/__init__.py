"""The compiled landing controller (:mod:`softlanding.control.bangbang`) exported as C.

Modules: :mod:`.layout` (the numbers the C takes from the Python modules: the layout of
``P`` and ``M``, statuses, tolerances, Dormand-Prince coefficients), :mod:`.writer` (the
hand-written templates ``controller.c.in``, ``controller.h.in``, ``README.txt.in`` of this
folder filled in and written), :mod:`.binding` (the export compiled with the system's C
compiler and called through :mod:`ctypes`), :mod:`.samples` (the recorded calls of random
landings) and :mod:`.check` (the C against the Python controller on them).
"""
