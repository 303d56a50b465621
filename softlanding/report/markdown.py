"""Markdown cells and tables for ``summary.md``."""

from __future__ import annotations

import math
from typing import Any


def cell(x: Any, nd: int = 4) -> str:
    """A number as a table cell: ``nd`` decimals, yes/no, n/a for None or NaN, +-inf.

    Parameters
    ----------
    x : object
        The value.
    nd : int
        Decimals of a float.
    """
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a" if x is None or math.isnan(x) else ("inf" if x > 0 else "-inf")
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return str(x)
    return f"{x:.{nd}f}"


def table(header: list[str], rows: list[list]) -> str:
    """A Markdown table.

    Parameters
    ----------
    header : list of str
        Column titles.
    rows : list of list
        The cells, row by row (converted with ``str``).
    """
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


__all__ = ["cell", "table"]
