"""The code base is ruff-clean (part of the README's test command; ruff is in [test])."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_clean():
    p = subprocess.run([sys.executable, "-m", "ruff", "check", str(ROOT)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr
