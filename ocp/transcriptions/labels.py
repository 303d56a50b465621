"""A name for every row of a transcription's constraint vector ``g``, for messages."""

from __future__ import annotations

from typing import Any

import casadi as ca

DEFECTS = ("continuity", "collocation")


def row_labels(tr: Any) -> list[str]:
    """One label per row of ``g``: ``"terminal 'x(tf) = 1'"``, ``"dynamics of 'v' at
    row 12"``, ``"path 'speed' at row 3"`` (a phase's name first when there are several).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    """
    out = [""] * tr.n_g
    multi = len(tr.layouts) > 1
    for ph, lay in zip(tr.multiphase.phases, tr.layouts, strict=True):
        pre = f"{ph.name}: " if multi else ""
        path_names = [c.name for c in ph.path for _ in range(c.expr.numel())]
        for kind, sl in lay.blocks.items():
            for j, row in enumerate(range(sl.start, sl.stop)):
                if kind in DEFECTS:
                    what = f"dynamics of {ph.state_names[j % ph.nx]!r} at row {row}"
                elif kind.startswith("path") and path_names:
                    what = f"path {path_names[j % len(path_names)]!r} at row {row}"
                else:
                    what = f"{kind} at row {row}"
                out[row] = pre + what
    for i, kind, cs in tr.groups:
        sl = (tr.link_blocks if i == -1 else tr.layouts[i].blocks)[kind]
        pre = f"{tr.multiphase.phases[i].name}: " if multi and i >= 0 else ""
        rows = [f"{pre}{kind} {end_row(c, j)!r}" for c in cs for j in range(c.expr.numel())]
        out[sl] = rows
    return out


def end_row(c: Any, j: int) -> str:
    """``"x(tf) = 1"`` or ``"0 <= e <= 4e+05"``: row ``j`` of an end-point constraint.

    Parameters
    ----------
    c : Constraint
        The constraint (in end-point symbols).
    j : int
        Its row.
    """
    e = str(c.expr[j]) if c.expr.numel() > 1 else str(c.expr)
    lo, hi = (_num(b[j]) for b in (c.lower, c.upper))
    if lo is not None and lo == hi:
        return f"{e} = {lo:g}"
    parts = [f"{lo:g} <= " if lo is not None and lo > -float("inf") else "", e,
             f" <= {hi:g}" if hi is not None and hi < float("inf") else ""]
    return "".join(parts)


def _num(b: Any) -> float | None:
    b = ca.SX(b)
    return float(b) if b.is_constant() else None
