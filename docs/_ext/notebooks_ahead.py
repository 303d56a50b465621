"""The notebooks executed before Sphinx reads them, several at a time, into myst-nb's cache.

myst-nb executes a notebook when Sphinx reads it, one after another: the seven teaching
notebooks are most of the build's time, and each mostly waits on its own kernel, one core.
Here, before the pages are read, every notebook to be read that myst-nb's cache does not hold
is executed the way myst-nb's ``cache`` mode executes it (jupyter-cache's
``single_nb_execution``: a fresh kernel in a temporary folder, the same timeout, errors not
allowed) by a pool of ``SOFTLANDING_DOCS_JOBS`` threads (default: the cores, at most 4), and
put in the cache; myst-nb then reads them from it as from an earlier build. A notebook that
fails here is left out of the cache: myst-nb runs it again and reports the failure as before
(the build fails). With ``SOFTLANDING_DOCS_JOBS=1`` nothing runs ahead (myst-nb's own order).

myst-nb 1.4 writes a notebook it takes from the cache to ``jupyter_execute/`` as read, without
its outputs (it merges them into a copy): a notebook run ahead is written there again, as
executed, once myst-nb has read it (tests/test_notebooks.py reads those files).
"""

from __future__ import annotations

import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import Any

from execution_log import say

_EXECUTED: dict[str, str] = {}
"""The notebooks run ahead, as executed (JSON), by document name."""


def jobs() -> int:
    """How many notebooks run at once (``SOFTLANDING_DOCS_JOBS``, default the cores up to 4)."""
    raw = os.environ.get("SOFTLANDING_DOCS_JOBS", "")
    return max(1, int(raw)) if raw.strip() else max(1, min(os.cpu_count() or 1, 4))


def _run(path: Path, config: Any) -> tuple[Any, float]:
    """One notebook executed as myst-nb's cache mode does (its result and wall seconds)."""
    import nbformat
    from jupyter_cache.executors.utils import single_nb_execution

    nb = nbformat.read(path, as_version=4)
    start = time.perf_counter()
    with TemporaryDirectory() as cwd:
        result = single_nb_execution(nb, cwd=cwd if config.execution_in_temp else
                                     str(path.parent), timeout=config.execution_timeout,
                                     allow_errors=config.execution_allow_errors,
                                     meta_override=True)
    return result, time.perf_counter() - start


def _execute_ahead(app: Any, env: Any, docnames: list[str]) -> None:
    config = getattr(env, "mystnb_config", None)
    n = jobs()
    if config is None or config.execution_mode != "cache" or n < 2:
        return
    import nbformat
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    cache = get_cache(config.execution_cache_path)
    todo = []
    for d in docnames:
        path = Path(env.doc2path(d))
        if path.suffix != ".ipynb":
            continue
        try:
            cache.match_cache_notebook(nbformat.read(path, as_version=4))
        except KeyError:
            todo.append((d, path))
    if len(todo) < 2:
        return
    say(f"running {len(todo)} notebooks, {n} at a time, into myst-nb's cache ...")
    with ThreadPoolExecutor(n) as pool:
        runs = [(d, path, pool.submit(_run, path, config)) for d, path in todo]
        for d, path, run in runs:  # the cache's database written from this thread only
            try:
                result, seconds = run.result()
            except Exception as err:  # noqa: BLE001 - myst-nb runs it again and reports it
                say(f"ran {d}: {type(err).__name__}, left to myst-nb")
                continue
            if result.err is not None:
                say(f"ran {d}: {type(result.err).__name__}, left to myst-nb to report")
                continue
            _EXECUTED[d] = nbformat.writes(result.nb)
            record = cache.add_nb_to_project(str(path))
            cache.cache_notebook_bundle(CacheBundleIn(result.nb, record.uri,
                                                      data={"execution_seconds": result.time}),
                                        check_validity=False, overwrite=True)
            say(f"ran {d} in {seconds:.1f} s")


def _write_executed(app: Any, doctree: Any) -> None:
    """After myst-nb wrote the notebook it read to ``jupyter_execute/``: the executed one."""
    text = _EXECUTED.pop(app.env.docname, None)
    if text is None:
        return
    *folders, name = app.env.docname.split("/")
    path = Path(app.env.mystnb_config.output_folder).joinpath(*folders, name + ".ipynb")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)  # whole or not at all


def setup(app: Any) -> dict[str, bool]:
    """Run the notebooks ahead when the pages are about to be read; write them as executed
    once read.

    Parameters
    ----------
    app : sphinx.application.Sphinx
        The application.
    """
    app.connect("env-before-read-docs", _execute_ahead, priority=400)
    app.connect("doctree-read", _write_executed)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
