"""Interior arcs made refinable: the singular arcs among them flown as a state feedback.

Structure detection (:mod:`ocp.structure.arcs`) calls ``"interior"`` every arc on which a
control is strictly inside its bounds and no constraint holds it. Where that control
enters H linearly and its switching function has an order
(:func:`ocp.structure.singular.singular_algebra`), such an arc is a *singular* arc, whose
control is the singular feedback of the switching function's derivatives
(:func:`~ocp.structure.singular.singular_feedback`, mode ``"singular"`` of
:class:`~ocp.structure.flows.ArcDynamics`). :func:`refinable_arcs` rewrites a structure so,
and :func:`~ocp.structure.switching.refine_switching` and
:func:`~ocp.structure.phase_refinement.refine_phases` call it on every structure they are
given, so a bang-singular optimum is refined by the default route: the durations of all
arcs are the unknowns, as for a bang-bang structure. No junction condition is imposed:
every member of the family (durations, singular feedback on the singular arcs, kept
within the control's bounds) is admissible and the optimum is one of them, so minimising
over the durations finds its junctions; the certificate then checks that the refined arcs
are extremal.

An interior arc of a control in which H is strictly convex (a regular arc, ``H_u = 0``)
is flown with ``u = argmin H`` and the costate carried as extra states
(:mod:`ocp.structure.costate_copies`): :func:`refinable_arcs` gives its intervals the mode
``"interior"`` with the index of their run. Any other interior arc is not refinable, and
:func:`refinable_arcs` says why.
"""

from __future__ import annotations

import casadi as ca

from ..definition.problem import OptimalControlProblem
from .arcs import Arc, ArcStructure, SwitchingStructure
from .flows import Mode
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


def refinable_arcs(pr: OptimalControlProblem, structure: ArcStructure) -> ArcStructure:
    """``structure`` with its interior arcs made singular or regular interior refinement modes.

    An interior arc of a control that enters H linearly with a singular order becomes a
    singular arc (kind ``"singular"``); one of a control in which H is strictly convex
    stays ``"interior"`` and its intervals get the mode ``Mode("interior", run=i)``, ``i``
    numbering the runs of interior intervals in time order (each has its costate copy,
    :mod:`ocp.structure.costate_copies`).

    Parameters
    ----------
    pr : OptimalControlProblem
        The problem (or phase) the structure was detected on.
    structure : ArcStructure

    Returns
    -------
    ArcStructure
        ``structure`` itself when it has no interior arc; else a copy with refinement
        intervals (``refinable`` stays False while it has regular interior arcs).

    Raises
    ------
    ValueError
        Naming the arcs and why an interior arc is neither (no singular order; H not
        strictly convex in the control).
    """
    if structure.refinable:
        return structure
    per, regular = [], set()
    for s in structure.per_control:
        kinds = [a.kind for a in s.arcs]
        if "interior" in kinds:
            why = not_singular(pr, s.control)
            if why and not is_regular(pr, s.control):
                raise ValueError(f"not refinable: arcs {kinds} of {s.control!r}; its interior "
                                 f"arc is neither singular ({why}) nor regular (H strictly "
                                 "convex in it)")
            if why:
                regular.add(s.control)
        per.append(SwitchingStructure(s.control, [
            Arc("singular" if a.kind == "interior" else a.kind, a.start, a.end, a.active,
                a.constraint, a.side, a.faces) for a in s.arcs], s.lower, s.upper))
    out = ArcStructure.from_controls(per)
    if not regular:
        return out
    run, prev = -1, False
    for iv in out.intervals:  # a run: consecutive intervals with a regular interior control
        inner = [c in regular and m.kind == "singular" for c, m in zip(out.controls, iv.modes,
                                                                      strict=True)]
        run += any(inner) and not prev
        prev = any(inner)
        iv.modes = tuple(Mode("interior", run=run) if f else m
                         for f, m in zip(inner, iv.modes, strict=True))
    per = [p if p.control not in regular else structure.per_control[j]
           for j, p in enumerate(per)]
    return ArcStructure(out.controls, tuple(per), out.intervals)


def is_regular(pr: OptimalControlProblem, control: str) -> bool:
    """H strictly convex in ``control`` where it is regular: ``H_uu`` (of the running cost,
    the dynamics being affine in the control) a positive constant.

    Parameters
    ----------
    pr : OptimalControlProblem
    control : str
    """
    j = pr.control_names.index(control)
    Huu = ca.hessian(ca.SX(pr.lagrange), pr.u[j])[0]
    return bool(Huu.is_constant() and float(ca.DM(Huu)) > 0.0 and not ca.depends_on(
        ca.jacobian(pr.rhs, pr.u[j]), pr.u[j]))


__all__ = ["is_regular", "not_singular", "refinable_arcs"]
