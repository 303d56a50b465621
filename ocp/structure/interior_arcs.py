"""Interior arcs made refinable: the singular arcs among them flown as a state feedback.

Structure detection (:mod:`ocp.structure.arcs`) calls ``"interior"`` every arc on which a
control is strictly inside its bounds and no constraint holds it. Where that control
enters H linearly and its switching function has an order
(:func:`ocp.structure.singular.singular_algebra`), such an arc is a *singular* arc, whose
control is the singular feedback of the switching function's derivatives
(:func:`~ocp.structure.singular.singular_feedback`, mode ``"singular"`` of
:class:`~ocp.structure.flows.ArcDynamics`). :func:`singular_arcs` rewrites a structure so,
and :func:`~ocp.structure.switching.refine_switching` and
:func:`~ocp.structure.phase_refinement.refine_phases` call it on every structure they are
given, so a bang-singular optimum is refined by the default route: the durations of all
arcs are the unknowns, as for a bang-bang structure. No junction condition is imposed:
every member of the family (durations, singular feedback on the singular arcs, kept
within the control's bounds) is admissible and the optimum is one of them, so minimising
over the durations finds its junctions; the certificate then checks that the refined arcs
are extremal.

An interior arc of a control that enters H nonlinearly (a regular arc, ``H_u = 0``) or has
no singular order is not refinable: :func:`singular_arcs` says which and why.
"""

from __future__ import annotations

from ..definition.problem import OptimalControlProblem
from .arcs import Arc, ArcStructure, SwitchingStructure
from .singular import singular_algebra


def not_singular(pr: OptimalControlProblem, control: str) -> str:
    """Why an interior arc of ``control`` is not a singular arc ("" when it may be one).

    Parameters
    ----------
    pr : OptimalControlProblem
    control : str
    """
    try:
        alg = singular_algebra(pr, control)
    except ValueError as err:  # H not linear in the control: a regular interior arc
        return str(err)
    return "" if alg.order is not None else alg.reason


def singular_arcs(pr: OptimalControlProblem, structure: ArcStructure) -> ArcStructure:
    """``structure`` with its interior arcs made singular arcs.

    Parameters
    ----------
    pr : OptimalControlProblem
        The problem (or phase) the structure was detected on.
    structure : ArcStructure

    Returns
    -------
    ArcStructure
        ``structure`` itself when it has no interior arc; else a refinable copy whose
        interior arcs have kind ``"singular"``.

    Raises
    ------
    ValueError
        Naming the arcs and why an interior arc is not singular (a control that enters H
        nonlinearly: a regular arc; or one with no singular order).
    """
    if structure.refinable:
        return structure
    per = []
    for s in structure.per_control:
        if any(a.kind == "interior" for a in s.arcs):
            why = not_singular(pr, s.control)
            if why:
                kinds = {c.control: c.kinds for c in structure.per_control}
                raise ValueError(f"not refinable: arcs {kinds}; the interior arc of "
                                 f"{s.control!r} is not a singular arc ({why})")
        arcs = [Arc("singular" if a.kind == "interior" else a.kind, a.start, a.end, a.active,
                    a.constraint, a.side, a.faces) for a in s.arcs]
        per.append(SwitchingStructure(s.control, arcs, s.lower, s.upper))
    return ArcStructure.from_controls(per)


__all__ = ["not_singular", "singular_arcs"]
