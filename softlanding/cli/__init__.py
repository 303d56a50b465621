"""The ``softlanding`` console script: :func:`main`.

Modules: :mod:`.commands` (the sub-commands' handlers and :func:`main`), :mod:`.parser`
(the argument parser), :mod:`.ground` (the ``--ground`` options), :mod:`.phased` (the
multi-phase variants and hops), :mod:`.output` (exit codes, tables, JSON, files, errors).
"""

from softlanding.cli.commands import main

__all__ = ["main"]
