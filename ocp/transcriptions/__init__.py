"""How a problem becomes an NLP, and what a solve returns.

:mod:`~ocp.transcriptions.transcription` (:class:`~ocp.MultipleShooting`,
:class:`~ocp.Collocation`, :func:`~ocp.transcribe`, :func:`~ocp.continuation`), the
per-phase discretisations (:mod:`~ocp.transcriptions.discretization`,
:mod:`~ocp.transcriptions.shooting`, :mod:`~ocp.transcriptions.collocation`),
:mod:`~ocp.transcriptions.integrators`, :mod:`~ocp.transcriptions.mesh` (error estimate and
h-refinement), :mod:`~ocp.transcriptions.refinement` (refinement until converged, confirmed;
multiple shooting's by doubling), :mod:`~ocp.transcriptions.indicators` (where the
objective's error lies), :mod:`~ocp.transcriptions.nlp` (the parametric NLP, built once;
Ipopt), :mod:`~ocp.transcriptions.verify` and :mod:`~ocp.transcriptions.extrema` (path
constraints between the nodes, at their maxima along the interpolant),
:mod:`~ocp.transcriptions.gridview` (how a solution's grid is read),
:mod:`~ocp.transcriptions.blas` (CasADi's OpenBLAS under Ipopt on one thread),
:mod:`~ocp.transcriptions.solver_output` (CasADi's messages logged, not printed) and
:mod:`~ocp.transcriptions.solution` (:class:`~ocp.Solution`). Imports only
:mod:`ocp.definition`.
"""
