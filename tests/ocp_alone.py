"""A pytest plugin that makes ``softlanding`` unimportable, so that ``ocp`` and its tests are
shown to run without it (issue 46 item 5): the ocp-only job of ``.ci/run`` runs
``python -m pytest -p tests.ocp_alone tests/ocp ...``.

Loaded with ``-p`` it installs its finder before any conftest is imported; an import of
``softlanding`` or of one of its modules then raises ModuleNotFoundError naming this job.
"""

from __future__ import annotations

import importlib.abc
import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

BLOCKED = "softlanding"


class SoftlandingBlocker(importlib.abc.MetaPathFinder):
    """Refuses ``softlanding`` and its sub-modules (first on ``sys.meta_path``)."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> ModuleSpec | None:
        """Raise for ``softlanding`` and ``softlanding.*``; None (not mine) for the rest."""
        if fullname == BLOCKED or fullname.startswith(BLOCKED + "."):
            raise ModuleNotFoundError(f"{fullname}: blocked, ocp is tested without softlanding "
                                      "(tests/ocp_alone.py)", name=fullname)
        return None


def install() -> None:
    """Put the blocker first on ``sys.meta_path`` (once); refuse if softlanding is loaded."""
    loaded = sorted(m for m in sys.modules if m == BLOCKED or m.startswith(BLOCKED + "."))
    if loaded:
        raise RuntimeError(f"softlanding was imported before the blocker: {loaded[:3]}")
    if not any(isinstance(f, SoftlandingBlocker) for f in sys.meta_path):
        sys.meta_path.insert(0, SoftlandingBlocker())


install()
