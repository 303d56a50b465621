"""What a solution's controls do, and its switching times to machine precision.

:mod:`~ocp.structure.arcs` (bang-bang, boundary and vertex arcs:
:func:`~ocp.detect_structure`; their types in :mod:`~ocp.structure.arc_structure`, where a
solution sits in :mod:`~ocp.structure.activity`), :mod:`~ocp.structure.constraint_kinds`
(state, mixed or control-only path constraints), :mod:`~ocp.structure.control_set` (the
polytope of coupled controls), :mod:`~ocp.structure.flows` (the dynamics on each arc),
:mod:`~ocp.structure.refinement` (the NLP over arc durations; its intervals in
:mod:`~ocp.structure.intervals`, its reports in :mod:`~ocp.structure.switching_report`),
:mod:`~ocp.structure.active_set_resolve` and :mod:`~ocp.structure.active_set_newton` (Newton
re-solves on a square active set), :mod:`~ocp.structure.variables` (decision variables
refined as constant states), :mod:`~ocp.structure.switching` (:func:`~ocp.refine_switching`,
:func:`~ocp.refine_structure`) and :mod:`~ocp.structure.phase_refinement`
(:func:`~ocp.refine_phases`). Imports only :mod:`ocp.definition` and
:mod:`ocp.transcriptions`.
"""
