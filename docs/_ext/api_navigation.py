"""The API's object pages out of the site's navigation tree.

autosummary lists each generated object page (about 230) in a toctree of its module's page,
so the theme's sidebar, rendered into every one of the site's pages, held every object of
the API: furo resolved and parsed that tree once per page, half of the build's CPU (93 s of
a build without the gallery). The object pages are reached from their module's table (and
every cross-reference); the sidebar lists the guides, notebooks, gallery and the module
pages. The generated pages are ``:orphan:`` (docs/_templates/autosummary), so that Sphinx
does not ask for a toctree that includes them.
"""

from __future__ import annotations

from typing import Any

from sphinx.ext.autosummary import autosummary_toc


def drop_object_toctrees(app: Any, doctree: Any) -> None:
    """Remove autosummary's toctrees from a page as it is read (before Sphinx collects the
    page's toctrees).

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    doctree : docutils.nodes.document
        The page just read.
    """
    for node in list(doctree.findall(autosummary_toc)):
        node.parent.remove(node)


def setup(app: Any) -> dict[str, Any]:
    """Register the handler, ahead of Sphinx's toctree collector (priority 500).

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    """
    app.connect("doctree-read", drop_object_toctrees, priority=400)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
