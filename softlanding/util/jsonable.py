"""JSON output helper (no heavy imports: the CLI uses it for every command)."""

from __future__ import annotations

import math


def json_safe(obj):
    """A JSON-able copy: numpy scalars and arrays to Python, non-finite floats to None.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, tuples, numpy scalars and arrays, numbers.
    """
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if hasattr(obj, "tolist"):  # numpy scalars and arrays
        return json_safe(obj.tolist())
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    return obj
