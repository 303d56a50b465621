"""Sphinx configuration of the softlanding documentation (``make -C docs html``).

Offline and reproducible: no intersphinx, no remote assets. The API reference is generated
from the front doors' ``__all__`` (see :func:`write_api_pages`), the gallery executes
``docs/examples/*.py`` (sphinx-gallery), the teaching notebooks (stored without outputs) are
executed at build so that their pages show the figures, several at a time
(docs/_ext/notebooks_ahead.py; ``SOFTLANDING_DOCS_JOBS``, default the cores) into myst-nb's
cache under ``_build/.jupyter_cache`` (re-executed only when a notebook changes), which
myst-nb then reads. MathJax is bundled
(sphinx-mathjax-offline): the maths renders without a network. ``SOFTLANDING_DOCS_GALLERY=0``
skips executing the gallery and the notebooks (a fast structural build).
"""

from __future__ import annotations

import importlib
import logging
import os
import sys
from pathlib import Path

import matplotlib
from nbclient import NotebookClient

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

from softlanding._version import __version__  # noqa: E402

project = "softlanding"
author = "softlanding developers"
copyright = "2026, softlanding developers"
version = release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static: no CDN (sets mathjax_path)
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",
    "sphinx_gallery.gen_gallery",
    "execution_log",  # docs/_ext: a line on stderr per executed example and notebook
    "notebooks_ahead",  # docs/_ext: the notebooks executed two (the cores) at a time
    "offline_timings",  # docs/_ext: the execution-times page without its CDN scripts
    "api_navigation",  # docs/_ext: the API's object pages out of the sidebar
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints",
                    "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5", "examples",
                    "sg_execution_times.rst"]
templates_path = ["_templates"]
suppress_warnings = ["config.cache"]  # sphinx-gallery's callables in the config

# -- HTML ------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"softlanding {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False

# -- MyST / myst-nb --------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
RUN_GALLERY = os.environ.get("SOFTLANDING_DOCS_GALLERY", "1") != "0"
# the test build (tests/conftest.py: docs_site) runs every example even if an earlier build left
# its output in docs/auto_examples (sphinx-gallery skips an example whose checksum it has)
RERUN_GALLERY = os.environ.get("SOFTLANDING_DOCS_RERUN") == "1"
# the notebooks are stored without outputs (tests/test_notebooks.py): executed here, each in
# a temporary folder, a failing cell fails the build (notebooks_ahead.py runs them first, as
# myst-nb's cache mode would, several at a time)
nb_execution_mode = "cache" if RUN_GALLERY else "off"
nb_execution_timeout = 600  # per cell; the longest notebook takes about a minute of CPU in all
nb_execution_in_temp = True
nb_execution_raise_on_error = True
nb_execution_show_tb = True  # the traceback in the log when a cell fails
# A quiet build. The a11y pygments styles (furo's) call logging.basicConfig(level=INFO) on
# import, which would print every library's INFO (nbclient's "Executing notebook ..."): a
# root handler first makes that a no-op and shows warnings only. The kernels (ipykernel 7)
# warn on their stderr that they talk over local TCP unencrypted: only their errors show.
logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
NotebookClient.class_traits()["extra_arguments"].default_value = ["--IPKernelApp.log_level=ERROR"]

# -- autodoc / numpydoc ----------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # numpydoc's Parameters sections say the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False

# -- sphinx-gallery --------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": ["examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r".*\.py$",  # every example is executed
    "plot_gallery": "True" if RUN_GALLERY else "False",
    "run_stale_examples": RERUN_GALLERY,
    "within_subsection_order": "gallery_order.gallery_order",
    "capture_repr": (),  # no "<Figure ...>" under the output
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "abort_on_example_error": True,
    # each example announced on stderr as it runs (docs/_ext/execution_log.py)
    "reset_modules": ("matplotlib", "execution_log.gallery_example"),
    "reset_modules_order": "both",
}

# -- API pages from the front doors ----------------------------------------------------------
FRONT_DOORS = {
    # module: one line for the API index
    "softlanding": "The package's front door: value objects, simulate, every variant's solve.",
    "softlanding.model": "Robot, ground, terrain, controllers, the dynamics, scaling.",
    "softlanding.simulation": "The exact event-driven simulator.",
    "softlanding.optimal": "Optimal landings: the paper's, two-phase, leg extension, hopping.",
    "softlanding.optimal.stance_phases": "A variant's building blocks: the ground modes as "
                                         "phases (yielding, static, flight).",
    "softlanding.control": "Feedback on an unknown ground: stepping plant, estimation, MPC.",
    "softlanding.studies": "Impedance optimisation, sweeps, comparison, robustness, terrain, "
                           "unknown ground.",
    "softlanding.plots": "Figures.",
    "softlanding.report": "The reproduction of the paper (every figure and table).",
    "softlanding.errors": "Every exception of the package.",
    "ocp": "Generic optimal control on CasADi and Ipopt.",
    "ocp.definition": "What a problem is: phases, symbols, bounds, guesses, scaling.",
    "ocp.transcriptions": "Multiple shooting, collocation, the NLP, the solution.",
    "ocp.structure": "Arc structure and switching-time refinement.",
    "ocp.certificate": "Pontryagin's conditions: costates, H, switching functions, verdicts.",
    "ocp.scenarios": "Scenario problems: robust open loop, two-stage trees.",
    "ocp.search": "Many starts: distinct local optima.",
}
HOME_ORDER = ["softlanding.model", "softlanding.simulation", "softlanding.optimal",
              "softlanding.optimal.stance_phases",
              "softlanding.control", "softlanding.studies", "softlanding.plots",
              "softlanding.report", "softlanding.errors", "ocp", "softlanding"]
"""An object exported by several front doors is documented once, under the first here."""


def _exports(modname: str) -> list[str]:
    mod = importlib.import_module(modname)
    names = getattr(mod, "__all__", None)
    if names is None:
        names = [n for n, v in vars(mod).items() if not n.startswith("_")
                 and getattr(v, "__module__", None) == modname]
    return sorted(names, key=lambda n: (n.upper() != n, n.lower()))


def write_api_pages() -> None:
    """One page per front door: its docstring, and a table of its names; each object gets
    its own page under the front door that owns it (the first in ``HOME_ORDER``)."""
    home: dict[int, str] = {}
    for modname in HOME_ORDER:
        mod = importlib.import_module(modname)
        for name in _exports(modname):
            obj = getattr(mod, name)
            home.setdefault(id(obj), f"{modname}.{name}")
    out = DOCS / "api"
    for modname in FRONT_DOORS:
        mod = importlib.import_module(modname)
        own, elsewhere, data = [], [], []
        for name in _exports(modname):
            obj = getattr(mod, name)
            if not (callable(obj) or isinstance(obj, type)):
                data.append(name)
            elif home[id(obj)] == f"{modname}.{name}":
                own.append(name)
            else:
                elsewhere.append(home[id(obj)])
        title = f"``{modname}``"
        lines = [f".. This page is written by docs/conf.py from {modname}.__all__.", "",
                 title, "=" * len(title), "", f".. automodule:: {modname}",
                 "   :no-members:", "", f".. currentmodule:: {modname}", ""]
        if own:
            lines += [".. autosummary::", "   :toctree: generated/", "   :nosignatures:", ""]
            lines += [f"   {n}" for n in own] + [""]
        if elsewhere:
            lines += ["Also exported here (documented where they are defined):", "",
                      ".. autosummary::", "   :nosignatures:", ""]
            lines += [f"   ~{q.removeprefix(modname + '.')}" for q in elsewhere] + [""]
        if data:
            lines += ["Constants", "---------", ""]
            for n in data:
                value = getattr(mod, n)
                lines += [f".. data:: {n}"]
                if home[id(value)] != f"{modname}.{n}":
                    lines += ["   :no-index:"]
                lines += ["", f"   ``{_short_repr(value)}``", ""]
        text = "\n".join(lines)
        path = out / f"{modname}.rst"
        if not path.exists() or path.read_text() != text:
            path.write_text(text)


def _short_repr(value) -> str:
    text = repr(value).replace("`", "'")
    return text if len(text) <= 90 else text[:87] + "..."


write_api_pages()


def _dot_products(app, what, name, obj, options, lines) -> None:
    """Docstrings write a dot product as ``a . b``; autosummary's one-line summaries end a
    sentence at ". ", which would cut such a literal in two: render it as ``a · b``."""
    lines[:] = [ln.replace(" . ", " · ") for ln in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _dot_products, priority=100)
