"""One row of the per-arc table of a PMP certificate, and how a row is judged.

Each arc of the candidate (bang, control boundary, interior, singular, state-constrained
boundary) gets an :class:`ArcCheck`: the residuals of the conditions of its type, the
tolerance each is held to and the numerical error it carries. A condition *holds* when
its residual is within its tolerance, is *uncertain* when the residual is within
:data:`~ocp.certificate.checks.ERROR_MARGIN` times its own error (or the condition is
degenerate), and *fails* otherwise. The arc takes the worst of its conditions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .checks import CERTIFIED, ERROR_MARGIN

HOLDS, UNCERTAIN, FAILS = "holds", "uncertain", "fails"
_RANK = {HOLDS: 0, UNCERTAIN: 1, FAILS: 2}
ARC_KINDS = ("bang", "control boundary", "interior", "singular", "state boundary")


@dataclass
class ArcCheck:
    """The conditions of the minimum principle on one arc.

    Attributes
    ----------
    kind : str
        ``"bang"``, ``"control boundary"`` (a mixed or control-only constraint held),
        ``"interior"`` (H strictly convex in the control, ``H_u = 0``), ``"singular"``
        (H linear in the control, ``sigma = 0``) or ``"state boundary"`` (a state
        constraint held).
    control : str
        The control (or, on a state boundary arc, the constraint's name).
    start, end : float
        The arc's span (junctions as detected, or refined).
    status : str
        ``"holds"``, ``"uncertain"`` or ``"fails"``: the worst of its conditions.
    residuals : dict of str to float
        Per condition, its measured residual (relative to the named scale).
    tolerances : dict of str to float
        Per condition, what its residual is allowed.
    errors : dict of str to float
        Per condition, the certificate's own numerical error in it.
    order : int or None
        Singular arc: the order ``k``; state boundary arc: the constraint's order ``p``.
    side : str or None
        State boundary arc: the limit held (``"lower"``/``"upper"``).
    notes : list of str
        Why a condition is uncertain or fails, and what was not tested.
    """

    kind: str
    control: str
    start: float
    end: float
    status: str = HOLDS
    residuals: dict[str, float] = field(default_factory=dict)
    tolerances: dict[str, float] = field(default_factory=dict)
    errors: dict[str, float] = field(default_factory=dict)
    order: int | None = None
    side: str | None = None
    notes: list[str] = field(default_factory=list)

    def where(self) -> str:
        """``"singular arc of u on [1, 2]"``: the arc, for a reason."""
        return f"{self.kind} arc of {self.control} on [{self.start:.6g}, {self.end:.6g}]"

    def judge(self, name: str, value: float, tol: float, err: float = 0.0,
              text: str = "") -> None:
        """Record condition ``name``: its residual ``value``, allowed ``tol``, error ``err``.

        Parameters
        ----------
        name : str
        value, tol, err : float
        text : str
            What the condition says (for a note when it does not hold).
        """
        self.residuals[name], self.tolerances[name], self.errors[name] = value, tol, err
        if not math.isfinite(value):
            self.mark(UNCERTAIN, f"{name}: could not be evaluated ({text})")
        elif value > tol:
            within = value <= ERROR_MARGIN * err
            self.mark(UNCERTAIN if within else FAILS,
                      f"{name} {value:.2e} > {tol:.1e} ({text})" + (
                          f", within {ERROR_MARGIN:g}x its numerical error {err:.1e}"
                          if within else ""))

    def mark(self, status: str, note: str) -> None:
        """Lower the arc's status to ``status`` (never raise it) and note why.

        Parameters
        ----------
        status : str
            ``"holds"``, ``"uncertain"`` or ``"fails"``.
        note : str
            Why.
        """
        if _RANK[status] > _RANK[self.status]:
            self.status = status
        self.notes.append(note)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (non-finite numbers become None)."""
        def f(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        return {"kind": self.kind, "control": self.control, "start": float(self.start),
                "end": float(self.end), "status": self.status,
                "residuals": {k: f(v) for k, v in self.residuals.items()},
                "tolerances": {k: f(v) for k, v in self.tolerances.items()},
                "errors": {k: f(v) for k, v in self.errors.items()},
                "order": self.order, "notes": list(self.notes)}


def worst(arcs: list[ArcCheck]) -> str:
    """The worst status of ``arcs`` (``"holds"`` when empty).

    Parameters
    ----------
    arcs : list of ArcCheck
    """
    return max((a.status for a in arcs), key=_RANK.__getitem__, default=HOLDS)


def certified_verdict(arcs: list[ArcCheck]) -> str:
    """The "certified" verdict naming the arc types that were certified.

    ``"bang-bang certified"`` when every arc is a bang (or control boundary) arc, the
    verdict of a bang-bang extremal as before; otherwise ``"certified (...)"`` with the
    kinds in order, singular arcs with their orders and state boundary arcs with their
    constraints' orders: ``"certified (bang, singular order 1)"``.

    Parameters
    ----------
    arcs : list of ArcCheck
    """
    if all(a.kind in ("bang", "control boundary") for a in arcs):
        return CERTIFIED
    names: list[str] = []
    for kind in ARC_KINDS:
        these = [a for a in arcs if a.kind == kind]
        if not these:
            continue
        orders = sorted({a.order for a in these if a.order is not None})
        if kind == "singular":
            names.append("singular order " + "/".join(map(str, orders)))
        elif kind == "state boundary":
            names.append("state boundary order " + "/".join(map(str, orders)))
        else:
            names.append(kind)
    return f"certified ({', '.join(names)})"


__all__ = ["ARC_KINDS", "ArcCheck", "FAILS", "HOLDS", "UNCERTAIN", "certified_verdict", "worst"]
