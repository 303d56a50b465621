"""Output files: exclusive placement under a race, rollback of a run, modes from the umask."""

import errno
import os
import stat
import threading

import pytest

import softlanding.util.files as files
from softlanding.errors import DiskFullError, ParameterError
from softlanding.util.files import atomic, atomic_folder, output_path, output_run


def _race(n, body):
    """Run ``body(i, barrier)`` in n threads at once; the outcome of each ("won"/"lost")."""
    barrier = threading.Barrier(n, timeout=10)
    outcome = [None] * n

    def run(i):
        try:
            body(i, barrier)
        except ParameterError as exc:
            outcome[i] = ("lost", str(exc))
        else:
            outcome[i] = ("won", "")

    threads = [threading.Thread(target=run, args=(i,)) for i in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return outcome


def test_two_writers_of_one_file_exactly_one_wins(tmp_path):
    target = tmp_path / "same.nc"
    payload = [b"A" * 200_000, b"B" * 300_000]

    def write(i, barrier):
        with atomic(target) as tmp:
            tmp.write_bytes(payload[i])
            barrier.wait()  # both finished writing and checked: now both place

    outcome = _race(2, write)
    assert sorted(o[0] for o in outcome) == ["lost", "won"]
    winner = [o[0] for o in outcome].index("won")
    lost = outcome[1 - winner][1]
    assert "exists; pass --force to overwrite it" in lost and "\n" not in lost
    assert target.read_bytes() == payload[winner]  # complete, and the winner's
    assert os.listdir(tmp_path) == ["same.nc"]  # no temporary file left


def test_force_replaces_and_a_failed_run_restores_the_file_it_replaced(tmp_path):
    target = tmp_path / "out.nc"
    target.write_bytes(b"old")
    with output_run(force=True):
        with atomic(target) as tmp:
            tmp.write_bytes(b"new")
    assert target.read_bytes() == b"new"
    with pytest.raises(KeyboardInterrupt), output_run(force=True):
        with atomic(target) as tmp:
            tmp.write_bytes(b"newer")
        assert target.read_bytes() == b"newer"
        raise KeyboardInterrupt  # the run fails after placing its file
    assert target.read_bytes() == b"new"
    assert os.listdir(tmp_path) == ["out.nc"]  # the backup is gone too


def test_a_failed_run_removes_the_outputs_it_already_placed(tmp_path):
    first, second = tmp_path / "m.nc", tmp_path / "m.png"
    with pytest.raises(ParameterError, match="exists"), output_run():
        output_path(first, "out", False), output_path(second, "plot", False)
        with atomic(first) as tmp:
            tmp.write_bytes(b"data")
        second.write_bytes(b"someone else's")  # appears while this run works
        with atomic(second) as tmp:
            tmp.write_bytes(b"figure")
    assert sorted(os.listdir(tmp_path)) == ["m.png"]
    assert second.read_bytes() == b"someone else's"


def test_two_runs_filling_one_new_folder_exactly_one_wins(tmp_path):
    target = tmp_path / "D"

    def fill(i, barrier):
        with atomic_folder(target, force=False) as tmp:
            (tmp / "summary.json").write_text(str(i))
            (tmp / f"only-{i}.txt").write_text(str(i))
            barrier.wait()

    outcome = _race(2, fill)
    assert sorted(o[0] for o in outcome) == ["lost", "won"]
    winner = [o[0] for o in outcome].index("won")
    assert sorted(os.listdir(target)) == sorted(["summary.json", f"only-{winner}.txt"])
    assert os.listdir(tmp_path) == ["D"]  # the loser's temporary folder is removed


def _full_disk_as_matplotlib_reports_it():
    """matplotlib's PDF writer, cleaning up after ENOSPC, raises an AttributeError instead."""
    try:
        raise OSError(errno.ENOSPC, "No space left on device")
    except OSError:
        raise AttributeError("'Stream' object has no attribute 'pos'") from None


def test_a_full_disk_is_one_error_naming_the_folder_and_leaves_nothing(tmp_path):
    with pytest.raises(DiskFullError, match=f"^no space left on {tmp_path}$"):
        with atomic(tmp_path / "fig.pdf") as tmp:
            tmp.write_bytes(b"%PDF half")
            _full_disk_as_matplotlib_reports_it()
    out = tmp_path / "D"
    with pytest.raises(DiskFullError, match=f"^no space left on {out}$"):
        with atomic_folder(out, force=False) as tmp:
            (tmp / "a.png").write_bytes(b"png")
            _full_disk_as_matplotlib_reports_it()
    assert os.listdir(tmp_path) == []


def _old_folder(tmp_path):
    d = tmp_path / "D"
    (d / "data").mkdir(parents=True)
    for name in ("a.txt", "b.txt", "mine.txt", "data/x.nc"):
        (d / name).write_text("old")
    return d


def test_force_replaces_a_folder_all_at_once_and_keeps_the_users_other_files(tmp_path):
    d = _old_folder(tmp_path)
    with atomic_folder(d, force=True) as tmp:
        (tmp / "data").mkdir()
        for name in ("a.txt", "b.txt", "data/x.nc"):
            (tmp / name).write_text("new")
    assert {str(p.relative_to(d)): p.read_text() for p in d.rglob("*.*")} == {
        "a.txt": "new", "b.txt": "new", "data/x.nc": "new", "mine.txt": "old"}
    assert os.listdir(tmp_path) == ["D"]


def test_force_into_a_folder_failing_while_placing_leaves_the_old_folder_whole(tmp_path,
                                                                              monkeypatch):
    """The placement's third rename or replace fails (an I/O error): all old or all new."""
    d = _old_folder(tmp_path)
    calls = []

    def failing(real):
        def move(src, dst, *a, **k):
            calls.append(dst)
            if len(calls) == 3:
                raise OSError(errno.EIO, "Input/output error")
            return real(src, dst, *a, **k)
        return move

    monkeypatch.setattr(files.os, "rename", failing(os.rename))
    monkeypatch.setattr(files.os, "replace", failing(os.replace))
    with pytest.raises(OSError, match="Input/output"):
        with atomic_folder(d, force=True) as tmp:
            for name in ("a.txt", "b.txt"):
                (tmp / name).write_text("new")
    monkeypatch.undo()
    assert {p.name: p.read_text() for p in d.rglob("*.*")} == {
        "a.txt": "old", "b.txt": "old", "mine.txt": "old", "x.nc": "old"}
    assert os.listdir(tmp_path) == ["D"]


def test_a_folder_is_refused_as_a_file_with_or_without_a_slash(tmp_path):
    (tmp_path / "adir").mkdir()
    for given in (tmp_path / "adir", f"{tmp_path / 'adir'}/"):
        with pytest.raises(ParameterError, match="adir/? is a folder; give a file name"):
            output_path(given, "plot", True, default_suffix=".png")
    with pytest.raises(ParameterError, match="is a folder"):
        output_path(f"{tmp_path / 'new'}/", "plot", False, default_suffix=".png")
    assert os.listdir(tmp_path) == ["adir"]


@pytest.mark.parametrize("bad", ["/proc/x.png", "/sys/x.png"])
def test_a_folder_that_takes_no_files_is_refused_up_front(bad):
    with pytest.raises(ParameterError, match="^plot: cannot create files in"):
        output_path(bad, "plot", False)


def test_a_name_too_long_is_refused_up_front(tmp_path):
    with pytest.raises(ParameterError, match="longer than the file system allows"):
        output_path(tmp_path / ("x" * 300 + ".png"), "plot", False)
    with pytest.raises(ParameterError, match="longer than the file system allows"):
        output_path(tmp_path / ("x" * 252), "plot", False, default_suffix=".png")
    # the longest legal name still works: the temporary name is kept short
    longest = tmp_path / ("y" * 251 + ".png")
    with atomic(output_path(longest, "plot", False)) as tmp:
        tmp.write_bytes(b"ok")
    assert longest.read_bytes() == b"ok"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into any folder")
def test_an_unwritable_folder_is_refused_up_front(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    with pytest.raises(ParameterError, match="not writable"):
        output_path(locked / "x.png", "plot", False)


def test_one_file_named_by_two_options_is_refused(tmp_path):
    with output_run(), pytest.raises(ParameterError, match="also the --out file"):
        output_path(tmp_path / "same.png", "out", False)
        output_path(tmp_path / "." / "same.png", "plot", False)


@pytest.mark.parametrize(("umask", "file_mode", "dir_mode"),
                         [(0o022, 0o644, 0o755), (0o077, 0o600, 0o700)])
def test_modes_follow_the_umask(tmp_path, umask, file_mode, dir_mode):
    old = os.umask(umask)
    try:
        with atomic(tmp_path / "f.nc") as tmp:
            tmp.write_bytes(b"x")
        with atomic_folder(tmp_path / "D") as tmp:
            (tmp / "a.txt").write_text("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "f.nc").stat().st_mode) == file_mode
    assert stat.S_IMODE((tmp_path / "D").stat().st_mode) == dir_mode


def test_force_refuses_up_front_a_folder_too_big_to_be_a_runs_output(tmp_path, monkeypatch):
    from softlanding.util.files import output_folder

    d = _old_folder(tmp_path)
    assert output_folder(d, "out", True) == d
    monkeypatch.setattr(files, "MAX_KEPT_ENTRIES", 3)  # a home folder, say
    with pytest.raises(ParameterError, match="holds more than 3 files; give a new or empty"):
        output_folder(d, "out", True)
