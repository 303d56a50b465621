"""The controls of singular and regular interior arcs, as laws the refinement can fly.

:class:`~ocp.structure.flows.ArcDynamics` asks :func:`free_arc_laws` for the controls of
the modes that neither sit at a bound nor hold a constraint:

* ``"singular"``: the singular control as a state feedback
  (:func:`ocp.structure.singular.singular_feedback`), one singular control at a time,
  the other controls at bounds;
* ``"interior"`` (a regular arc): the controls that make ``H_u = 0`` with the costate
  copy of the mode's run (:mod:`ocp.structure.costate_copies`); H must be quadratic in
  them (a control-affine problem with a quadratic running cost), so the law is explicit.

Either law is kept within the control's bounds by rows of the refinement NLP
(``law_bounds``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from .costate_copies import copy_of
from .singular import singular_feedback


def free_arc_laws(dyn: Any, others: dict[str, ca.SX]) -> dict[str, ca.SX]:
    """The singular or interior controls of ``dyn``'s modes (its ``law_bounds`` appended).

    Parameters
    ----------
    dyn : ArcDynamics
        Being built: ``problem``, ``modes`` and ``law_bounds``.
    others : dict of str to SX
        The other controls' values (bounds, boundary laws).

    Returns
    -------
    dict of str to SX
        Control name -> its law, an expression of the state and parameters.
    """
    pr, modes = dyn.problem, dyn.modes
    sing = [n for n, m in zip(pr.control_names, modes, strict=True) if m.kind == "singular"]
    inner = [n for n, m in zip(pr.control_names, modes, strict=True) if m.kind == "interior"]
    if not sing and not inner:
        return {}
    if sing and (len(sing) > 1 or inner or any(m.held for m in modes)):
        raise ValueError("a singular arc is refined alongside bang arcs of the other "
                         "controls only (one singular control at a time)")
    laws = {sing[0]: singular_feedback(pr, sing[0], others)} if sing else \
        _interior_laws(pr, modes, inner, others)
    for name, law in laws.items():
        if ca.depends_on(law, pr.x):  # (a constant law is no row: Ipopt needs slack)
            lo, hi = pr.control_limits[name]
            kind = modes[pr.control_names.index(name)].kind
            dyn.law_bounds.append((f"{name} within its bounds ({kind})", law, lo, hi))
    return laws


def _interior_laws(pr: Any, modes: tuple, names: list[str],
                   others: dict[str, ca.SX]) -> dict[str, ca.SX]:
    """``H_u = 0`` solved for the interior controls, with the costate copy of their run."""
    lay = copy_of(pr)
    runs = {modes[pr.control_names.index(n)].run for n in names}
    if lay is None or len(runs) != 1 or None in runs:
        raise ValueError("an interior mode needs a problem with costate copies "
                         "(ocp.structure.costate_copies.costates_as_states), one run per "
                         "interval")
    run = runs.pop()
    org = lay.origin
    lam = ca.SX.sym("lam", org.nx)  # H of the original problem in pr's symbols, copy as lam
    H = ca.substitute(ca.SX(org.lagrange) + ca.dot(lam, org.rhs),
                      ca.vertcat(org.x, org.u, org.p, lam),
                      ca.vertcat(pr.x[:lay.nx], pr.u, pr.p, pr.x[lay.rows(run)]))
    rest = [n for n in pr.control_names if n not in names]
    if rest:
        H = ca.substitute(H, ca.vertcat(*[pr.u[pr.control_names.index(n)] for n in rest]),
                          ca.vertcat(*[others[n] for n in rest]))
    uI = ca.vertcat(*[pr.u[pr.control_names.index(n)] for n in names])
    Hu = ca.gradient(H, uI)
    J = ca.jacobian(Hu, uI)
    if ca.depends_on(J, uI):
        raise ValueError(f"H is not quadratic in {names}: the interior control has no "
                         "explicit law (a control-affine problem with a quadratic running "
                         "cost has one)")
    e0 = ca.substitute(Hu, uI, ca.DM.zeros(uI.numel()))
    law = -e0 / J if uI.numel() == 1 else -ca.solve(J, e0)
    return {n: law[i] for i, n in enumerate(names)}


__all__ = ["free_arc_laws"]
