"""The documentation site builds with warnings as errors (``make -C docs html``).

The full build executes the gallery (docs/examples; about 50 s with the API pages on 2
cores, numba's kernels already compiled) and the seven teaching notebooks (one per core, at
most four, at a time: docs/_ext/notebooks_ahead.py; a few seconds to about a minute of CPU
each; the whole build took about 6 min CPU on a 2-core machine loaded 4-fold), so it is
``slow`` (CI runs it with the second test command). The build is the ``docs_site`` fixture of
tests/conftest.py: tests/test_notebooks.py checks the notebooks as this build executed them.
A structural check of every page, docstring and cross-reference without executing the gallery
or the notebooks takes about 15 s, too much for the fast suite; run it locally with
``SOFTLANDING_DOCS_GALLERY=0 make -C docs dummy``.
"""

import re

import pytest


@pytest.mark.slow
def test_the_site_builds_with_its_gallery_executed(docs_site):
    res, out = docs_site  # built once per test run; tests/test_notebooks.py reads its notebooks
    assert res.returncode == 0, res.stderr[-4000:]
    html = out / "html"
    for page in ("index.html", "getting_started.html", "guides/landing.html",
                 "guides/ocp_scenarios.html", "api/softlanding.html", "api/ocp.html",
                 "auto_examples/index.html", "auto_examples/fastest_arrest.html",
                 "notebooks/01_model_scaling_modes.html"):
        assert (html / page).is_file(), page
    # every gallery example ran and left its figure
    figures = list((html / "_images").glob("sphx_glr_plot_*_001.png"))
    assert len(figures) >= 6, figures
    api = (html / "api" / "generated" / "softlanding.model.Robot.html").read_text()
    assert "r_m" in api and "Parameters" in api
    # the sidebar lists the module pages, not the ~230 object pages (docs/_ext/api_navigation:
    # half of the build's CPU went into rendering them into every page); the module's table
    # links them
    nav = re.findall(r'<li class="toctree-l\d[^"]*"><a class="reference internal" '
                     r'href="([^"]*)"', api)
    assert "../softlanding.model.html" in nav and not [h for h in nav if "generated/" in h]
    assert 'href="generated/softlanding.model.Robot.html' in \
        (html / "api" / "softlanding.model.html").read_text()
    # the notebooks are executed at build: their pages show the figures
    nb = (html / "notebooks" / "07_unknown_ground.html").read_text()
    assert nb.count("<img") >= 4
    # MathJax is bundled, no page loads it from the network
    assert (html / "_static" / "mathjax" / "tex-chtml.js").is_file()
    maths = (html / "notebooks" / "01_model_scaling_modes.html").read_text()
    assert "_static/mathjax/tex-chtml.js" in maths and "cdn.jsdelivr" not in maths
    # the guide's code names link to their API pages
    guide = (html / "guides" / "unknown_ground.html").read_text()
    assert "generated/softlanding.control.GroundEstimator.html" in guide
    # no CasADi message on any page (a notebook's cell printed 22 lines of them)
    pages = [p for p in html.rglob("*.html")]
    assert not [p for p in pages if "WARNING(" in p.read_text(errors="replace")]
    # nothing from the network: no script or style sheet of another site (the execution
    # times page loaded jQuery and DataTables from CDNs)
    remote = re.compile(r'<(?:script|link)\b[^>]*\b(?:src|href)="(?:https?:)?//', re.I)
    assert not [p for p in pages if remote.search(p.read_text(errors="replace"))]
    assert (html / "auto_examples" / "sg_execution_times.html").is_file()
    # quiet: nothing printed but warnings (none: -W), errors and a line per executed example
    # and notebook (docs/_ext/execution_log.py); a notebook kernel's teardown noise (tornado
    # logging a ZMQ socket closed under it) is not the docs'
    err = re.sub(r"ERROR:tornado\.general:Uncaught exception in ZMQStream callback\n"
                 r"(?:.*\n)*?zmq\.error\.ZMQError: Socket operation on non-socket\n?", "",
                 res.stderr)
    said = [ln for ln in err.splitlines() if ln.startswith("docs: ")]
    assert sum("executing the gallery example" in ln for ln in said) >= 6, said
    assert sum("executing the notebook" in ln for ln in said) == 7, said
    assert sum(" done in " in ln for ln in said) == 7, said
    # run ahead, several at a time (docs/_ext/notebooks_ahead.py): none failed there and was
    # left to myst-nb to run again
    ahead = [ln for ln in said if ln.startswith("docs: ran ")]
    assert all(re.search(r" in [0-9.]+ s$", ln) for ln in ahead), ahead
    err = "\n".join(ln for ln in err.splitlines() if not ln.startswith("docs: "))
    assert not res.stdout.strip() and not err.strip(), (res.stdout + err)[-4000:]

