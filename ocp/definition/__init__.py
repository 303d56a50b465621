"""What a problem is: phases, their symbols, bounds, constraints, costs and times.

:mod:`~ocp.definition.problem` (one phase; its symbols in
:mod:`~ocp.definition.problem_symbols`), :mod:`~ocp.definition.shared` (parameters and
variables shared by the phases), :mod:`~ocp.definition.references` (scaling references),
:mod:`~ocp.definition.multiphase` (phases in sequence, links, shared parameters),
:mod:`~ocp.definition.symbols` (helpers on CasADi symbols and bounds),
:mod:`~ocp.definition.normal_form` (one form for bounds however they are written),
:mod:`~ocp.definition.compiled` (a phase's expressions as CasADi Functions),
:mod:`~ocp.definition.guess` (default guesses), :mod:`~ocp.definition.sizes` and
:mod:`~ocp.definition.scaling` (the sizes of the unknowns and the NLP's scaling),
:mod:`~ocp.definition.trajectory` (sampled trajectories), :mod:`~ocp.definition.errors`.
Imports nothing from the other sub-packages.
"""
