"""CasADi's messages, taken from the output and re-emitted as this package's log.

CasADi reports from C++ with ``casadi_warning``: a line ``CasADi - <date> <time>
WARNING("...") [<source>:<line>]`` for, e.g., a NaN in an evaluation of a rootfinder's or an
NLP's functions (``active_set_newton:jac_g_x failed: NaN detected ...``, normal when Newton or
Ipopt tries a step outside the arcs' domain and backs off) or multipliers it could not
compute. CasADi's Python build prints them, and whatever Ipopt prints, through Python's
``sys.stdout`` and ``sys.stderr`` (so that a notebook shows them), not to the file
descriptors: so they are taken there.

:func:`solver_output` wraps a solver's evaluation: while any thread is inside one, both
streams are replaced by a filter that passes every write through at once, except, on a thread
inside the context, the lines of CasADi's message format, which become :mod:`logging`
records of the logger ``ocp.solver`` (level DEBUG: a verbose log, silent by default; a failed
solve is reported by its status, not by these lines). Nothing else is held back: a crash
inside the evaluation loses at most the unfinished line of a CasADi message. The streams are
put back when the last thread leaves (one a caller replaced meanwhile is left to it, and the
filter it wraps keeps passing writes through). Cost: a lock and two attribute swaps per call,
about a microsecond.

Turn the log on with ``logging.getLogger("ocp.solver").setLevel(logging.DEBUG)`` and a handler
(``logging.basicConfig(level=logging.DEBUG)``).
"""

from __future__ import annotations

import contextlib
import logging
import re
import sys
import threading
from collections.abc import Iterator
from typing import Any

LOGGER = logging.getLogger("ocp.solver")
"""Where CasADi's messages go (level DEBUG)."""

MESSAGE = re.compile(r"^CasADi - \S+ \S+ (?P<kind>[A-Z]+)\(\"(?P<text>.*)\"\)"
                     r"(?: \[(?P<where>[^\]]*)\])?\s*$")
"""A line of CasADi's message format (``casadi_warning``, ``casadi_message``)."""

_PREFIX = "CasADi - "
_LOCK = threading.Lock()
_LOCAL = threading.local()  # .logs: this thread's open contexts' message lists; .pending
_STREAMS = ("stdout", "stderr")
_state: dict[str, Any] = {"users": 0, "filters": {}}


def _capturing() -> list | None:
    logs = getattr(_LOCAL, "logs", None)
    return logs[-1] if logs else None


class _Filter:
    """A stream that passes writes through to ``target``, but CasADi's message lines
    written by a thread inside :func:`solver_output`."""

    def __init__(self, target: Any, name: str) -> None:
        self.target = target
        self.name = name

    def write(self, text: str) -> int:
        """Pass ``text`` on, or log the CasADi lines in it (on a capturing thread)."""
        log = _capturing()
        if log is None:
            return self.target.write(text)
        pending: dict[str, str] = _LOCAL.__dict__.setdefault("pending", {})
        text = pending.pop(self.name, "") + text
        out = []
        for line in text.splitlines(keepends=True):
            if not line.endswith("\n") and (line.startswith(_PREFIX) or
                                            _PREFIX.startswith(line)):
                pending[self.name] = line  # maybe CasADi's: wait for the line's end
            elif line.startswith(_PREFIX) and _emit(line, log):
                continue
            else:
                out.append(line)
        if out:
            self.target.write("".join(out))
        return len(text)

    def flush(self) -> None:
        """Flush the stream passed through to."""
        self.target.flush()

    def __getattr__(self, attr: str) -> Any:  # isatty, fileno, encoding, ...: the target's
        return getattr(self.target, attr)


def _emit(line: str, log: list) -> bool:
    """Log one line if it is CasADi's message format; whether it was."""
    m = MESSAGE.match(line)
    if m is None:
        return False
    text = m["text"]
    log.append(text)
    LOGGER.debug("CasADi %s: %s%s", m["kind"].lower(), text,
                 f" [{m['where']}]" if m["where"] else "")
    return True


def _install() -> None:
    for name in _STREAMS:
        current = getattr(sys, name)
        if current is None:  # no such stream (pythonw): nothing is printed anyway
            continue
        if isinstance(current, _Filter):  # left in place by an earlier context: reused
            _state["filters"][name] = current
            continue
        f = _Filter(current, name)
        _state["filters"][name] = f
        setattr(sys, name, f)


def _uninstall() -> None:
    for name, f in _state["filters"].items():
        if getattr(sys, name) is f:
            setattr(sys, name, f.target)
    _state["filters"] = {}


@contextlib.contextmanager
def solver_output() -> Iterator[list[str]]:
    """Take CasADi's messages written during the block and log them (``ocp.solver``,
    DEBUG) instead of printing them; everything else is printed as it comes.

    Yields
    ------
    list of str
        The messages taken on this thread during the block (filled as they come), e.g.
        ``"active_set_newton:jac_g_x failed: NaN detected for output jac_o0_i0, ..."``.
    """
    log: list[str] = []
    with _LOCK:
        if _state["users"] == 0:
            _install()
        _state["users"] += 1
    logs = _LOCAL.__dict__.setdefault("logs", [])
    logs.append(log)
    try:
        yield log
    finally:
        logs.pop()
        pending = _LOCAL.__dict__.get("pending", {}) if not logs else {}
        for name, text in list(pending.items()):  # an unfinished line: as it was
            del pending[name]
            if not _emit(text, log):
                getattr(sys, name).write(text)
        with _LOCK:
            _state["users"] -= 1
            if _state["users"] == 0:
                _uninstall()
