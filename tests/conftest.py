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
