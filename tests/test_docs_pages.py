"""The teaching pages as a class reads them (fast: the sources only, no build).

The guides typeset their maths, as the notebooks do; no page speaks of the project's
internal history; a guide is read in one sitting; getting started lists every sub-command;
code examples fit the page; the execution-times page loads nothing from the network. The
built site is checked in tests/test_docs.py (slow).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
GUIDES = sorted((DOCS / "guides").glob("*.md"))
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md")), *GUIDES]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))

MAX_GUIDE_WORDS = 6000
"""A guide or reference page a class reads in one sitting (about half an hour)."""


def _prose(text: str) -> list[str]:
    """The lines outside fenced and indented code blocks."""
    out, fenced = [], False
    for ln in text.splitlines():
        if re.match(r"^\s*(```|~~~)", ln):
            fenced = not fenced
        elif not fenced and not ln.startswith("    "):
            out.append(ln)
    return out


def _code_spans(text: str) -> list[str]:
    return [m.group(1) for ln in _prose(text)
            for m in re.finditer(r"(?<![`{}\w])`([^`]+)`(?![`\w])", ln)]


def _all_text() -> list[tuple[str, str]]:
    texts = [(str(p.relative_to(ROOT)), p.read_text()) for p in PAGES]
    for nb in NOTEBOOKS:
        cells = nbformat.read(nb, as_version=4).cells
        texts.append((str(nb.relative_to(ROOT)), "\n".join(c.source for c in cells)))
    return texts


FORMULA = re.compile(r"^(?:[A-Za-z]\w{0,3}|\|\w+\|) *(?:<=|>=|=) *-?[\d.]+$|.* (?:<=|>=) .*")
"""A code span that is a formula: ``v0 = -3``, ``K = 0.5``, ``0 <= x_b - x_f <= s``."""

CODE_ROWS = {"2 * v - 1 <= 0.6", "x - k <= 0", "u - peak <= 0"}
"""Constraints as a user writes them in Python (ocp guide): code, not formulas."""


@pytest.mark.parametrize("page", [*GUIDES, DOCS / "getting_started.md"],
                         ids=lambda p: p.name)
def test_the_guides_typeset_their_maths(page):
    spans = [s for s in _code_spans(page.read_text()) if FORMULA.match(s)
             and not s.startswith(("softlanding ", "-", "python ")) and s not in CODE_ROWS]
    assert not spans, f"formulas written as code (use $...$): {spans[:10]}"


def test_the_docs_enable_dollar_maths():
    conf = (DOCS / "conf.py").read_text()
    extensions = re.search(r"myst_enable_extensions = \[(.*?)\]", conf).group(1)
    assert '"dollarmath"' in extensions and '"amsmath"' in extensions


def test_no_page_speaks_of_internal_history():
    internal = re.compile(r"\bstop \d+\b|\bissue \d+\b|\bhelper's\b|\bsession\b", re.I)
    found = [(name, m.group(0)) for name, text in _all_text()
             for m in internal.finditer(text)]
    assert not found, found


def test_a_guide_is_read_in_one_sitting():
    words = {p.name: len(p.read_text().split()) for p in GUIDES}
    assert max(words.values()) <= MAX_GUIDE_WORDS, words
    assert words["unknown_ground.md"] <= 2500, words  # the short guide; its details split off


def test_getting_started_lists_every_sub_command():
    from softlanding.cli.commands import HANDLERS
    from softlanding.cli.output import CliParser
    from softlanding.cli.parser import build_parser

    parser = build_parser(HANDLERS, CliParser, [])
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    table = [ln for ln in (DOCS / "getting_started.md").read_text().splitlines()
             if ln.startswith("| `")]
    listed = {re.match(r"\| `([\w-]+)` \| (.+?) \|", ln).group(1): ln for ln in table}
    assert set(sub.choices) <= set(listed), set(sub.choices) - set(listed)
    for name in sub.choices:  # each with its purpose in a line
        assert len(listed[name].split("|")[2].split()) >= 4, listed[name]


def test_code_examples_fit_the_page():
    """Python and indented command blocks wrap at 90 columns (a command's printed output is
    shown as the command prints it, wrapped on the page by docs/_static/custom.css)."""
    long = []
    for page in PAGES[1:]:  # README.md is GitHub's page
        lines, lang = page.read_text().splitlines(), None
        for i, ln in enumerate(lines):
            m = re.match(r"^\s*(```|~~~)\s*(\S*)", ln)
            if m:
                lang = None if lang is not None else m.group(2)
            elif (lang == "python" or lang is None and ln.startswith("    ")) and len(ln) > 90:
                long.append(f"{page.name}:{i + 1}")
    assert not long, long
    assert "pre-wrap" in (DOCS / "_static" / "custom.css").read_text()


def test_the_execution_times_page_loads_nothing_remote(tmp_path):
    """sphinx-gallery's own page, as it writes it, read through docs/_ext/offline_timings."""
    from sphinx_gallery.gen_gallery import write_computation_times
    from sphinx_gallery.gen_rst import ExampleCost

    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        from offline_timings import plain
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    src = tmp_path / "plot_one.py"
    src.write_text("")
    write_computation_times({"write_computation_times": True, "src_dir": str(tmp_path)},
                            str(tmp_path), [ExampleCost(1.5, 0.0, str(src), str(tmp_path))])
    raw = (tmp_path / "sg_execution_times.rst").read_text()
    assert "https://" in raw  # what sphinx-gallery writes: its scripts from CDNs
    page = plain(raw)
    assert "http" not in page and "<script" not in page
    assert ".. list-table::" in page and "plot_one.py" in page  # the table stays
