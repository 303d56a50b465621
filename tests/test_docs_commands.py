"""Every ``softlanding ...`` command the README and the documentation show runs as written.

The commands are read from the pages (README.md, docs/*.md, docs/guides/*.md):

* a line ``$ softlanding ...`` in a fenced block, followed by the output it prints (``...``
  stands for any number of lines, as in tests/test_readme.py);
* a command in an indented block (``... && softlanding demo``);
* an inline code span ```softlanding ...``` in the prose or a figure's caption. Optional
  parts in brackets (``[--pmp]``) are read both with and without them; placeholders in
  capitals (``DIR``, ``FILE.png``, ``mymodule:VARIANT``) are replaced by the example values
  of :data:`PLACEHOLDERS` (an unknown one fails the test: add it there). A sub-command named
  without its required options (```softlanding hop```) is a name, not a command: it is
  completed with :data:`REQUIRED` and parsed.

Every command is parsed by the CLI's own parser, in-process (fast: an argument error such as
``--plot`` without its file is caught without running anything). Each cheap one shown with
its output (in a block or a caption) is also run, in a temporary folder, and its exit code
and output compared with what the page shows (``slow``); a command shown on several pages runs
once per test run (the ``console`` fixture of tests/conftest.py), each page's output compared
with it, and ``reproduce --out paper --quick`` is the same run tests/softlanding/report read.
The expensive ones (:data:`EXPENSIVE`, with their measured cost) are parsed only.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import json
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.test_readme import _mask, _matches

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
         *sorted((ROOT / "docs" / "guides").glob("*.md"))]

PLACEHOLDERS = {
    "DIR": "out-dir", "FILE": "file.png", "FILE.png": "file.png", "F": "file.png",
    "NAME": "two-phase", "S": "1e-3", "N": "1", "P": "1.29026202654",
    "mymodule:VARIANT": "softlanding.optimal.min_peak_force:VARIANT",
}
"""Example values of the placeholders the pages write in capitals."""

REQUIRED = {"--v0": "-3", "--out": "out"}
"""Values that complete a sub-command named without its required options."""

EXPENSIVE = {
    # command as shown -> why it is parsed only (CPU time measured on 2 shared cores)
}
"""Commands shown with their output that the tests parse but do not run."""

VOLATILE = (
    re.compile(r"^(solve time \[s\]) .*"),  # the solve's wall-clock time
    re.compile(r"^(replay difference) .*"),  # rounding level, machine dependent
    re.compile(r"^(\[\d+/\d+\] \S.*?)\s+\d+(\.\d+)? s$"),  # a section's duration (reproduce)
    re.compile(r"^(\d+ files written to .*); total \d+(\.\d+)? s$"),  # the run's duration
)


@dataclass(frozen=True)
class Shown:
    """A command as a page shows it."""

    page: str
    line: int
    text: str  # as written (placeholders and optional parts included)
    output: tuple[str, ...] | None  # the output shown with it, if any
    caption: str = ""  # the figure's caption the command is in (the command drew it)

    def __str__(self) -> str:
        return f"{self.page}:{self.line}: {self.text}"


def _fences(lines: list[str]) -> list[tuple[int, int, str]]:
    """(first, last, info) line indices of the fenced blocks (``` or ~~~)."""
    out, start, info = [], None, ""
    for i, ln in enumerate(lines):
        m = re.match(r"^(```+|~~~+)\s*(.*)$", ln)
        if m is None:
            continue
        if start is None:
            start, info = i, m.group(2)
        elif not m.group(2):
            out.append((start, i, info))
            start = None
    return out


def _block_commands(page: str, lines: list[str], first: int, last: int) -> list[Shown]:
    out: list[Shown] = []
    body = lines[first + 1:last]
    starts = [i for i, ln in enumerate(body) if ln.startswith("$ ")]
    for k, i in enumerate(starts):
        text = re.sub(r"\s+#.*$", "", body[i][2:]).strip()
        if not text.startswith("softlanding "):
            continue
        end = starts[k + 1] if k + 1 < len(starts) else len(body)
        out.append(Shown(page, first + 2 + i, text, tuple(body[i + 1:end])))
    return out


def shown_commands() -> list[Shown]:
    """Every ``softlanding`` command of the pages, in page order."""
    found: list[Shown] = []
    for path in PAGES:
        page = str(path.relative_to(ROOT))
        lines = path.read_text().splitlines()
        fences = _fences(lines)
        code = set()  # lines of code blocks and fence markers; a directive's body is prose
        captions: dict[int, int] = {}  # line of a figure caption -> its first line
        for first, last, info in fences:
            if info.startswith("{"):  # a MyST directive ({figure}): its caption is prose
                code.update((first, last))
                if info.startswith("{figure}"):
                    captions.update(dict.fromkeys(range(first, last), first))
            else:
                code.update(range(first, last + 1))
                found += _block_commands(page, lines, first, last)
        prose = ["" if i in code else ln for i, ln in enumerate(lines)]
        for i, ln in enumerate(prose):  # Markdown: the paragraph after an image
            if ln.startswith("![") and i + 2 < len(prose) and not prose[i + 1].strip():
                j = i + 2
                while j < len(prose) and prose[j].strip():
                    captions[j] = i + 2
                    j += 1
        for i, ln in enumerate(prose):
            if ln.startswith("    ") and "softlanding " in ln:  # an indented command
                for part in ln.split("&&"):
                    if part.strip().startswith("softlanding "):
                        found.append(Shown(page, i + 1, part.strip(), None))
        text = "\n".join(ln if not ln.startswith("    ") else "" for ln in prose)
        for m in re.finditer(r"`(softlanding\s[^`]*)`", text):
            line = text.count("\n", 0, m.start())
            caption = " ".join(ln for k, ln in enumerate(prose)
                               if line in captions and captions.get(k) == captions[line])
            found.append(Shown(page, line + 1, " ".join(m.group(1).split()), None, caption))
    return found


def expand(text: str) -> list[list[str]]:
    """The argument lists a shown command stands for (without ``softlanding``)."""
    text = text.replace("...", " ")
    parts = re.split(r"\[([^\]]*)\]", text)  # odd entries: the optional groups
    variants = []
    for keep in itertools.product((False, True), repeat=len(parts) // 2):
        variants.append("".join(p if i % 2 == 0 or keep[i // 2] else ""
                                for i, p in enumerate(parts)))
    out = []
    for v in dict.fromkeys(variants):
        args = []
        for tok in v.split()[1:]:
            if tok in PLACEHOLDERS:
                tok = PLACEHOLDERS[tok]
            assert not re.fullmatch(r"[A-Z][A-Z_.]*", tok) or tok.startswith("--"), \
                f"placeholder {tok!r} of {text!r}: add an example value to PLACEHOLDERS"
            args.append(tok)
        out.append(args)
    return out


def parse(args: list[str]) -> tuple[int, str]:
    """Exit code (0: parsed) and message of the CLI's parser on ``args``, in-process."""
    from softlanding.cli.commands import HANDLERS
    from softlanding.cli.output import CliParser
    from softlanding.cli.parser import build_parser

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            build_parser(HANDLERS, CliParser, args).parse_args(args)
        except SystemExit as e:
            return int(e.code or 0), err.getvalue().strip()
    return 0, ""


SHOWN = shown_commands()


def test_the_pages_show_commands():
    pages = {s.page for s in SHOWN}
    assert {"README.md", "docs/index.md", "docs/getting_started.md",
            "docs/guides/landing.md", "docs/guides/hybrid.md"} <= pages
    assert sum(s.output is not None for s in SHOWN) >= 30, len(SHOWN)


@pytest.mark.parametrize("shown", SHOWN, ids=str)
def test_the_cli_parses_the_command(shown):
    expect_error = any(": error: " in ln for ln in shown.output or ())
    for args in expand(shown.text):
        code, message = parse(args)
        missing = re.search(r"the following arguments are required: (.*)$", message)
        if missing and shown.output is None:  # a sub-command named, not a command
            for opt in missing.group(1).split(", "):
                args += [opt, REQUIRED[opt]]
            code, message = parse(args)
        if expect_error and code == 2:
            continue  # a usage error shown as one (checked against its text when run)
        assert code == 0, f"{shown}\n{message}"


def expected_exit(output: tuple[str, ...]) -> int:
    """The exit code an output implies: 2 for a usage error, 1 for a failure reported on
    one line (``softlanding: infeasible: ...``, not ``softlanding: warning: ...``) or a result
    not verified, else 0."""
    if any(": error: " in ln for ln in output):
        return 2
    failure = [ln for ln in output if ln.startswith("softlanding: ")
               and not ln.startswith("softlanding: warning: ")]  # a warning does not fail
    if failure or any(ln.startswith("verified ") and " NO: " in ln for ln in output):
        return 1
    return 0


def _masked(lines) -> list[str]:
    out = []
    for ln in lines:
        for pattern in VOLATILE:
            ln = pattern.sub(r"\1 <masked>", ln)
        out.append(_mask(ln))
    return out


def _json(lines) -> object:
    """The object or array ``lines`` hold as one JSON document (None if they hold none)."""
    try:
        value = json.loads("\n".join(lines))
    except ValueError:
        return None
    return value if isinstance(value, (dict, list)) else None


FIRST_COMPILE = re.compile(r"softlanding: compiling .* \(once, about \d+ s\)\.\.\.$")
"""The line a first compile prints (softlanding.simulation.kernel.first_compile): on a cold
cache only, so a page does not show it."""

RUN = [s for s in SHOWN if (s.output is not None or s.caption) and s.text not in EXPENSIVE]


@pytest.mark.slow
@pytest.mark.parametrize("shown", RUN, ids=str)
def test_the_command_prints_what_the_page_shows(shown, console):
    [args] = expand(shown.text)
    res, _ = console(*args)  # a command two pages show runs once
    printed = [ln for ln in (res.stdout + res.stderr).rstrip("\n").split("\n")
               if not FIRST_COMPILE.match(ln)]  # a cold numba cache's notices: not the page's
    output = shown.output or ("...",)
    assert res.returncode == expected_exit(output), f"{shown}\n" + "\n".join(printed)
    assert not [ln for ln in printed if "WARNING(" in ln], printed  # no CasADi message
    shown_json = _json(output)
    if shown_json is not None:  # a JSON document, wrapped on the page: the same value
        assert _json(printed) == shown_json, \
            "\n".join([str(shown), "page:", *output, "printed:", *printed])
        return
    assert _matches(_masked(output), _masked(printed)), \
        "\n".join([str(shown), "page:", *output, "printed:", *printed])
    arcs = re.search(r"arcs `([^`]*)`", shown.caption)
    if shown.caption:  # the caption says which arcs the figure shows: the ones printed
        assert arcs and f"arcs {arcs.group(1)}" in [" ".join(ln.split()) for ln in printed]
