"""Pontryagin's conditions: proves, refutes, or says inconclusive and why.

In layers, each importing only those before it: :mod:`~ocp.certificate.costates` (from the
multipliers, or integrated backward along refined arcs; H and the switching functions),
:mod:`~ocp.certificate.chattering` (switches accumulating at a point),
:mod:`~ocp.certificate.checks` (the checks on one set of samples, tolerances, verdicts),
:mod:`~ocp.certificate.result` (:class:`~ocp.PMPCertificate`, its assembly and refusal),
:mod:`~ocp.certificate.from_refined` and :mod:`~ocp.certificate.from_transcription`
(certificates of a refined solution, of a transcription alone),
:mod:`~ocp.certificate.phases` (phase by phase) and :mod:`~ocp.certificate.certify`
(:func:`~ocp.certify`, the entry point).
"""
