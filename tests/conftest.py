import os

import pytest


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


@pytest.fixture(autouse=True, scope="session")
def _no_compile_notice(request):
    """The simulator's first-compile notice (stderr, once per process, cold cache only) would
    land in whichever test compiles first; tests/softlanding/simulation/test_first_run.py runs
    it in subprocesses of its own. The ocp-only job (``-p tests.ocp_alone``) has no simulator."""
    if request.config.pluginmanager.has_plugin("tests.ocp_alone"):
        return
    from softlanding.simulation import kernel

    kernel._CHECKED.update({"affine", "non-affine"})


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
