"""The README's commands print what the README shows.

Convention: a fenced ``console`` block holds commands, each a line ``$ softlanding ...``,
followed by the output it prints (stdout and stderr, in order); a line ``...`` stands for any
number of lines. Each command is run (``python -m softlanding``, so exit codes are real) and
its output compared line by line, after masking the values of the volatile rows named in
``VOLATILE``. A fenced ``pycon`` block is run as a doctest. Only cheap commands belong in the
README (each of these takes a second or two).

Numbers in the README's prose, outside those blocks, and the test that checks each:

* ``u_max = 8.2``, ``r_m = 5, s = 20`` (the paper's robot): test_prose_numbers_are_the_models;
* ``Python 3.11``: test_prose_numbers_are_the_models (``requires-python``);
* exit codes 2 (bad input), 1 (failed or not verified), 3 (a bug):
  test_prose_numbers_are_the_models (``softlanding.cli.output``), and exit 2 again by the
  bad-input block's run in test_console_block.
"""

import doctest
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"

VOLATILE = {
    # row label -> why its value is masked
    "solve time [s]": "wall-clock time of the solve",
    "replay difference": "rounding-level difference (1e-16 .. 1e-15), machine dependent",
}
"""Rows whose value is not compared (the row itself must still be there)."""


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```", README.read_text(), re.M | re.S)


def _commands() -> list[tuple[str, list[str]]]:
    out = []
    for block in _blocks("console"):
        for chunk in re.split(r"^(?=\$ )", block, flags=re.M):
            if chunk.strip():
                first, *rest = chunk.rstrip("\n").split("\n")
                out.append((first[2:], rest))
    return out


def _mask(line: str) -> str:
    for label in VOLATILE:
        if line.startswith(label + " "):
            return label + " <masked>"
    return line.rstrip()


def _matches(expected: list[str], actual: list[str]) -> bool:
    """Line by line; ``...`` matches any run of lines (possibly none)."""
    if not expected:
        return not actual
    if expected[0] == "...":
        return any(_matches(expected[1:], actual[i:]) for i in range(len(actual) + 1))
    return bool(actual) and _mask(expected[0]) == _mask(actual[0]) \
        and _matches(expected[1:], actual[1:])


COMMANDS = _commands()


def test_the_readme_is_a_front_page():
    assert len(README.read_text().splitlines()) <= 250
    assert COMMANDS and _blocks("pycon")


@pytest.mark.parametrize("command, expected", COMMANDS, ids=[c for c, _ in COMMANDS])
def test_console_block(command, expected):
    assert command.startswith("softlanding "), command
    args = command.split()[1:]
    res = subprocess.run([sys.executable, "-m", "softlanding", *args], capture_output=True,
                         text=True, cwd=ROOT, timeout=300)
    actual = (res.stdout + res.stderr).rstrip("\n").split("\n")
    assert _matches(expected, actual), "\n".join(["README:", *expected, "printed:", *actual])
    assert res.returncode == (2 if any(": error: " in ln for ln in expected) else 0)
    for line in actual:  # a masked value still says something
        if line.startswith("replay difference "):
            assert float(line.split()[-1]) < 1e-12


def test_python_block():
    parser = doctest.DocTestParser()
    for i, block in enumerate(_blocks("pycon")):
        test = parser.get_doctest(block, {}, f"README pycon block {i}", str(README), 0)
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
        runner.run(test)
        assert runner.failures == 0, f"README pycon block {i} failed (see output above)"


def test_relative_links_exist():
    for target in re.findall(r"\]\(([^)#:]+)\)", README.read_text()):
        assert (ROOT / target).exists(), target


def test_prose_numbers_are_the_models():
    from softlanding import PAPER_ROBOT
    from softlanding.cli import output

    assert (PAPER_ROBOT.r_m, PAPER_ROBOT.s, PAPER_ROBOT.u_max) == (5, 20, 8.2)
    assert (output.EXIT_BAD_INPUT, output.EXIT_FAILURE, output.EXIT_BUG) == (2, 1, 3)
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["requires-python"] == ">=3.11"
    text = README.read_text()
    for claim in ("u_max = 8.2", "r_m = 5, s = 20", "Python 3.11", "exit code 2"):
        assert claim in text, claim


def test_citation_file_names_the_paper_and_this_version():
    from softlanding._version import __version__

    cff = (ROOT / "CITATION.cff").read_text()
    assert f'version: "{__version__}"' in cff
    tex = ROOT.parent.parent / "shared" / "paper" / "soft-landing-problem.tex"
    assert "The Soft Landing Problem: Minimizing Energy Loss by a Legged Robot Impacting " \
           "Yielding Terrain" in cff
    if tex.exists():  # the paper's source, beside the repository where it is checked out
        assert "The Soft Landing Problem" in tex.read_text()


def test_ci_runs_exactly_the_readmes_test_commands():
    """A fresh Debian or Ubuntu refuses ``pip install`` outside a virtual environment: the
    README's set-up makes one, and ``.ci/run`` runs the README's two test commands verbatim."""
    setup = README.read_text().split("## Set-up", 1)[1].split("\n## ", 1)[0]
    commands = [ln.strip() for ln in setup.splitlines() if ln.startswith("    ")]
    tests = [c for c in commands if "pytest" in c]
    assert len(tests) == 2 and all(c.startswith("python3 -m venv .venv && . .venv/bin/activate")
                                   for c in commands if "pip install" in c)
    ci = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert [ln for ln in ci if "pytest" in ln and ln != OCP_ALONE] == tests
    assert ci.count(OCP_ALONE) == 1  # and the ocp-only job, once


OCP_ALONE = ('python -m pytest -p tests.ocp_alone tests/ocp -m "not slow" '
             '-k "test_ocp.py or test_pmp.py or test_layout.py" -q -p no:cacheprovider')
"""The ocp-only job of ``.ci/run``: tests/ocp collected with softlanding unimportable, three
quick files run (issue 46)."""
