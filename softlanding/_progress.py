"""Optional progress bars (tqdm, imported only when asked for)."""

from __future__ import annotations

from collections.abc import Iterable


def progress(items: Iterable, enabled: bool, desc: str, unit: str) -> Iterable:
    """``items`` wrapped in a tqdm bar when ``enabled``, else unchanged."""
    if not enabled:
        return items
    from tqdm.auto import tqdm

    return tqdm(items, desc=desc, unit=unit)
