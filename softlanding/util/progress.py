"""Progress bars (tqdm, imported only when a bar is shown).

A bar is drawn only when asked for *and* stderr is a terminal, so logs and
pipes never fill with carriage-return frames; :data:`FORCE` (the CLI's
``--progress``) draws them anyway.

:func:`activity` is the bar of one long call whose inside reports its steps with
:func:`step` (a no-op when no activity is open on the thread: library code calls it freely);
its elapsed time runs even between steps, so a terminal never sits silent.
"""

from __future__ import annotations

import contextlib
import sys
import threading
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
    n = 0

    def update(self, n: int = 1) -> None:
        """Ignore progress."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Ignore the note."""


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


_ACTIVE = threading.local()  # .bars: this thread's open activities, innermost last


@contextlib.contextmanager
def activity(desc: str, total: int | None = None, unit: str = "step", *,
             enabled: bool | None = True, leave: bool = False) -> Iterator[Any]:
    """A bar for a long call (on a terminal, or with :data:`FORCE`): ``total`` steps (None:
    a count), advanced by :func:`step` from the code inside, redrawn every second so the
    elapsed time runs between steps.

    Parameters
    ----------
    desc : str
        What runs (the bar's description).
    total : int, optional
        Steps expected.
    unit : str
        tqdm's unit.
    enabled : bool or None
        Whether a bar is wanted (still only on a terminal).
    leave : bool
        Keep the bar's last state on the screen when done.

    Yields
    ------
    object
        The bar (``update``, ``set_postfix_str``), or one that ignores them.
    """
    bars = _ACTIVE.__dict__.setdefault("bars", [])
    if not _wanted(enabled):
        bars.append(_NoBar())
        try:
            yield bars[-1]
        finally:
            bars.pop()
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit, leave=leave)
    done = threading.Event()

    def tick() -> None:
        while not done.wait(1.0):
            bar.refresh()

    ticker = threading.Thread(target=tick, name="softlanding-progress", daemon=True)
    ticker.start()
    bars.append(bar)
    try:
        yield bar
    finally:
        bars.pop()
        done.set()
        ticker.join()
        bar.close()


def step(note: str | None = None, n: int = 1) -> None:
    """Advance this thread's innermost :func:`activity` by ``n`` (nothing if none is open).

    Parameters
    ----------
    note : str, optional
        Shown after the bar (e.g. ``"start 2 of 3"``).
    n : int
        Steps done.
    """
    bars = getattr(_ACTIVE, "bars", None)
    if not bars:
        return
    if note is not None:
        bars[-1].set_postfix_str(note, refresh=False)
    bars[-1].update(n)
