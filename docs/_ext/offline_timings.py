"""The execution-times page offline: no script or style sheet from the internet.

sphinx-gallery writes ``sg_execution_times.rst`` with a raw HTML block that loads jQuery,
DataTables and Bootstrap from CDNs to make its table sortable; those were the site's only
remote assets. The block is dropped as the page is read; the table itself stays (plain).
"""

from __future__ import annotations

import re
from typing import Any

REMOTE_BLOCK = re.compile(r"^  \.\. raw:: html\n(?:\n|    .*\n)*", re.MULTILINE)
"""sphinx-gallery's raw block, indented under its ``.. container::`` up to the table."""


def plain(text: str) -> str:
    """The page without its raw HTML block.

    Parameters
    ----------
    text : str
        The reST source of an execution-times page.

    Returns
    -------
    str
        The same page, its table kept, nothing loaded from the network.
    """
    return REMOTE_BLOCK.sub("", text)


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    if docname.endswith("sg_execution_times"):
        source[0] = plain(source[0])


def setup(app: Any) -> dict[str, Any]:
    """Register the ``source-read`` handler (a Sphinx extension)."""
    app.connect("source-read", _source_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
