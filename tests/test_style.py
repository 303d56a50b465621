"""The code base is ruff-clean (the README's test command) and type-checks (its slow
command); ruff and mypy are in [test]. Its modules and functions stay small, and ``ocp``
(and its tests) never import ``softlanding`` (issue 46 item 5)."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_clean():
    p = subprocess.run([sys.executable, "-m", "ruff", "check", str(ROOT)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr


@pytest.mark.slow  # about 25 s CPU on a cold cache, as CI runs it
def test_mypy_clean():
    """The type checker passes on softlanding and ocp (configured in pyproject.toml)."""
    p = subprocess.run([sys.executable, "-m", "mypy", "--no-error-summary"], cwd=ROOT,
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr


# ------------------------------------------------------------------ sizes (issue 46 item 5)
MAX_MODULE_LINES = 800
MAX_FUNCTION_CODE_LINES = 80
PACKAGES = ("softlanding", "ocp")

# Offenders tolerated, each with its reason (none now). An entry that no longer offends fails
# the test too, so the list cannot outlive its reason.
SIZE_ALLOWED: set[str] = set()


def code_lines(source_lines: list[str], node: ast.AST) -> int:
    """Lines of a function that hold code: blank lines, comment lines and its docstring
    aside (a nested function's lines count in the function that holds it)."""
    body = node.body  # type: ignore[attr-defined]
    doc = range(0)
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        doc = range(body[0].lineno, body[0].end_lineno + 1)
    first = min([node.lineno, *[d.lineno for d in node.decorator_list]])  # type: ignore[attr-defined]
    return sum(1 for i in range(first, node.end_lineno + 1)  # type: ignore[attr-defined]
               if i not in doc and source_lines[i - 1].strip()
               and not source_lines[i - 1].strip().startswith("#"))


def size_offenders() -> dict[str, str]:
    """``{"path" or "path:function": what}`` for every module over 800 lines and every
    function over 80 code lines in softlanding/ and ocp/."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            text = path.read_text()
            lines = text.splitlines()
            if len(lines) > MAX_MODULE_LINES:
                out[rel] = f"{len(lines)} lines"
            for node in ast.walk(ast.parse(text)):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    n = code_lines(lines, node)
                    if n > MAX_FUNCTION_CODE_LINES:
                        out[f"{rel}:{node.name}"] = f"{n} code lines (line {node.lineno})"
    return out


def test_no_module_over_800_lines_nor_function_over_80_code_lines():
    """Small modules with one job each (the developer guide; issue 46 item 5)."""
    found = size_offenders()
    offenders = {k: v for k, v in found.items() if k not in SIZE_ALLOWED}
    assert not offenders, "split these by role:\n" + "\n".join(
        f"  {k}: {v}" for k, v in sorted(offenders.items()))
    stale = sorted(SIZE_ALLOWED - set(found))
    assert not stale, f"no longer over the limits, remove from SIZE_ALLOWED: {stale}"


def test_code_lines_leave_out_docstring_comments_and_blanks():
    src = ('def f(x):\n    """Doc.\n\n    More.\n    """\n    # why\n\n'
           '    y = (x +\n         1)\n    return y\n')
    (node,) = ast.parse(src).body
    assert code_lines(src.splitlines(), node) == 4  # def, two lines of y, return


# ------------------------------------------------- ocp without softlanding (issue 46 item 5)
def imported_modules(path: Path) -> set[str]:
    """Every module a file imports (lazy imports in functions included), absolute names;
    ``importlib.import_module("...")`` with a literal name counts as an import."""
    tree = ast.parse(path.read_text())
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[:len(package.split(".")) - node.level + 1] \
                if node.level else []
            mod = ".".join([*base, *([node.module] if node.module else [])])
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "import_module" \
                and node.args and isinstance(node.args[0], ast.Constant):
            out.add(str(node.args[0].value))
    return out


def project_file(module: str) -> Path | None:
    """The file of a module of this repository's tests (``tests.oracles.x``), if any."""
    parts = module.split(".")
    for p in (ROOT.joinpath(*parts).with_suffix(".py"), ROOT.joinpath(*parts, "__init__.py")):
        if parts[0] == "tests" and p.is_file():
            return p
    return None


def test_ocp_and_its_tests_never_import_softlanding():
    """``ocp`` knows nothing of landing, and ``tests/ocp`` runs without softlanding
    (followed through the test helpers they import, e.g. tests/oracles)."""
    todo = [*sorted((ROOT / "ocp").rglob("*.py")), *sorted((ROOT / "tests" / "ocp").rglob("*.py"))]
    seen: set[Path] = set()
    bad = []
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen.add(path)
        mods = imported_modules(path)
        for mod in mods:
            # ("from a import b" gives a and a.b: a is named)
            if mod.split(".")[0] == "softlanding" and mod.rpartition(".")[0] not in mods:
                bad.append(f"{path.relative_to(ROOT)} imports {mod}")
            helper = project_file(mod)
            if helper is not None:
                todo.append(helper)
    assert not bad, "\n".join(sorted(bad))


def test_the_ocp_alone_plugin_blocks_softlanding():
    """The plugin of the ocp-only CI job makes softlanding unimportable (not a vacuous job)."""
    code = ("import tests.ocp_alone, importlib\n"
            "try:\n    importlib.import_module('softlanding.optimal')\n"
            "except ModuleNotFoundError as e:\n    print('blocked', e.name)\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 0 and p.stdout.split() == ["blocked", "softlanding"], \
        p.stdout + p.stderr
