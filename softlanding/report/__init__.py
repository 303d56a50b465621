"""The reproduction of the paper and beyond: :func:`reproduce` writes every figure, table,
dataset and ``summary.md`` into one folder.

Modules: :mod:`.registry` (a section: its run and its Markdown; the run's context and
settings), :mod:`.paper` (the paper's sections), :mod:`.terrain` (the terrain models),
:mod:`.phased` (the multi-phase landings and hops), :mod:`.reproduction` (the registry in
order, :func:`reproduce`, ``summary.md``), :mod:`.markdown` (cells and tables), :mod:`.demo`
(the ``softlanding demo`` table and figure).
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach_stub(__name__, __file__)
