"""SIGTERM and SIGHUP handled like Ctrl-C: the same cleanup runs, then a distinct exit code.

Python turns SIGINT into :class:`KeyboardInterrupt`, so context managers and ``finally``
blocks remove temporary files; SIGTERM (``kill``, a batch system, a container stopping) or
SIGHUP (the terminal closed) would end the process on the spot and leave them.
:func:`handle_signals` makes them raise :class:`Terminated`, a :class:`KeyboardInterrupt`,
so every cleanup path written for Ctrl-C serves all three; :func:`startup_signals` does so
from the first line of the command (before its imports), so that a signal during start-up
ends it the same way. :func:`deferred_signals` holds a signal back for the few steps
(placing a file and recording it) that must not be split. Once a signal has arrived, the
warnings CasADi prints about the interruption it met inside a solve
(``WARNING("KeyboardInterruptException")``) are dropped: the run's one line says it.
"""

from __future__ import annotations

import _thread
import contextlib
import signal
import sys
import threading
import time
from collections.abc import Iterator
from types import FrameType
from typing import Any, TextIO

EXIT_INTERRUPTED = 130
"""Exit code after SIGINT (Ctrl-C): 128 + 2, as a shell reports it."""
EXIT_TERMINATED = 143
"""Exit code after SIGTERM: 128 + 15, as a shell reports it."""

TERMINATING: dict[int, str] = {signal.SIGTERM: "terminated (SIGTERM)"}
"""Signals that end the run as :class:`Terminated` (exit 128 + the signal's number), and how
the one line names them: SIGTERM, and SIGHUP where the platform has it."""
if hasattr(signal, "SIGHUP"):
    TERMINATING[signal.SIGHUP] = "hung up (SIGHUP)"


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM or SIGHUP (raised in the main thread, like Ctrl-C's
    exception).

    Parameters
    ----------
    signum : int
        The signal (default SIGTERM).
    """

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__(signum)
        self.signum = int(signum)


_deferring = 0
_pending: list[int] = []
_received: list[int] = []
_reported: list[int] = []  # the exit codes report_interrupt gave
_terminated = False


def _interruption(signum: int) -> KeyboardInterrupt:
    return Terminated(signum) if signum in TERMINATING else KeyboardInterrupt()


def _raise_for(signum: int) -> None:
    global _terminated
    _received.append(signum)
    _quiet_casadi()
    if signum in TERMINATING:
        if _terminated:  # a repeated signal must not cut the cleanup of the first short
            return
        _terminated = True
        raise Terminated(signum)
    raise KeyboardInterrupt()


class _WithoutCasadiNotes:
    """``sys.stderr`` less CasADi's lines (``CasADi - <time> WARNING(...)``), which CasADi
    writes through it: after an interruption they only report it, inside a solve."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.line = ""  # a CasADi line being written, until its end

    def write(self, text: str) -> int:
        if not self.line and not text.startswith("CasADi - "):
            return self.stream.write(text)
        self.line += text
        head, sep, rest = self.line.partition("\n")
        if sep:  # the CasADi line is whole: dropped; what follows is written
            self.line = ""
            if rest:
                self.write(rest)
        return len(text)

    def __getattr__(self, name: str) -> Any:  # flush, isatty, fileno, encoding...
        return getattr(self.stream, name)


def _quiet_casadi() -> None:
    if not isinstance(sys.stderr, _WithoutCasadiNotes) and sys.stderr is not None:
        sys.stderr = _WithoutCasadiNotes(sys.stderr)


def _restore_stderr() -> None:
    if isinstance(sys.stderr, _WithoutCasadiNotes):
        sys.stderr = sys.stderr.stream


def _handler(signum: int, frame: FrameType | None) -> None:
    if _deferring:
        _pending.append(signum)
        return
    _raise_for(signum)


def _quiet_unraisable(hook: Any) -> Any:
    """``sys.unraisablehook`` that hands back an interruption raised where it cannot propagate.

    The handler's exception may land in a destructor (llvmlite's, while numba compiles) or a
    C callback: Python prints it there as "Exception ignored" with a traceback, and the run
    goes on. Instead: print nothing, and deliver the signal again to the main thread, where
    it raises at the next bytecode.
    """
    def unraisable(u: Any) -> None:
        global _terminated
        if u.exc_type is not None and issubclass(u.exc_type, KeyboardInterrupt) and _received:
            signum = _received[-1]
            if signum in TERMINATING:
                _terminated = False  # the raise was lost: the repeated delivery must raise
            # from another thread, once this hook has returned (raised inside the hook, it
            # would be lost again): the thread waits for the hook's last statement, since
            # starting it blocks here (a timer fired within that wait under load)
            ready = threading.Event()

            def again() -> None:
                ready.wait()
                time.sleep(0.001)
                _thread.interrupt_main(signal.Signals(signum))

            threading.Thread(target=again, daemon=True).start()
            ready.set()
            return
        hook(u)

    return unraisable


@contextlib.contextmanager
def deferred_signals() -> Iterator[None]:
    """Hold SIGINT and SIGTERM (as installed by :func:`handle_signals`) until the body ends.

    Outside :func:`handle_signals` (and :func:`startup_signals`), or in another thread,
    this does nothing.
    """
    global _deferring
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
        if not _deferring and _pending:
            signum = _pending[0]
            _pending.clear()
            _raise_for(signum)


def raise_if_interrupted() -> None:
    """Raise the interruption again if one was received and swallowed on its way up.

    CasADi, for one, turns the exception raised inside a solve into a failed solve; a caller
    may then carry on. Call this before keeping a run's results.

    Raises
    ------
    KeyboardInterrupt
        :class:`Terminated` after SIGTERM, :class:`KeyboardInterrupt` after SIGINT.
    """
    if _received:
        raise _interruption(_received[0])


def _install() -> dict[int, Any]:
    """Our handler for SIGINT, SIGTERM and SIGHUP where each has its default (a handler
    someone else installed, e.g. SIGINT or SIGHUP ignored by ``nohup``, is left alone);
    the previous handlers of those changed."""
    previous: dict[int, Any] = {}
    defaults: list[tuple[int, Any]] = [(signal.SIGINT, signal.default_int_handler)] + [
        (signum, signal.SIG_DFL) for signum in TERMINATING]
    for signum, default in defaults:
        if signal.getsignal(signum) is default:
            previous[signum] = signal.signal(signum, _handler)
    return previous


def startup_signals() -> None:
    """SIGTERM and SIGHUP raise :class:`Terminated` from now on, in the main thread (for a
    command's first line: its start-up then ends like the rest of the run). Kept for the
    process's life; :func:`handle_signals` then works as usual."""
    if threading.current_thread() is threading.main_thread():
        _install()


@contextlib.contextmanager
def handle_signals() -> Iterator[None]:
    """Within the body, SIGTERM and SIGHUP raise :class:`Terminated` and SIGINT
    :class:`KeyboardInterrupt`.

    Handlers someone else installed (e.g. SIGINT ignored by ``nohup``, a test runner's own)
    are left alone; the previous handlers are restored on exit. Only the main thread can
    install handlers: elsewhere the body runs unchanged.
    """
    global _terminated
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = _install()
    _terminated = False
    _received.clear()
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _quiet_unraisable(previous_hook)
    try:
        yield
    except Exception as exc:  # an interruption swallowed and turned into another error
        if _received:
            raise _interruption(_received[0]) from exc
        raise
    finally:
        sys.unraisablehook = previous_hook
        for signum, old in previous.items():
            signal.signal(signum, old)
        _pending.clear()
        _received.clear()
        _restore_stderr()


def report_interrupt(exc: KeyboardInterrupt, prog: str = "softlanding") -> int:
    """One line on stderr for an interrupted run; its exit code (130 Ctrl-C, 143 SIGTERM,
    129 SIGHUP).

    Parameters
    ----------
    exc : KeyboardInterrupt
        The interruption (:class:`Terminated` for SIGTERM).
    prog : str
        The program's name, for the message.

    Returns
    -------
    int
        The exit code.
    """
    code = 128 + exc.signum if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    what = TERMINATING.get(exc.signum, "terminated") if isinstance(exc, Terminated) else \
        "interrupted"
    print(f"{prog}: {what}", file=sys.stderr)
    _reported.append(code)
    return code


def reported_interrupt() -> int:
    """The exit code :func:`report_interrupt` gave last (0: it has not reported)."""
    return _reported[-1] if _reported else 0
