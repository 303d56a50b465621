"""The build says what it executes: a line on stderr per gallery example and notebook.

The build is quiet otherwise (``-q``: warnings and errors only), and the executed pages are
most of its time (each notebook up to a minute, the gallery about a minute in all), so
without these lines ``make -C docs html`` would sit silent for many minutes. Each line
says what runs and, when it is done, how long it took (a notebook unchanged since the
last build comes from myst-nb's cache in a moment). Written to stderr directly, so ``-q``
does not hide them and ``-W`` does not count them as warnings.
"""

from __future__ import annotations

import sys
import time
from typing import Any

PREFIX = "docs:"
"""Every line of this extension starts with it (tests/test_docs.py tells them apart)."""

_started: dict[str, float] = {}


def say(text: str) -> None:
    """One line on stderr, flushed at once.

    Parameters
    ----------
    text : str
        The line, without the prefix.
    """
    print(f"{PREFIX} {text}", file=sys.stderr, flush=True)


def gallery_example(gallery_conf: dict, fname: str | None, when: str) -> None:
    """sphinx-gallery's ``reset_modules`` hook, before and after each example it runs.

    Parameters
    ----------
    gallery_conf : dict
        sphinx-gallery's configuration.
    fname : str or None
        The example (None when sphinx-gallery calls it entering a gallery folder).
    when : {"before", "after"}
        Which side of the example.
    """
    if fname is None:
        return
    if when == "before":
        _started[fname] = time.perf_counter()
        say(f"executing the gallery example {fname} ...")
    else:
        say(f"executed {fname} in {time.perf_counter() - _started.pop(fname, 0.0):.1f} s")


def _notebooks(env: Any, docnames: list[str]) -> list[str]:
    return [d for d in docnames if env.doc2path(d).suffix == ".ipynb"]


def _before_reading(app: Any, env: Any, docnames: list[str]) -> None:
    nbs = _notebooks(env, docnames)
    if nbs and app.config.nb_execution_mode != "off":
        say(f"reading {len(docnames)} pages, {len(nbs)} of them notebooks, executed by myst-nb "
            "(a notebook unchanged since the last build comes from its cache)")


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    if app.config.nb_execution_mode != "off" and _notebooks(app.env, [docname]):
        _started[docname] = time.perf_counter()
        say(f"executing the notebook {docname} ...")


def _doctree_read(app: Any, doctree: Any) -> None:
    docname = app.env.docname
    if docname in _started:
        say(f"notebook {docname} done in {time.perf_counter() - _started.pop(docname):.1f} s")


def setup(app: Any) -> dict[str, bool]:
    """Connect the notebook lines (the gallery's come from its ``reset_modules`` hook,
    set in conf.py).

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    """
    app.connect("env-before-read-docs", _before_reading)
    app.connect("source-read", _source_read)
    app.connect("doctree-read", _doctree_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
