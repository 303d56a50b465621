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
def _no_compile_notice():
    """The simulator's first-compile notice (stderr, once per process, cold cache only) would
    land in whichever test compiles first; tests/softlanding/simulation/test_first_run.py runs
    it in subprocesses of its own."""
    from softlanding.simulation import kernel

    kernel._CHECKED.update({"affine", "non-affine"})
