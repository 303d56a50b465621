"""The ``softlanding`` console script: :func:`console_main` around :func:`main`.

Modules: :mod:`.commands` (the sub-commands' handlers and :func:`main`), :mod:`.parser`
(the argument parser), :mod:`.ground` (the ``--ground`` options), :mod:`.variants` (the
variant table of ``solve``), :mod:`.output` (exit codes, tables, JSON, errors).
"""

from softlanding.cli.commands import console_main, main

__all__ = ["console_main", "main"]
