"""Output files of the console script: races, checks before any work, signals, modes, Dask.

In-process through ``main(argv)`` (the ``cli`` fixture) where a monkeypatch stages the race
deterministically, and for the umask (set after every import); real subprocesses for
concurrency and signals.
"""

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

import softlanding.studies.sweeps as sweeps

CMD = [sys.executable, "-m", "softlanding"]
ROOT = Path(__file__).resolve().parents[3]
ENV = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}


@pytest.fixture(scope="module")
def _map_results():
    """What ``map --v0 -3 --n 11`` computed, by call: the tests of its files run it five
    times (about 1.3 s CPU each), and which files are left is what they check."""
    return {}


@pytest.fixture
def map_once(monkeypatch, _map_results):
    """``depth_map`` and ``optimize_impedance`` (the map command's work) computed once per
    module for each argument list; every caller gets its own copy of the result."""
    import copy

    import softlanding.studies.impedance as impedance

    def once(name, real):
        def run(*a, **k):
            key = (name, repr(a), repr(sorted(k.items())))
            if key not in _map_results:
                _map_results[key] = real(*a, **k)
            return copy.deepcopy(_map_results[key])
        return run

    monkeypatch.setattr(sweeps, "depth_map", once("depth_map", sweeps.depth_map))
    monkeypatch.setattr(impedance, "optimize_impedance",
                        once("optimize_impedance", impedance.optimize_impedance))


def _appears_meanwhile(monkeypatch, path, content=b"the other run's"):
    """A concurrent run writes ``path`` while this one computes its depth map."""
    real = sweeps.depth_map

    def depth_map(*a, **k):
        path.write_bytes(content)
        return real(*a, **k)

    monkeypatch.setattr(sweeps, "depth_map", depth_map)


def test_map_whose_out_file_appeared_meanwhile_exits_2_and_leaves_nothing(tmp_path, cli,
                                                                          monkeypatch, map_once):
    out, png = tmp_path / "same.nc", tmp_path / "same.png"
    _appears_meanwhile(monkeypatch, out)
    code, stdout, err = cli("map", "--v0", "-3", "--n", "11", "--out", out, "--plot", png)
    assert code == 2 and err.count("\n") == 1
    assert err.strip() == f"softlanding: error: --out: {out} exists; pass --force to overwrite it"
    assert out.read_bytes() == b"the other run's" and not png.exists()
    assert os.listdir(tmp_path) == ["same.nc"]  # no temporary file either
    assert "written" not in stdout


def test_a_later_output_failing_removes_the_earlier_one(tmp_path, cli, monkeypatch, map_once):
    out, png = tmp_path / "m5.nc", tmp_path / "m5.png"
    _appears_meanwhile(monkeypatch, png)
    code, _, err = cli("map", "--v0", "-3", "--n", "11", "--out", out, "--plot", png)
    assert code == 2 and "plot: " in err and "exists; pass --force" in err
    assert os.listdir(tmp_path) == ["m5.png"]  # the dataset placed first is rolled back
    assert png.read_bytes() == b"the other run's"


def test_with_force_a_failed_run_restores_the_file_it_replaced(tmp_path, cli, monkeypatch,
                                                               map_once):
    import softlanding.plots.paper as figures

    out = tmp_path / "m.nc"
    out.write_bytes(b"yesterday's")

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(figures, "plot_depth_map", interrupted)  # after the dataset is placed
    code, _, _ = cli("map", "--v0", "-3", "--n", "11", "--out", out, "--plot",
                     tmp_path / "m.png", "--force")
    assert code == 130
    assert out.read_bytes() == b"yesterday's" and os.listdir(tmp_path) == ["m.nc"]


@pytest.mark.slow
def test_two_concurrent_runs_onto_one_file_exactly_one_wins(tmp_path):
    # both start at once and pass the check of the outputs (it comes before the heavy imports,
    # which with the map take seconds): the exclusive creation at the end decides
    out = tmp_path / "same.nc"
    runs = [subprocess.Popen([*CMD, "map", "--v0", v0, "--n", "61", "--out", str(out)],
                             env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for v0 in ("-3", "-5")]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in runs]
    for p in runs:
        p.stdout.close(), p.stderr.close()
    assert sorted(code for code, _ in results) == [0, 2], results
    loser = [err for code, err in results if code == 2][0]
    # one line, besides the compile notice of a process that finds no compiled simulator
    lines = [ln for ln in loser.splitlines() if not ln.startswith("softlanding: compiling")]
    assert len(lines) == 1 and "exists; pass --force to overwrite it" in lines[0], loser
    winner_v0 = -3.0 if results[0][0] == 0 else -5.0
    ds = sweeps.load_dataset(out)
    assert float(ds.v0) == winner_v0 and ds.depth.shape == (61, 61)
    assert os.listdir(tmp_path) == ["same.nc"]


# ------------------------------------------------------------ checked before any work
def _no_work(monkeypatch):
    def depth_map(*a, **k):
        raise AssertionError("the work started before the outputs were checked")

    monkeypatch.setattr(sweeps, "depth_map", depth_map)


@pytest.mark.parametrize(("out", "plot", "option", "message"), [
    ("m.nc", "/proc/x.png", "plot", "cannot create files in /proc"),
    ("/sys/m.nc", "m.png", "out", "cannot create files in /sys"),
    ("x" * 300 + ".nc", "m.png", "out", "longer than the file system allows"),
    ("m.nc", "y" * 252, "plot", "longer than the file system allows"),  # with .png added
    ("same.nc", "same.nc", "plot", "also the --out file"),
    ("same.png", "./same", "plot", "also the --out file"),  # the same once .png is added
])
def test_unusable_outputs_exit_2_before_any_work(tmp_path, cli, monkeypatch, out, plot, option,
                                                 message):
    _no_work(monkeypatch)
    monkeypatch.chdir(tmp_path)
    code, _, err = cli("map", "--v0", "-3", "--n", "11", "--out", out, "--plot", plot)
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"softlanding: error: --{option}: ") and message in err
    assert os.listdir(tmp_path) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into any folder")
def test_an_unwritable_folder_exits_2_before_any_work(tmp_path, cli, monkeypatch):
    _no_work(monkeypatch)
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    code, _, err = cli("map", "--v0", "-3", "--out", locked / "m.nc")
    assert code == 2 and "--out: folder" in err and "not writable" in err


def test_reproduce_into_an_unusable_folder_exits_2_before_any_work(cli):
    code, _, err = cli("reproduce", "--quick", "--out", "/proc/D")
    assert code == 2 and err.strip() == ("softlanding: error: --out: cannot create files in "
                                         "/proc: No such file or directory")


# ------------------------------------------------------------------------- signals
def _with_sitecustomize(folder, code: str) -> dict:
    """The child's environment with ``code`` run at its start-up (a ``sitecustomize`` module
    in ``folder``, first on its path): a hook into the real process's run."""
    (folder / "sitecustomize.py").write_text(code)
    return {**ENV, "PYTHONPATH": f"{folder}{os.pathsep}{ENV['PYTHONPATH']}"}


@pytest.mark.parametrize(("signum", "code", "line"), [
    (signal.SIGTERM, 143, "softlanding: terminated (SIGTERM)"),
    pytest.param(signal.SIGINT, 130, "softlanding: interrupted", marks=pytest.mark.slow)])
def test_a_signal_mid_run_cleans_up_and_exits_128_plus_signal(tmp_path, signum, code, line):
    """Mid-way through the simulations of a large map (numba returns to Python between its
    chunks, so the signal is taken within a chunk): one line, 128 + the signal, no file."""
    site, out = tmp_path / "site", tmp_path / "out"
    site.mkdir(), out.mkdir()
    started = site / "started"  # the map's work has begun (a fixed wait was mostly idle CPU)
    env = _with_sitecustomize(site, (
        "import pathlib\n"
        "import softlanding.studies.sweeps as s\n"
        "def depth_map(*a, _map=s.depth_map, **k):\n"
        f"    pathlib.Path({str(started)!r}).touch()\n"
        "    return _map(*a, **k)\n"
        "s.depth_map = depth_map\n"))
    p = subprocess.Popen([*CMD, "map", "--v0", "-10", "--n", "2001", "--out",
                          str(out / "m.nc"), "--plot", str(out / "m.png")], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         # a suite run as a background job (`pytest &`) ignores SIGINT, and
                         # its children inherit that (the CLI keeps an ignored SIGINT ignored)
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while not started.exists() and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)  # into the simulations (the run takes minutes)
    if not (started.exists() and p.poll() is None):
        p.kill()  # (not left running its minutes-long map)
        pytest.fail(f"the map did not start, or ended early: {p.communicate(timeout=60)[1]}")
    p.send_signal(signum)
    returncode = p.wait(timeout=60)
    err = p.stderr.read()
    p.stderr.close()
    assert returncode == code, err
    assert err == line + "\n"
    assert os.listdir(out) == []  # no dataset, no figure, no temporary file


def test_an_interruption_inside_generated_code_still_exits_130_under_python_m(tmp_path):
    """CPython marks a KeyboardInterrupt that arrived while a string ``exec`` ran as unhandled
    even once caught, and ``python -m`` then died by SIGINT (-2) after printing the run's one
    line (the SIGINT test above failed so, now and then: the signal had landed in such code,
    an import's dataclass or a compile, under load)."""
    env = _with_sitecustomize(tmp_path, (
        "import softlanding.cli.commands as c\n"
        "def main(own_process=False):\n"
        "    exec('raise KeyboardInterrupt')\n"
        "c.main = main\n"))
    res = subprocess.run([*CMD, "simulate", "--v0", "-1", "--rigid"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert (res.returncode, res.stderr) == (130, "softlanding: interrupted\n")


# --------------------------------------------------------------------------- modes
@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600)])
def test_files_get_the_modes_of_the_umask(tmp_path, cli, umask, mode):
    # in-process: the umask set after every import, so a value read at import time would fail
    png = tmp_path / "t.png"
    old = os.umask(umask)
    try:
        code, _, err = cli("simulate", "--v0", "-1", "--rigid", "--plot", png)
    finally:
        os.umask(old)
    assert code == 0, err
    assert stat.S_IMODE(png.stat().st_mode) == mode


# ---------------------------------------------------------------------------- Dask
@pytest.fixture
def lone_worker():
    """A scheduler and its only worker (a separate process, no nanny to restart it)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, host="127.0.0.1", processes=True,
                                  dashboard_address=None) as cluster:
        w = subprocess.Popen(["dask", "worker", cluster.scheduler_address, "--no-nanny",
                              "--nthreads", "1", "--no-dashboard"], env=ENV,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            with distributed.Client(cluster.scheduler_address) as c:
                c.wait_for_workers(1, timeout=30)
            yield cluster.scheduler_address, w
        finally:
            w.kill()
            w.wait()


@pytest.mark.dask
def test_a_stalled_worker_fails_after_the_dask_timeout(tmp_path, cli, lone_worker):
    address, worker = lone_worker
    worker.send_signal(signal.SIGSTOP)  # alive to the scheduler, but never answers
    t0 = time.monotonic()
    code, _, err = cli("map", "--v0", "-3", "--n", "11", "--out", tmp_path / "m.nc",
                       "--scheduler", address, "--dask-timeout", "2")
    assert code == 1 and err.count("\n") == 1
    assert err.startswith("softlanding: cluster: no result from the Dask cluster for 2 s")
    assert time.monotonic() - t0 < 20 and os.listdir(tmp_path) == []


@pytest.mark.dask
def test_a_sweep_whose_only_worker_dies_fails(tmp_path, lone_worker, monkeypatch):
    import threading

    from softlanding.errors import ClusterError

    monkeypatch.setattr(sweeps, "WORKER_TIMEOUT_S", 1.0)
    address, worker = lone_worker
    worker.send_signal(signal.SIGSTOP)  # holds the tasks until it is killed
    threading.Timer(1.0, worker.kill).start()
    with pytest.raises(ClusterError, match="no Dask worker left"):
        sweeps.depth_map(-3.0, n=11, scheduler=address, dask_timeout=60)


def test_the_dask_timeout_default_is_the_library_default():
    from softlanding.cli.parser import DASK_TIMEOUT_S, MAX_DASK_TIMEOUT_S

    assert DASK_TIMEOUT_S == sweeps.DASK_TIMEOUT_S
    assert MAX_DASK_TIMEOUT_S == sweeps.MAX_DASK_TIMEOUT_S
    with pytest.raises(sweeps.ParameterError, match="dask_timeout: must be in"):
        sweeps.depth_map(-3.0, n=2, dask_timeout=1e300)


@pytest.mark.parametrize(("args", "message"), [
    (["sweep", "--n", "2", "--grid", "11", "--dask-timeout", "5"], "applies with --scheduler"),
    (["map", "--v0", "-3", "--n", "11", "--dask-timeout", "5"], "applies with --scheduler"),
    (["map", "--v0", "-3", "--scheduler", "tcp://127.0.0.1:9", "--dask-timeout", "1e300"],
     "must be in (0, 86400] seconds, got 1e+300"),
])
def test_a_dask_timeout_that_does_not_apply_or_is_unbounded_exits_2(tmp_path, cli, monkeypatch,
                                                                   args, message):
    _no_work(monkeypatch)
    monkeypatch.setattr(sweeps, "optimal_impedance_curves", sweeps.depth_map)  # no work either
    code, out, err = cli(*args, "--out", tmp_path / "x.nc")
    assert code == 2 and not out and err.count("\n") == 1, err
    assert err.startswith("softlanding: error: dask-timeout: ") and message in err
    assert os.listdir(tmp_path) == []


# ------------------------------------------------------ a folder named as a file, a full disk
@pytest.mark.parametrize("args", [
    ["simulate", "--v0", "-1", "--rigid", "--plot"], ["mpc", "--v0", "-3", "--plot"],
    ["demo", "--out"]])
@pytest.mark.parametrize("slash", ["", "/"])
def test_an_existing_folder_given_as_a_file_exits_2(tmp_path, cli, monkeypatch, args, slash):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir").mkdir()
    code, out, err = cli(*args, "adir" + slash)
    assert code == 2 and err.count("\n") == 1, err
    assert f"adir{slash} is a folder; give a file name" in err and not out
    assert os.listdir(tmp_path) == ["adir"] and os.listdir(tmp_path / "adir") == []


def _disk_fills_up(monkeypatch):
    """The figure's write fails as matplotlib's PDF writer reports a full disk."""
    from matplotlib.figure import Figure

    def savefig(self, fname, *a, **k):
        Path(fname).write_bytes(b"%PDF half written")
        try:
            raise OSError(28, "No space left on device")
        except OSError:
            raise AttributeError("'Stream' object has no attribute 'pos'") from None

    monkeypatch.setattr(Figure, "savefig", savefig)


def test_a_full_disk_is_one_line_exit_1_and_leaves_nothing(tmp_path, cli, monkeypatch, map_once):
    _disk_fills_up(monkeypatch)
    code, _, err = cli("map", "--v0", "-3", "--n", "11", "--out", tmp_path / "m.nc", "--plot",
                       tmp_path / "m.pdf")
    assert (code, err) == (1, f"softlanding: error: no space left on {tmp_path}\n")
    assert os.listdir(tmp_path) == []  # the dataset placed before is removed too


def test_reproduce_onto_a_full_disk_is_one_line_exit_1_and_leaves_nothing(tmp_path, cli,
                                                                         monkeypatch):
    import matplotlib.pyplot as plt

    import softlanding.report.reproduction as reproduction
    from softlanding.util.files import save_figure

    def sections(out, *a, **k):
        (out / "summary.md").write_text("half")
        save_figure(plt.figure(), out / "fig1.pdf")
        raise AssertionError("the full disk went unnoticed")

    _disk_fills_up(monkeypatch)
    monkeypatch.setattr(reproduction, "_run_sections", sections)
    out = tmp_path / "R"
    code, _, err = cli("reproduce", "--quick", "--out", out)
    assert (code, err) == (1, f"softlanding: error: no space left on {out}\n")
    assert os.listdir(tmp_path) == []


def test_matplotlibs_cache_notes_on_a_full_home_are_not_printed(tmp_path, cli, monkeypatch,
                                                                map_once, caplog):
    """A full disk also fills matplotlib's caches: its notes made a full-disk map 3 lines."""
    import logging

    real = sweeps.depth_map

    def depth_map(*a, **k):
        logging.getLogger("matplotlib").warning("%s is not a writable directory", "/home/x")
        logging.getLogger("matplotlib.font_manager").warning(
            "Could not save font_manager cache %s", OSError(28, "No space left on device"))
        return real(*a, **k)

    monkeypatch.setattr(sweeps, "depth_map", depth_map)
    code, _, err = cli("map", "--v0", "-3", "--n", "11", "--out", tmp_path / "m.nc")
    assert code == 0 and err == ""
    assert [r for r in caplog.records if r.name.startswith("matplotlib")] == []  # none emitted
