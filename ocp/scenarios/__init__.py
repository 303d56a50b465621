"""Scenario problems: copies of a problem with other parameter values sharing one control.

:mod:`~ocp.scenarios.scenario` (:class:`~ocp.ScenarioProblem`, open-loop robust or a
two-stage tree; worst-case or expected objective), :mod:`~ocp.scenarios.stack` (the stacked
multi-phase problem) and :mod:`~ocp.scenarios.result` (:class:`~ocp.ScenarioResult`: the
solution split and checked by scenario).
"""
