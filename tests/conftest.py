import contextlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.parallel import assign_groups, require_group_tags, require_loadgroup

# One thread per batch of landings in the tests (before numba is imported, and inherited by
# every process a test starts: the CLI's, the documentation's notebooks): the second command
# already runs one worker per core, and on this 2-core machine a second thread per batch costs
# CPU: 7 % on one large affine batch (benchmarks/bench_batch_threads.py, 1.8x faster on an idle
# machine), 10-30 % on a study's many small ones (notebook 03's robustness study: 11.7 to 12.3 s
# CPU on one thread, 14.1 to 15.7 s on two, 12 % faster), and it saves no time on busy cores.
# The results do not depend on it (tests/softlanding/simulation/test_batch_threads.py checks
# a batch on three threads against the one-thread batch, bit for bit).
os.environ.setdefault("NUMBA_NUM_THREADS", "1")


@pytest.fixture
def cli(capsys):
    """Run ``softlanding ARGS`` in-process: returns (exit code, stdout, stderr)."""
    from softlanding.cli import main

    def run(*args):
        try:
            code = main([str(a) for a in args])
        except SystemExit as e:  # argparse usage errors, --help, --version
            code = e.code
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture(scope="session")
def console(tmp_path_factory):
    """Run ``python -m softlanding ARGS`` (a real process: real exit codes, the console's
    output) in a fresh folder, once per test run for each argument list: returns the
    completed process and its folder. The documentation shows some commands on two pages,
    and ``reproduce --out paper --quick`` (about 3 minutes of CPU) is both a page's command
    (tests/test_docs_commands.py) and the run whose files tests/softlanding/report read.
    Outputs are only read; a run that timed out is not run again (its error is raised to
    every test that reads it)."""
    done: dict[tuple[str, ...], object] = {}

    def run(*args):
        key = tuple(str(a) for a in args)
        if key not in done:
            cwd = tmp_path_factory.mktemp("console")
            env = dict(os.environ, COLUMNS="100")
            try:  # a hang guard only: reproduce --quick took over 20 min wall on 2 loaded cores
                res = subprocess.run([sys.executable, "-m", "softlanding", *key],
                                     capture_output=True, text=True, cwd=cwd, timeout=3600,
                                     env=env)
                done[key] = (res, cwd)
            except subprocess.TimeoutExpired as err:
                done[key] = err
        if isinstance(done[key], Exception):
            raise done[key]
        return done[key]

    return run


@pytest.fixture(scope="session")
def docs_site(tmp_path_factory):
    """The documentation site built once per test run, its gallery and its seven notebooks
    executed (``sphinx -W --keep-going -b html``): returns the completed build and its folder
    (``html``, ``doctrees``, and ``jupyter_execute``, where myst-nb writes each notebook as it
    executed it). tests/test_docs.py checks the site, tests/test_notebooks.py the executed
    notebooks: each notebook runs once, not once per file."""
    out = tmp_path_factory.mktemp("docs")
    # no MPLBACKEND: the notebooks' kernels inherit it, and under Agg their figures are not
    # shown inline (conf.py selects Agg for the build's own process)
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    env["SOFTLANDING_DOCS_GALLERY"] = "1"
    env["SOFTLANDING_DOCS_RERUN"] = "1"  # every example, whatever docs/auto_examples holds
    docs = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")
    res = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                          "html", "-d", str(out / "doctrees"), docs, str(out / "html")],
                         capture_output=True, text=True, env=env, timeout=2400)
    return res, out


@pytest.fixture(autouse=True, scope="session")
def _no_compile_notice(request):
    """The simulator's first-compile notices (stderr, once per process and kernel entry, cold
    cache only) would land in whichever test compiles first (the batch loop's broke the first
    map test of tests/softlanding/cli/test_output_files.py run alone on a cold cache);
    tests/softlanding/simulation/test_first_run.py runs them in subprocesses of its own. The
    ocp-only job (``-p tests.ocp_alone``) has no simulator."""
    if request.config.pluginmanager.has_plugin("tests.ocp_alone"):
        return
    from softlanding.simulation import kernel

    kernel._CHECKED.update(kernel.FIRST_COMPILE)  # every entry's notice


# The bytecode of softlanding and ocp, compiled once per test run where Python does not write
# it (PYTHONDONTWRITEBYTECODE): each process a test starts (the CLI's, the documentation's
# notebooks and commands, dozens) would otherwise compile the package's sources again, about
# 0.3 s of CPU each (`python -m softlanding solve --v0 -3`: 1.75 s, 1.45 s with the bytecode).
# At the run's end the files it wrote are removed, and the __pycache__ folders it made if
# they are empty (numba's cache may have moved in): nothing is left behind.
PACKAGES = ("softlanding", "ocp")
WROTE = pytest.StashKey[tuple[list[Path], list[Path]]]()


def pytest_sessionstart(session):
    """The packages' bytecode written beside their sources, if Python does not write it
    (once, in the main process: not in a pytest-xdist worker)."""
    if not sys.flags.dont_write_bytecode or hasattr(session.config, "workerinput"):
        return
    import compileall
    import importlib.util

    root = Path(__file__).resolve().parents[1]
    caches = [Path(importlib.util.cache_from_source(str(f)))
              for pkg in PACKAGES for f in (root / pkg).rglob("*.py")]
    # recorded before compiling: an interrupted compile is cleaned up too
    files = [c for c in caches if not c.exists()]
    folders = sorted({c.parent for c in files if not c.parent.exists()}, reverse=True)
    session.config.stash[WROTE] = (files, folders)
    for pkg in PACKAGES:
        compileall.compile_dir(root / pkg, quiet=2)  # (a read-only tree: nothing written)


def pytest_sessionfinish(session):
    """The bytecode :func:`pytest_sessionstart` wrote, and the folders it made, removed."""
    files, folders = session.config.stash.get(WROTE, ([], []))
    for f in files:
        f.unlink(missing_ok=True)
    for d in folders:
        with contextlib.suppress(OSError):  # not empty: another cache lives there now
            d.rmdir()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """With ``SOFTLANDING_TEST_CPU=FILE``, each test's CPU seconds (setup, call and teardown,
    its subprocesses included) appended to FILE: the README's budget is CPU, which pytest's
    ``--durations`` (wall) does not show on a shared machine."""
    path = os.environ.get("SOFTLANDING_TEST_CPU")
    if not path:
        yield
        return
    t0 = os.times()
    yield
    t1 = os.times()
    cpu = sum(b - a for a, b in zip(t0[:4], t1[:4], strict=True))
    with open(path, "a") as f:
        f.write(f"{cpu:.2f}\t{item.nodeid}\n")


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook, which reads the groups' marks
def pytest_collection_modifyitems(config, items):
    """On a pytest-xdist worker (the second test command's ``-n 2 --dist loadgroup``), the
    tests grouped by what they share and the longest groups first (tests/parallel.py)."""
    if hasattr(config, "workerinput"):
        items[:] = assign_groups(items)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_node_collection_finished(node, ids):
    """Every test a worker collected tagged with its group, or the run stopped (pytest-xdist
    3.8 under pytest 9.2 drops the tags silently: pytest-xdist#1386)."""
    require_group_tags(ids)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """One group per worker at a time, in the order tests/parallel.py gives (xdist would
    otherwise put the groups with the most tests first, not the longest). Refused without
    ``--dist loadgroup``: xdist then ignores the groups (it tags a test with its group only in
    that mode), and two workers would each build what a group shares."""
    from xdist.scheduler import LoadGroupScheduling

    require_loadgroup(config.getvalue("dist"))
    config.option.loadscopereorder = False
    return LoadGroupScheduling(config, log)
