"""The code base is ruff-clean (the README's test command) and type-checks (its slow
command); ruff and mypy are in [test]."""

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
