"""The console script: in-process through ``main(argv)`` (the ``cli`` fixture), plus a few
real subprocesses."""

import json
import os
import subprocess
import sys

import pytest

from softlanding.cli import main

CMD = [sys.executable, "-m", "softlanding"]


def test_simulate_json_has_documented_keys(tmp_path, cli):
    png = tmp_path / "traj.png"
    code, out, err = cli("simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.18",
                         "--json", "--plot", str(png))
    assert code == 0, err
    d = json.loads(out)
    for k in ("depth", "steps", "feasible", "u_peak", "stroke_min", "stroke_max",
              "t_first_stop", "energy", "robot", "impact", "controller", "ground"):
        assert k in d
    for k in ("E0", "ET", "ground", "actuator", "cot"):
        assert k in d["energy"]
    assert d["steps"] == 2
    assert d["controller"] == {"kind": "impedance", "k_p": 0.2, "k_d": 0.18, "l0": None}
    assert png.stat().st_size > 10_000


def test_simulate_rigid_table(cli):
    code, out, _ = cli("simulate", "--v0", "-3", "--rigid")
    assert code == 0
    assert "4.16227766" in out  # 1 + sqrt(10)


def test_negative_numbers_in_scientific_notation_are_values(cli):
    code, out, err = cli("simulate", "--v0", "-1e-3", "--rigid", "--json")
    assert code == 0, err
    assert json.loads(out)["impact"]["v0"] == -1e-3


@pytest.mark.parametrize("args", [
    ["simulate", "--v0", "0.5", "--rigid"],
    ["simulate", "--v0", "nan", "--rigid"],
    ["simulate", "--v0", "-inf", "--rigid"],
    ["simulate", "--v0", "-1", "--kp", "-0.2", "--kd", "0.1"],
    ["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "inf"],
    ["simulate", "--v0", "-1", "--rigid", "--rm", "0"],
    ["simulate", "--v0", "-1", "--rigid", "--s", "-20"],
    ["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.2", "--umax", "0"],
    ["simulate", "--v0", "-1", "--kp", "0.2"],
    ["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.2", "--rigid"],
    ["simulate", "--v0", "-1", "--rigid", "--l0", "25"],
    ["simulate", "--v0", "fast"],
    ["scale", "--mb", "-2.5", "--mf", "0.5", "--kg", "4400", "--stroke", "0.1"],
    ["scale", "--mb", "2.5", "--mf", "0.5", "--kg", "0", "--stroke", "0.1"],
    ["scale", "--mb", "2.5", "--mf", "0.5", "--kg", "4400", "--stroke", "0.1", "--v0-si", "1"],
    ["scale", "--to-si", "--mb", "10"],
    ["scale", "--to-si", "--rm", "5"],
    ["solve-sweep", "--n", "3", "--rm", "nan"],
    ["solve", "--v0", "-3", "--extra-arcs", "-1"],
    ["solve", "--v0", "-3", "--nodes", "10000000"],
    ["impedance", "--v0", "-3", "--grid", "0"],
    ["impedance", "--v0", "-3", "--grid", "10000000"],
    ["map", "--v0", "-3", "--n", "10000000", "--out", "x.nc"],
    ["sweep", "--n", "0"],
    ["simulate", "--v0", "-1", "--kp", "1e7", "--kd", ".2"],
    ["simulate", "--v0", "-1", "--rigid", "--rm", "1e300"],
    ["simulate", "--v0", "-1", "--rigid", "--rm", "1e-300"],
    ["simulate", "--v0", "-1", "--rigid", "--s", "1e300"],
    ["simulate", "--v0=-1e6", "--rigid"],
    ["impedance", "--v0=-1e6"],
    ["solve", "--v0", "-3", "--umax", "1e300"],
    ["solve", "--v0", "-3", "--s", "1e-300"],
    ["scale", "--to-si", "--mb", "10"],
    ["reproduce", "--quick"],
])
def test_bad_input_one_line_exit_2(args, cli):
    code, _, err = cli(*args)
    assert code == 2
    assert err.count("\n") == 1, err
    assert "Traceback" not in err
    assert err.startswith("softlanding")
    assert "np.float64" not in err


@pytest.mark.parametrize("args,status", [
    (["simulate", "--v0", "-1", "--kp", "0", "--kd", "0"], "passes through"),
    (["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.18", "--umax", "0.01"],
     "passes through"),
])
def test_a_meaningless_landing_is_not_reported_as_rest(args, status, cli):
    code, out, _ = cli(*args, "--json")
    d = json.loads(out)
    assert code == 1 and status in d["status"] and not d["rest_proven"] and not d["feasible"]


def test_the_force_limit_applies_to_the_rigid_leg(cli):
    code, out, _ = cli("simulate", "--v0", "-1", "--rigid", "--umax", "1", "--json")
    d = json.loads(out)
    assert d["u_peak"] <= 1.0 + 1e-12  # the lock slips at the limit instead of ignoring it
    assert not d["feasible"] and code == 1


@pytest.mark.parametrize("args,match", [
    (["compare", "--n", "3", "--umax", "0.5"], "body weight"),
    pytest.param(["solve", "--v0", "-10", "--umax", "2"], "arrest force u_b <= u_max",
                 marks=pytest.mark.slow),  # 5.5 s CPU (its API twin in test_landing is fast)
])
def test_infeasible_request_one_line_exit_1(args, match, cli):
    """Well-posed but infeasible: exit 1, not the bad-input code 2."""
    code, _, err = cli(*args)
    assert code == 1
    assert err.startswith("softlanding: infeasible:") and match in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_an_internal_error_is_reported_as_a_bug(cli, monkeypatch):
    import importlib

    sim = importlib.import_module("softlanding.simulation.simulator")

    def boom(*a, **k):
        raise ZeroDivisionError("synthetic")

    monkeypatch.setattr(sim, "simulate", boom)
    code, _, err = cli("simulate", "--v0", "-1", "--rigid")
    assert code == 3
    assert "internal error" in err and "--debug" in err and err.count("\n") == 1
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "simulate", "--v0", "-1", "--rigid"])
    with pytest.raises(ZeroDivisionError):
        main(["simulate", "--v0", "-1", "--rigid", "--debug"])


def test_scale_round_trip_json(cli):
    _, out, _ = cli("scale", "--preset", "paper", "--v0-si", "-1.2", "--json")
    d = json.loads(out)
    assert d["dimensionless"]["s"] == pytest.approx(20.0)
    _, out, _ = cli("scale", "--to-si", "--mt", "3", "--kg", "4400", "--rm", "5",
                    "--s", "20", "--v0", str(d["dimensionless"]["v0"]), "--json")
    back = json.loads(out)["physical"]
    assert back["v0"] == pytest.approx(-1.2)
    assert back["m_b"] == pytest.approx(2.5)


def test_scale_preset_takes_overrides(cli):
    _, out, _ = cli("scale", "--preset", "paper", "--umax-si", "100", "--g", "1.62",
                    "--json")
    d = json.loads(out)
    assert d["physical"]["u_max"] == 100.0 and d["physical"]["g"] == 1.62
    assert d["dimensionless"]["u_max"] == pytest.approx(100.0 / (3.0 * 1.62))


def test_demo_runs_and_writes_figure(tmp_path, cli, monkeypatch):
    """By default into its own folder, replaced by a second run (a user's file is not)."""
    monkeypatch.chdir(tmp_path)
    out_png = tmp_path / "softlanding-demo" / "demo.png"
    out_png.parent.mkdir()
    out_png.write_bytes(b"the last run's")
    code, out, err = cli("demo", "--json")
    assert code == 0, err
    assert os.listdir(tmp_path) == ["softlanding-demo"] and os.listdir(out_png.parent) == [
        "demo.png"]
    (tmp_path / "softlanding-demo" / "mine.txt").write_text("a user's file")
    code, _, err = cli("demo", "--json")
    assert code == 2 and "softlanding-demo holds files this command did not write" in err
    assert "NaN" not in out  # valid JSON: NaN becomes null
    d = json.loads(out)
    for row in d["table"]:
        assert row["rigid_depth"] == pytest.approx(row["rigid_depth_analytic"], abs=1e-10)
    assert [s["steps"] for s in d["stepped_intrusions"]] == [1, 2, 3]
    assert d["simulator"] == "compiled"  # in-process: the caller's numba is left as it is
    assert out_png.stat().st_size > 10_000


def test_help_explains(cli):
    code, out, _ = cli("--help")
    assert code == 0 and "yielding" in out
    code, out, _ = cli("simulate", "--help")
    assert "--kp" in out and "impact velocity" in out


def test_version(cli):
    from importlib.metadata import version

    code, out, _ = cli("--version")
    assert code == 0 and out.strip() == f"softlanding {version('softlanding')}"


# ------------------------------------------------------------ real processes
def run(*args):
    return subprocess.run(CMD + list(args), capture_output=True, text=True, timeout=300)


def test_smoke_console_script_runs_a_landing():
    p = run("simulate", "--v0", "-3", "--rigid", "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["depth"] == pytest.approx(1 + 10**0.5, abs=1e-10)


def test_smoke_bad_input_from_a_real_process():
    p = run("simulate", "--v0", "0.5", "--rigid")
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr


# ------------------------------------------------------------------- files
def test_existing_files_are_not_overwritten_without_force(tmp_path, cli):
    png = tmp_path / "t.png"
    png.write_bytes(b"mine")
    code, _, err = cli("simulate", "--v0", "-1", "--rigid", "--plot", png)
    assert code == 2 and "--force" in err and err.count("\n") == 1
    assert png.read_bytes() == b"mine"
    code, out, _ = cli("simulate", "--v0", "-1", "--rigid", "--plot", png, "--force")
    assert code == 0 and png.read_bytes()[:4] == b"\x89PNG"
    assert f"figure written to {png}" in out


def test_the_path_actually_written_is_reported(tmp_path, cli):
    code, out, _ = cli("simulate", "--v0", "-1", "--rigid", "--plot", tmp_path / "fig")
    assert code == 0
    assert (tmp_path / "fig.png").exists() and f"figure written to {tmp_path / 'fig.png'}" in out


@pytest.mark.parametrize("args", [
    ["reproduce", "--out", ""], ["demo", "--out", "/nonexistent/x.png"],
    ["simulate", "--v0", "-1", "--rigid", "--plot", "."]])
def test_unusable_output_paths_are_refused_before_any_work(args, cli):
    code, _, err = cli(*args)
    assert code == 2 and err.count("\n") == 1


def test_reproduce_refuses_a_non_empty_folder(tmp_path, cli):
    (tmp_path / "summary.md").write_text("my notes")
    code, _, err = cli("reproduce", "--out", tmp_path, "--quick")
    assert code == 2 and "not empty" in err
    assert (tmp_path / "summary.md").read_text() == "my notes"


def test_a_failed_run_leaves_no_file_behind(tmp_path, cli, monkeypatch):
    import softlanding.studies.impedance as imp

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(imp, "optimize_impedance", boom)
    code, _, err = cli("map", "--v0", "-2", "--n", "11", "--out", tmp_path / "m.nc",
                       "--plot", tmp_path / "m.png")
    # (a cold numba cache adds its one compile notice before the run's work)
    lines = [ln for ln in err.splitlines() if not ln.startswith("softlanding: compiling")]
    assert code == 130 and lines == ["softlanding: interrupted"]
    assert list(tmp_path.iterdir()) == []  # no dataset, no figure, no temporary file


def test_progress_bars_only_on_a_terminal(cli):
    """A log or a pipe gets no carriage-return frames; --progress forces them."""
    code, out, err = cli("solve-sweep", "--n", "3", "--v0-min", "-2")
    assert code == 0 and "\r" not in err and err == ""
    # the paper's sweep is any variant's (issue 46 item 5: one sweep path): its table names
    # it and says which landings are verified, beside the rigid leg's depth
    lines = out.splitlines()
    assert lines[0] == "variant paper" and lines[1].split()[:4] == ["v0", "depth", "rigid",
                                                                    "ratio"]
    assert "verified" in lines[1] and all(ln.split()[6] == "yes" for ln in lines[2:5])
    code, out, err = cli("--progress", "solve-sweep", "--n", "3", "--v0-min", "-2")
    assert code == 0 and "\r" in err and "paper sweep" in err
    from softlanding.util import progress as _progress

    _progress.FORCE = False


@pytest.mark.parametrize("args", [
    ["impedance", "--v0", "-3", "--grid", "10000000"],
    ["map", "--v0", "-3", "--n", "10000000", "--out", "x.nc"],
    ["sweep", "--grid", "10000000"],
    ["solve", "--v0", "-3", "--nodes", "10000000"],
    ["solve-sweep", "--n", "100000000"],
])
def test_huge_sizes_are_refused_at_once(args, cli):
    import time

    cli("--version")  # imports paid before the clock starts
    c = time.process_time()
    code, _, err = cli(*args)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert time.process_time() - c < 1.0


def test_robust_bounds_its_ground_set_before_any_work(cli):
    """10,002 grounds were accepted (each drag ground compiled its law): refused, exit 2."""
    from softlanding.model.ground import MAX_GROUNDS

    drag = ",".join(f"{i / 1000:g}" for i in range(MAX_GROUNDS // 2 + 1))
    code, out, err = cli("robust", "--v0", "-3", "--stiffness", "1,2", "--cd", drag)
    assert code == 2 and not out and err.count("\n") == 1
    assert f"--cd: 2 x {MAX_GROUNDS // 2 + 1} = {MAX_GROUNDS + 2} grounds" in err
    assert f"at most {MAX_GROUNDS}" in err
    code, _, err = cli("robust", "--v0", "-3", "--cd", "0,-1")  # the option, by its name
    assert code == 2 and err.strip().endswith("--cd: must be >= 0, got -1")


def test_robust_json_gives_every_grounds_stiffness(cli, monkeypatch):
    import softlanding.control.robust as robust

    real = robust.robust_landing  # a short search: this checks the JSON, not the optimum
    monkeypatch.setattr(robust, "robust_landing", lambda *a, **k: real(*a, **k, max_iterations=1))
    code, out, err = cli("robust", "--v0", "-3", "--stiffness", "1,2", "--json")
    assert code in (0, 1), err
    rows = json.loads(out)["robust"]["grounds"]
    assert [r["ground"]["stiffness"] for r in rows] == [1.0, 2.0]
