"""The console script, run as a user would (a real subprocess)."""

import json
import subprocess
import sys

import pytest

CMD = [sys.executable, "-m", "softlanding"]


def run(*args):
    return subprocess.run(CMD + list(args), capture_output=True, text=True, timeout=300)


def test_simulate_json_has_documented_keys(tmp_path):
    png = tmp_path / "traj.png"
    p = run("simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.18", "--json", "--plot", str(png))
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    for k in ("depth", "steps", "feasible", "u_peak", "stroke_min", "stroke_max",
              "t_first_stop", "energy"):
        assert k in d
    for k in ("E0", "ET", "ground", "actuator", "cot"):
        assert k in d["energy"]
    assert d["steps"] == 2
    assert png.stat().st_size > 10_000


def test_simulate_rigid_table():
    p = run("simulate", "--v0", "-3", "--rigid")
    assert p.returncode == 0
    assert "4.16227766" in p.stdout  # 1 + sqrt(10)


@pytest.mark.parametrize("args", [
    ["simulate", "--v0", "0.5", "--rigid"],
    ["simulate", "--v0", "nan", "--rigid"],
    ["simulate", "--v0", "-1", "--kp", "-0.2", "--kd", "0.1"],
    ["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "inf"],
    ["simulate", "--v0", "-1", "--rigid", "--rm", "0"],
    ["simulate", "--v0", "-1", "--rigid", "--s", "-20"],
    ["simulate", "--v0", "-1", "--kp", "0.2", "--kd", "0.2", "--umax", "0"],
    ["simulate", "--v0", "-1", "--kp", "0.2"],
    ["simulate", "--v0", "fast"],
    ["scale", "--mb", "-2.5", "--mf", "0.5", "--kg", "4400", "--stroke", "0.1"],
    ["scale", "--mb", "2.5", "--mf", "0.5", "--kg", "0", "--stroke", "0.1"],
    ["scale", "--mb", "2.5", "--mf", "0.5", "--kg", "4400", "--stroke", "0.1", "--v0-si", "1"],
    ["compare", "--n", "3", "--umax", "0.5"],
    ["solve-sweep", "--n", "3", "--rm", "nan"],
    ["reproduce", "--quick"],
])
def test_bad_input_one_line_exit_2(args):
    p = run(*args)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1, p.stderr
    assert "Traceback" not in p.stderr
    assert p.stderr.startswith("softlanding")


def test_scale_round_trip_json():
    p = run("scale", "--preset", "paper", "--v0-si", "-1.2", "--json")
    d = json.loads(p.stdout)
    assert d["dimensionless"]["s"] == pytest.approx(20.0)
    q = run("scale", "--to-si", "--mt", "3", "--kg", "4400", "--rm", "5", "--s", "20",
            "--v0", str(d["dimensionless"]["v0"]), "--json")
    back = json.loads(q.stdout)["physical"]
    assert back["v0"] == pytest.approx(-1.2)
    assert back["m_b"] == pytest.approx(2.5)


def test_demo_runs_and_writes_figure(tmp_path):
    out = tmp_path / "demo.png"
    p = run("demo", "--out", str(out), "--json")
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    for row in d["table"]:
        assert row["rigid_depth"] == pytest.approx(row["rigid_depth_analytic"], abs=1e-10)
    assert [s["steps"] for s in d["stepped_intrusions"]] == [1, 2, 3]
    assert out.stat().st_size > 10_000


def test_help_explains():
    p = run("--help")
    assert p.returncode == 0 and "yielding" in p.stdout
    p = run("simulate", "--help")
    assert "--kp" in p.stdout and "impact velocity" in p.stdout
