"""Bang-singular optima refined like bang-bang ones: junction times to machine precision.

:func:`singular_structure` reads the arc structure of a transcription and calls every
interior arc of a control that enters H linearly *singular* (mode ``"singular"``, whose
control is the singular feedback of :func:`ocp.structure.singular.singular_feedback`,
from the switching function's derivatives); :func:`refine_singular` then refines the
durations of all arcs as :func:`~ocp.structure.switching.refine_switching` refines a
bang-bang structure. No junction condition is imposed: every member of the family
(durations, singular feedback on the singular arcs, kept within the control's bounds)
is admissible and the optimum is one of them, so minimising over the durations finds
its junctions; the certificate then checks that the refined arcs are extremal.
"""

from __future__ import annotations

from typing import Any

from .arcs import Arc, ArcStructure, SolutionLike, SwitchingStructure, detect_structure, transcribed
from .singular import singular_algebra
from .switching import RefinedSwitching, refine_switching


def singular_structure(sol: SolutionLike, structure: ArcStructure | None = None) -> ArcStructure:
    """The structure of ``sol`` with its interior arcs made singular arcs.

    Parameters
    ----------
    sol : Solution
        A transcribed single-phase solution.
    structure : ArcStructure, optional
        Default: :func:`~ocp.structure.arcs.detect_structure` of ``sol``.

    Returns
    -------
    ArcStructure
        Refinable: its interior arcs have kind ``"singular"``.

    Raises
    ------
    ValueError
        When a control with an interior arc enters H nonlinearly (a regular interior
        arc, not singular) or has no singular order.
    """
    tsol = transcribed(sol)
    st = detect_structure(tsol) if structure is None else structure
    per = []
    for s in st.per_control:
        if any(a.kind == "interior" for a in s.arcs):
            alg = singular_algebra(tsol.problem, s.control)
            if alg.order is None:
                raise ValueError(f"interior arc of {s.control!r} is not singular: {alg.reason}")
        arcs = [Arc("singular" if a.kind == "interior" else a.kind, a.start, a.end, a.active,
                    a.constraint, a.side, a.faces) for a in s.arcs]
        per.append(SwitchingStructure(s.control, arcs, s.lower, s.upper))
    return ArcStructure.from_controls(per)


def refine_singular(sol: SolutionLike, structure: ArcStructure | None = None,
                    **options: Any) -> RefinedSwitching:
    """Refine a structure of bang, boundary and singular arcs.

    Parameters
    ----------
    sol : Solution
        A transcribed single-phase solution.
    structure : ArcStructure, optional
        Default: :func:`singular_structure` of ``sol``.
    **options
        Passed to :func:`~ocp.structure.switching.refine_switching`.

    Returns
    -------
    RefinedSwitching
        Its ``kinds`` say ``"singular"`` on the singular arcs.
    """
    st = singular_structure(sol) if structure is None else structure
    return refine_switching(sol, st, **options)


__all__ = ["refine_singular", "singular_structure"]
