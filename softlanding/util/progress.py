"""Progress bars (tqdm, imported only when a bar is shown).

A bar is drawn only when asked for *and* stderr is a terminal, so logs and
pipes never fill with carriage-return frames; :data:`FORCE` (the CLI's
``--progress``) draws them anyway.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterable, Iterator
from typing import Any

FORCE = False
"""Draw bars even when stderr is not a terminal."""


def _wanted(enabled: bool | None) -> bool:
    if not enabled:
        return False
    return FORCE or (hasattr(sys.stderr, "isatty") and sys.stderr.isatty())


def progress(items: Iterable, enabled: bool | None, desc: str, unit: str) -> Iterable:
    """``items`` wrapped in a tqdm bar when enabled and on a terminal, else unchanged.

    Parameters
    ----------
    items : iterable
        What to iterate over.
    enabled : bool or None
        Whether a bar is wanted.
    desc, unit : str
        tqdm's description and unit.
    """
    if not _wanted(enabled):
        return items
    from tqdm.auto import tqdm

    return tqdm(items, desc=desc, unit=unit)


class _NoBar:
    def update(self, n: int = 1) -> None:
        """Ignore progress."""


@contextlib.contextmanager
def progress_bar(total: int, desc: str, unit: str) -> Iterator[Any]:
    """A tqdm bar of ``total`` steps (none when ``total`` is 0 or stderr is no terminal).

    Parameters
    ----------
    total : int
        Number of steps (0: no bar).
    desc, unit : str
        tqdm's description and unit.
    """
    if not _wanted(total > 0):
        yield _NoBar()
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit)
    try:
        yield bar
    finally:
        bar.close()
