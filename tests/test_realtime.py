"""``benchmarks.realtime``: a benchmark run as a robot's control loop (issue 33's wall-time
maximum), or refused in one line (exit 2) without the privilege, never measured otherwise."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHILD = """
import os, sys
from benchmarks.realtime import enter_realtime
if sys.argv[1] == "drop":
    os.setuid(65534)  # nobody: no CAP_SYS_NICE
print(enter_realtime())
print(os.sched_getscheduler(0) == os.SCHED_FIFO, len(os.sched_getaffinity(0)))
"""


def _child(mode: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", CHILD, mode], cwd=ROOT, text=True,
                          capture_output=True, timeout=60)


needs_linux = pytest.mark.skipif(not hasattr(os, "sched_setscheduler"), reason="Linux only")


@needs_linux
def test_without_privilege_it_refuses_in_one_line():
    if os.geteuid() != 0:
        pytest.skip("needs root to drop the privilege in a child")
    out = _child("drop")
    assert out.returncode != 0
    assert "RealtimeUnavailable: real-time scheduling not permitted" in out.stderr


@needs_linux
def test_with_privilege_the_process_runs_fifo_on_one_cpu():
    if os.geteuid() != 0:
        pytest.skip("needs root (or CAP_SYS_NICE)")
    out = _child("keep")
    assert out.returncode == 0, out.stderr
    head, check = out.stdout.splitlines()
    assert head.startswith("real-time: SCHED_FIFO priority 50 on CPU")
    assert check == "True 1"


def _study(monkeypatch, capsys, *args) -> tuple[object, str]:
    """``python -m benchmarks.study_unknown_ground ARGS`` in-process (its refusals come
    before any work: a subprocess only added the package's import, 2 s CPU each):
    (exit code, stderr)."""
    from benchmarks import study_unknown_ground

    monkeypatch.setattr(sys, "argv", ["study_unknown_ground.py", *args])
    with pytest.raises(SystemExit) as exit_:
        study_unknown_ground.main()
    return exit_.value.code, capsys.readouterr().err


def test_the_benchmarks_refuse_it_with_exit_2_where_it_does_not_apply(monkeypatch, capsys):
    code, err = _study(monkeypatch, capsys, "--realtime")
    assert code == 2
    assert "--realtime applies to --controllers only" in err


def test_the_study_refuses_an_existing_json_file_before_any_work(tmp_path, monkeypatch,
                                                                 capsys):
    # (its --json was opened after the study: an existing file replaced silently)
    out_file = tmp_path / "rows.json"
    out_file.write_text("keep")
    code, err = _study(monkeypatch, capsys, "--controllers", "--json", str(out_file))
    assert code == 2 and "exists" in err and "--force" in err
    assert out_file.read_text() == "keep" and list(tmp_path.iterdir()) == [out_file]
