"""The ``softlanding`` console script: :func:`console_main` around :func:`main`.

Modules: :mod:`.commands` (the sub-commands' handlers and :func:`main`), :mod:`.parser`
(the argument parser), :mod:`.ground` (the ``--ground`` options), :mod:`.scale`
(``scale``), :mod:`.variants` (the variant table of ``solve``), :mod:`.output` (exit codes,
tables, JSON, errors).

This module is light: :func:`console_main` installs the signal handlers before importing
the rest, so that SIGTERM or SIGHUP during start-up ends the run as it would later (one
line, the signal's exit code), not silently.
"""

from typing import Any

from softlanding.util.signals import report_interrupt, startup_signals


def console_main() -> int:
    """The ``softlanding`` console script and ``python -m softlanding``
    (:func:`softlanding.cli.commands.console_main`, its signals handled from the start).

    Returns
    -------
    int
        The exit code.
    """
    startup_signals()
    try:
        from softlanding.cli.commands import console_main as run
    except KeyboardInterrupt as exc:  # during the imports
        return report_interrupt(exc)
    return run()


def __getattr__(name: str) -> Any:
    if name == "main":  # the command's entry point, loaded on first use
        from softlanding.cli.commands import main

        return main
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["console_main", "main"]
