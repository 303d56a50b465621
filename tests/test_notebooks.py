"""Every notebook in notebooks/ runs top to bottom without error.

The notebooks are executed once per test run, by the documentation's build (the
``docs_site`` fixture of tests/conftest.py: myst-nb runs each in a Jupyter kernel, in a
temporary folder, and writes it as executed under ``jupyter_execute/``); the tests here read
those executed notebooks (they used to execute them a second time with nbclient: the build,
notebooks included, takes about 470 s CPU on a cold cache).
"""

from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
FIGURES = {"05_terrain_models.ipynb": 3, "06_hybrid_landing_and_hopping.ipynb": 4,
           "07_unknown_ground.ipynb": 5}
"""How many figures a notebook shows (each once): none lost, none shown twice."""


def _plots(source: str) -> bool:
    """A cell that draws: calls a plot_* function or pyplot, ending with a bare expression."""
    return "plot" in source or "plt." in source


@pytest.mark.notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes_and_shows_its_figures(path, docs_site):
    res, out = docs_site
    executed = out / "jupyter_execute" / "notebooks" / path.name
    assert executed.is_file(), f"{path.name} not executed by the docs build:\n{res.stderr[-4000:]}"
    nb = nbformat.read(executed, as_version=4)
    stored = nbformat.read(path, as_version=4)  # the notebook as stored, every cell executed
    assert [c.source for c in nb.cells] == [c.source for c in stored.cells]
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.execution_count for c in code), [c.source[:80] for c in code
                                                  if not c.execution_count]
    errors = [o for c in code for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors
    printed = "".join(o.get("text", "") for c in code for o in c.get("outputs", [])
                      if o.get("output_type") == "stream")
    assert "WARNING(" not in printed, printed[:2000]  # CasADi's messages: logged, not shown
    drawing = [c for c in code if _plots(c.source) and "import" not in c.source]
    assert drawing
    for c in drawing:  # inline figures: the library must not switch the backend away
        pngs = [o for o in c.outputs if "image/png" in o.get("data", {})]
        assert pngs, f"no figure shown by the cell:\n{c.source[:200]}"
    for c in code:  # each figure once (a cell ending in a figure shows it a second time)
        shown = [o["data"]["image/png"] for o in c.get("outputs", [])
                 if "image/png" in o.get("data", {})]
        assert len(shown) == len(set(shown)), f"a figure shown twice by:\n{c.source[:200]}"
    if path.name in FIGURES:
        pngs = [o for c in code for o in c.get("outputs", []) if "image/png" in o.get("data", {})]
        assert len(pngs) == FIGURES[path.name]


def test_there_is_a_notebook():
    assert NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stored_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)
