"""SIGTERM handled like Ctrl-C: the same cleanup runs, then a distinct exit code.

Python turns SIGINT into :class:`KeyboardInterrupt`, so context managers and ``finally``
blocks remove temporary files; SIGTERM (``kill``, a batch system, a container stopping) would
end the process on the spot and leave them. :func:`handle_signals` makes SIGTERM raise
:class:`Terminated`, a :class:`KeyboardInterrupt`, so every cleanup path written for Ctrl-C
serves both. :func:`deferred_signals` holds a signal back for the few steps (placing a file
and recording it) that must not be split.
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
from typing import Any

EXIT_INTERRUPTED = 130
"""Exit code after SIGINT (Ctrl-C): 128 + 2, as a shell reports it."""
EXIT_TERMINATED = 143
"""Exit code after SIGTERM: 128 + 15, as a shell reports it."""


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM (raised in the main thread, like Ctrl-C's exception).

    Parameters
    ----------
    *args, **kwargs
        As :class:`KeyboardInterrupt`.
    """


_deferring = 0
_pending: list[int] = []
_received: list[int] = []
_terminated = False


def _interruption(signum: int) -> KeyboardInterrupt:
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def _raise_for(signum: int) -> None:
    global _terminated
    _received.append(signum)
    if signum == signal.SIGTERM:
        if _terminated:  # a repeated SIGTERM must not cut the cleanup of the first short
            return
        _terminated = True
        raise Terminated()
    raise KeyboardInterrupt()


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
            if signum == signal.SIGTERM:
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

    Outside :func:`handle_signals`, or in another thread, this does nothing.
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


@contextlib.contextmanager
def handle_signals() -> Iterator[None]:
    """Within the body, SIGTERM raises :class:`Terminated` and SIGINT :class:`KeyboardInterrupt`.

    Handlers someone else installed (e.g. SIGINT ignored by ``nohup``, a test runner's own)
    are left alone; the previous handlers are restored on exit. Only the main thread can
    install handlers: elsewhere the body runs unchanged.
    """
    global _terminated
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for signum, default in ((signal.SIGTERM, signal.SIG_DFL),
                            (signal.SIGINT, signal.default_int_handler)):
        if signal.getsignal(signum) is default:
            previous[signum] = signal.signal(signum, _handler)
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


def report_interrupt(exc: KeyboardInterrupt, prog: str = "softlanding") -> int:
    """One line on stderr for an interrupted run; its exit code (130 Ctrl-C, 143 SIGTERM).

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
    if isinstance(exc, Terminated):
        print(f"{prog}: terminated (SIGTERM)", file=sys.stderr)
        return EXIT_TERMINATED
    print(f"{prog}: interrupted", file=sys.stderr)
    return EXIT_INTERRUPTED
