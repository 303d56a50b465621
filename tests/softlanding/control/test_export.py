"""The controller exported as C (``softlanding export-controller``): its numbers against the
Python modules', compiled with the system's C compiler and compared with the numba
controller on 1,000 samples of random landings and with the numba foot filter and the
filtered step (weights, recovery) on 600 samples of noisy landings, and on the samples of
mpc_landing's creep landings (the creep law), C programs that follow the README, and the
command's bad input and output folder."""

import contextlib
import dataclasses
import io
import json
import re
import subprocess

import numpy as np
import pytest

from softlanding.cli import main
from softlanding.control import bangbang as bb
from softlanding.control import creep, estimation, recovery
from softlanding.control import foot_filter as ff
from softlanding.control.estimation import GroundEstimator
from softlanding.control.export_c import layout
from softlanding.control.export_c.binding import CFLAGS, CController, compile_shared, find_compiler
from softlanding.control.export_c.check import TOLERANCE, compare, compare_calls, plan_forces
from softlanding.control.export_c.creep_samples import CREEP_LANDINGS, creep_calls
from softlanding.control.export_c.filter_check import PROBES, compare_filter, filtered_calls
from softlanding.control.export_c.reference import ground_estimate, plan_force_integrals
from softlanding.control.export_c.step_check import compare_steps
from softlanding.control.export_c.writer import HEADER, README, SOURCE
from softlanding.model.robot import PAPER_ROBOT
from softlanding.simulation.kernel import dop853

needs_cc = pytest.mark.skipif(find_compiler() is None,
                              reason="no C compiler (cc, gcc or $CC) on this system")


def _run(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as e:
            code = e.code
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The paper's robot exported (with the check against numba, where there is a compiler):
    the folder and the command's JSON."""
    folder = tmp_path_factory.mktemp("export") / "controller"
    check = ("--check",) if find_compiler() is not None else ()
    code, out, err = _run("export-controller", "--out", folder, "--json", *check)
    assert code == 0, err
    return folder, json.loads(out)


def _defines(text):
    return dict(re.findall(r"^#define SL_(\w+)\s+(\S+)", text, re.M))


def _array(text, name):
    """The numbers of the C array ``name``'s initializer (its comments left out)."""
    body = re.search(rf"{name}\[[^=]*= \{{(.*?)\}};", text, re.S).group(1)
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    return np.array([float(v) for v in re.findall(r"-?\d+\.?\d*(?:e[-+]?\d+)?", body)])


def test_the_files_and_json(exported):
    folder, d = exported
    assert sorted(p.name for p in folder.iterdir()) == sorted([HEADER, SOURCE, README])
    assert d["files"] == [str(folder / n) for n in (HEADER, SOURCE, README)]
    r = PAPER_ROBOT
    P = bb.robot_numbers(r.r_m, r.s, r.u_max, 1.0, 0.0, creep=True)  # (as mpc_landing's)
    assert P[bb.P_CREEP] == 1.0
    assert d["numbers"] == {k[2:]: P[i] for k, i in layout.indices("P_").items()}


def test_the_header_holds_the_python_modules_numbers(exported):
    folder, _ = exported
    got = _defines((folder / HEADER).read_text())
    for prefix in ("P_", "M_"):
        idx = layout.indices(prefix)
        assert idx and all(int(got[k]) == v for k, v in idx.items())
    assert int(got["NP"]) == bb.NP and int(got["NM"]) == bb.NM
    assert max(layout.indices("P_").values()) < bb.NP and bb.M_PRED + 4 <= bb.NM
    for name in layout.CONSTANTS:
        assert float(got[name]) == getattr(bb, name)
    for name in layout.CREEP_CONSTANTS:  # the creep law's, from its module
        assert float(got[f"CREEP_{name}"]) == getattr(creep, name)
    assert {"CREEPING", "CREEP_LAW", "CREEP_SIGMAS"} <= set(layout.CONSTANTS)
    src = (folder / SOURCE).read_text()
    assert np.array_equal(_array(src, "SL_GL_X"), creep.GL_X)
    assert np.array_equal(_array(src, "SL_GL_W"), creep.GL_W)
    assert np.array_equal(_array(src, "SL_DA"), dop853.A.ravel())
    for name, want in (("SL_DB", dop853.B), ("SL_DE5", dop853.E5), ("SL_DE3", dop853.E3)):
        assert np.array_equal(_array(src, name), want)
    r = PAPER_ROBOT
    assert np.array_equal(_array(src, "SL_ROBOT_NUMBERS"),
                          bb.robot_numbers(r.r_m, r.s, r.u_max, 1.0, 0.0, creep=True))


def test_an_entry_the_export_does_not_describe_fails_the_export(monkeypatch):
    # (the layout is bangbang_layout's, which bangbang re-exports)
    from softlanding.control import bangbang_layout

    monkeypatch.setattr(bangbang_layout, "M_NEW", bb.NM, raising=False)
    with pytest.raises(KeyError, match="M_NEW"):
        layout.layout_lines("M_")


@needs_cc
def test_c_and_numba_agree_on_1000_samples_of_random_landings(exported):
    check = exported[1]["check"]
    assert check["samples"] == 1000 and check["landings"] >= 40  # as many grounds
    assert all(v <= TOLERANCE for v in check["max_relative_difference"].values()), check
    # the comparison went through every path of the step, not only the easy ones
    st = check["statuses"]
    assert all(st.get(s, 0) >= 50 for s in ("ok", "converging", "plan holds")), st
    assert st.get("creep", 0) >= 1  # a plan not covered: SL_CREEP in C too (samples.py)
    assert st.get("creep law", 0) >= 10  # the creep law on, every other landing
    assert st.get("deferred", 0) >= 10  # the work bound ran out (samples.py's tight ones)
    assert check["pull_samples"] >= 50  # and after the switch
    assert sum(st.values()) == 1000 + check["landings"] + 1  # the creep's probe


@pytest.mark.slow
@needs_cc
def test_the_comparison_sees_a_changed_constant(exported, tmp_path):
    # an honest comparison: the step-size control's exponent off by 1e-7 shows
    src = (exported[0] / SOURCE).read_text()
    assert src.count("-1.0 / 8.0") == 2
    mutant = tmp_path / "mutant"
    mutant.mkdir()
    (mutant / HEADER).write_text((exported[0] / HEADER).read_text())
    (mutant / SOURCE).write_text(src.replace("-1.0 / 8.0", "-1.0 / 8.000001"))
    c = CController(compile_shared(mutant, tmp_path / "mutant.so"))
    assert compare(c, 30).worst() > 1e-9


# ---- the creep law --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def creep_samples():
    """The samples of mpc_landing's creep landings of the paper's robot (exact, and noisy
    filtered)."""
    return creep_calls(PAPER_ROBOT)


@pytest.fixture(scope="module")
def compiled(exported, tmp_path_factory):
    """The exported C, compiled."""
    return CController(compile_shared(exported[0], tmp_path_factory.mktemp("lib") / "l.so"))


@needs_cc
def test_c_and_python_creep_law_agree_on_creep_landings(compiled, creep_samples):
    # every sample of the exact creep landing through both steps: the same status (the
    # creep law's takeover decided alike), and the creep law's force to the last bit
    c, ws = compiled, bb.workspace()
    assert CREEP_LANDINGS[0][:3] == (-1.0, 1.0, 1.5) and creep_samples.landings == 2
    creeping = 0
    for k in creep_samples.exact:
        Pp, Pc, Mp, Mc = k.P.copy(), k.P.copy(), k.M.copy(), k.M.copy()
        sp = int(bb.control_step(Pp, Mp, k.x.copy(), k.a_f, k.u, k.h, k.estimate, *ws))
        sc = c.control_step(Pc, Mc, k.x.copy(), k.a_f, k.u, k.h, k.estimate)
        assert sc == sp and np.array_equal(Mc, Mp) and np.array_equal(Pc, Pp)
        if sp == bb.CREEP_LAW:
            creeping += 1
            u = float(Mp[bb.M_UCREEP])
            assert Mc[bb.M_PHASE] == bb.CREEPING and abs(u) <= Pp[bb.P_UMAX]
            # sl_force holds the creep law's force, as the Python schedule
            for t in (0.0, 0.5 * Pp[bb.P_PERIOD], 10.0):
                assert c.force(Pc, Mc, t) == u == float(plan_forces(Pp, Mp, t))
            h = float(Pp[bb.P_PERIOD])
            assert np.array_equal(c.force_integrals(Pc, Mc, h), plan_force_integrals(Pp, Mp, h))
    assert creeping >= 40 and creeping >= len(creep_samples.exact) - 5, creeping
    # and the comparison of both (the filtered landing's steps too)
    result = compare_calls(c, creep_samples.exact, creep_samples.landings)
    assert result.worst() == 0.0 and result.statuses["creep law"] == creeping
    filtered = compare_steps(c, creep_samples.filtered)
    assert filtered.worst() == 0.0 and filtered.statuses["creep law"] >= 60, filtered.statuses


@needs_cc
def test_c_and_python_stroke_guard_agree_on_a_short_stroke(compiled):
    # the short stroke's creep landing, where the creep law's stroke guard limits the force
    # (tests/softlanding/control/test_creep.py): every sample alike to the last bit
    short = dataclasses.replace(PAPER_ROBOT, s=3.0)
    calls = creep_calls(short, ((-1.0, 0.5, 0.5, 0.0, 0),))
    assert calls.landings == 1 and len(calls.exact) > 100
    result = compare_calls(compiled, calls.exact, calls.landings)
    assert result.worst() == 0.0 and result.statuses["creep law"] > 100


@needs_cc
def test_the_check_compares_creep_law_samples(exported):
    check = exported[1]["check"]
    cl = check["creep_landings"]
    assert cl["landings"] == len(CREEP_LANDINGS)
    assert cl["statuses"]["creep law"] >= 40 and cl["filtered_statuses"]["creep law"] >= 60
    assert all(v <= TOLERANCE for v in (*cl["max_relative_difference"].values(),
                                        *cl["filtered_max_relative_difference"].values())), cl
    assert check["creep_law_samples"] >= cl["statuses"]["creep law"] + \
        cl["filtered_statuses"]["creep law"] + check["statuses"]["creep law"]


@pytest.mark.slow
@needs_cc
def test_the_creep_comparison_sees_a_changed_constant(exported, creep_samples, tmp_path):
    # an honest comparison: the cruise's gain off by 1e-7 shows in the creep law's force
    header = (exported[0] / HEADER).read_text()
    line = "#define SL_CREEP_GAIN       0.5\n"
    assert header.count(line) == 1
    mutant = tmp_path / "mutant"
    mutant.mkdir()
    (mutant / HEADER).write_text(header.replace(line, line.replace("0.5", "0.5000001")))
    (mutant / SOURCE).write_text((exported[0] / SOURCE).read_text())
    c = CController(compile_shared(mutant, tmp_path / "mutant.so"))
    result = compare_calls(c, creep_samples.exact, creep_samples.landings)
    assert result.max_relative["M"] > 1e-9 and result.max_relative["force"] > 1e-9


ROBOT_C = """
#include <stdio.h>
#include <string.h>
#include "softlanding_controller.h"
int main(void) {
    double P[SL_NP], M[SL_NM], x[4] = {10.0, -3.0, 0.0, -3.0};
    double h;
    int st, k;
    memcpy(P, SL_ROBOT_NUMBERS, sizeof P);
    h = P[SL_P_PERIOD];
    sl_new_memory(M, 0.1, 0.1, P[SL_P_K], P[SL_P_CD], 1.0, 1.0, P[SL_P_NOISE]);
    st = sl_solve_plan(P, M, x);
    printf("%d %.17g %.17g %.17g\\n", st, M[SL_M_TAU1], M[SL_M_TAU2], sl_force(P, M, 0.0));
    for (k = 0; k < 8; k++) {  /* the state the plan predicted, else moved on at its speed */
        if (M[SL_M_PRED_OK] == 1.0) {
            memcpy(x, M + SL_M_PRED, sizeof x);
        } else {
            x[0] += h * x[1];
            x[2] += h * x[3];
        }
        st = sl_control_step(P, M, x, 0.0, P[SL_P_UMAX], h, 0);
        printf("%d %.17g %.17g %.17g\\n", st, M[SL_M_TAU1], M[SL_M_TAU2], sl_force(P, M, h));
    }
    return 0;
}
"""


@needs_cc
def test_a_c_program_following_the_readme_runs_as_the_python_controller(exported, tmp_path):
    folder = exported[0]
    assert f"cc -std=c99 -O2 -ffp-contract=off -o robot robot.c {SOURCE} -lm" in \
        (folder / README).read_text()
    (tmp_path / "robot.c").write_text(ROBOT_C)
    exe = tmp_path / "robot"
    subprocess.run([*find_compiler(), *CFLAGS, "-pedantic", "-Wall", "-Werror", "-I",
                    str(folder), "-o", str(exe), str(tmp_path / "robot.c"),
                    str(folder / SOURCE), "-lm"], check=True)
    got = [[float(v) for v in ln.split()] for ln in subprocess.run(
        [str(exe)], capture_output=True, text=True, check=True).stdout.splitlines()]
    # the same calls in Python
    r = PAPER_ROBOT
    P = bb.robot_numbers(r.r_m, r.s, r.u_max, 1.0, 0.0, creep=True)
    M = bb.new_memory(0.1, 0.1, (1.0, 0.0), (1.0, 1.0), float(P[bb.P_NOISE]))
    x, h, ws = np.array([10.0, -3.0, 0.0, -3.0]), float(P[bb.P_PERIOD]), bb.workspace()
    st = bb.solve_plan(P, M, x, *ws, np.inf)
    want = [[st, M[bb.M_TAU1], M[bb.M_TAU2], float(plan_forces(P, M, 0.0))]]
    for _ in range(8):
        if M[bb.M_PRED_OK] == 1.0:
            x = M[bb.M_PRED:bb.M_PRED + 4].copy()
        else:
            x = x + h * np.array([x[1], 0.0, x[3], 0.0])
        st = bb.control_step(P, M, x, 0.0, r.u_max, h, False, *ws)
        want.append([st, M[bb.M_TAU1], M[bb.M_TAU2], float(plan_forces(P, M, h))])
    assert got == want
    assert want[0][0] == bb.OK and {w[0] for w in want[1:]} <= {bb.OK, bb.CONVERGING, bb.HOLDS}
    assert len({w[1] for w in want}) == len(want)  # a new plan every sample


@pytest.mark.parametrize("args,match", [
    (("--period", "0"), "--period"), (("--noise-std", "nan"), "--noise-std"),
    (("--margin", "-1"), "--margin"), (("--l0", "3"), "does not apply"),
    (("--model-cd", "0.2"), "applies to --model-ground drag"),
    (("--model-ground", "drag"), "is required"), (("--rm", "-1"), "--rm"),
    (("--estimator", "filtered"), "--noise-std > 0")])
def test_bad_input_one_line_exit_2_nothing_written(args, match, tmp_path, cli):
    code, out, err = cli("export-controller", "--out", tmp_path / "c", *args)
    assert code == 2 and match in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "c").exists() and out == ""


def test_an_existing_folder_is_kept_unless_force(tmp_path, cli):
    folder = tmp_path / "c"
    folder.mkdir()
    (folder / "mine.txt").write_text("keep")
    code, _, err = cli("export-controller", "--out", folder)
    assert code == 2 and "--force" in err and sorted(p.name for p in folder.iterdir()) == \
        ["mine.txt"]
    code, out, _ = cli("export-controller", "--out", folder, "--force", "--s", "10")
    assert code == 0 and "s = 10" in out
    assert (folder / "mine.txt").read_text() == "keep" and (folder / SOURCE).exists()
    assert not [p for p in tmp_path.iterdir() if p.name != "c"]  # no temporary left


def test_a_failed_check_leaves_nothing(tmp_path, cli, monkeypatch):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    code, _, err = cli("export-controller", "--out", tmp_path / "c", "--check")
    assert code == 2 and "needs a C compiler" in err
    from softlanding.control.export_c import check
    from softlanding.errors import ExportError

    def fails(folder):
        raise ExportError("the compiled C differs")

    monkeypatch.delenv("CC")
    monkeypatch.setattr(check, "check_export", fails)
    code, _, err = cli("export-controller", "--out", tmp_path / "c", "--check")
    assert code == 1 and "differs" in err and list(tmp_path.iterdir()) == []


def test_help_explains(cli):
    code, out, _ = cli("export-controller", "--help")
    assert code == 0 and "libm" in out and "--check" in out and "SL_ROBOT_NUMBERS" in out


# ---- the foot filter ----------------------------------------------------------------------

NOISE = 1e-3


@pytest.fixture(scope="module")
def exported_filtered(tmp_path_factory):
    """The paper's robot exported for the filtered estimate at sensor noise 1e-3 (no check)."""
    folder = tmp_path_factory.mktemp("export") / "filtered"
    code, out, err = _run("export-controller", "--out", folder, "--json", "--noise-std", NOISE,
                          "--estimator", "filtered")
    assert code == 0, err
    return folder, json.loads(out)


def test_the_header_holds_the_filters_numbers(exported_filtered):
    folder, d = exported_filtered
    got = _defines((folder / HEADER).read_text())
    idx = layout.indices("F_")
    assert idx == {k: v for k, v in vars(ff).items() if k.startswith("F_")}
    assert all(int(got[k]) == v for k, v in idx.items()) and int(got["NF"]) == ff.NF
    for name in layout.FILTER_CONSTANTS:
        assert float(got[f"FILTER_{name}"]) == getattr(ff, name)
    assert float(got["FILTER_START_VAR"]) == ff.START_STD ** 2
    assert max(idx.values()) < ff.NF and ff.F_U2 + 2 < ff.NF  # the second sample's integrals
    # the numbers are the filtered estimate's, the sensor noise the filter's
    r = PAPER_ROBOT
    assert d["estimator"] == "filtered" and d["sensor_noise"] == NOISE
    assert d["numbers"]["NOISE"] == bb.ground_force_noise(r.r_m, NOISE, True) != \
        bb.ground_force_noise(r.r_m, NOISE)
    src = (folder / SOURCE).read_text()
    assert re.search(r"const double SL_SENSOR_NOISE = (\S+);", src).group(1) == "0.001"
    # the filtered estimate's weights and recovery: from the Python modules
    for module, name in layout.FILTERED_CONSTANTS:
        assert float(got[name]) == getattr(module, name)
    assert {name for _, name in layout.FILTERED_CONSTANTS} == {
        "FILTERED_REGRESSOR", "MIN_WEIGHT", "RECOVERY_SAMPLES"}
    assert (int(got["RECOVERY_SAMPLES"]), float(got["MIN_WEIGHT"])) == (
        recovery.RECOVERY_SAMPLES, estimation.MIN_WEIGHT)


def test_a_filter_entry_the_export_does_not_describe_fails_the_export(monkeypatch):
    monkeypatch.setattr(ff, "F_NEW", ff.NF, raising=False)
    with pytest.raises(KeyError, match="foot_filter has F_NEW"):
        layout.layout_lines("F_")


@needs_cc
def test_c_and_numba_filters_agree_on_600_samples_of_noisy_landings(exported):
    f = exported[1]["check"]["filter"]
    assert f["steps"] == 600 and f["landings"] >= 15, f
    assert all(v <= TOLERANCE for v in f["max_relative_difference"].values()), f
    # every path of the filter: the provisional first two, their redo at the third, the
    # quadratic, the chord of a sample of another length, and the innovation check
    p = f["paths"]
    assert p["first"] == p["second"] == f["landings"] and p["redo"] >= 10, p
    assert p["quadratic"] >= 100 and p["chord"] >= 20 and p["widened"] >= 20, p
    assert f["plans"] >= f["steps"]  # the force integrals of each sample's plan


@needs_cc
def test_the_filter_comparison_sees_a_changed_constant(exported_filtered, tmp_path):
    # an honest comparison: the process noise off by 1e-7 shows, the probes alone (the fast
    # draggy impact's 40 samples, the innovation check's path among them)
    folder = exported_filtered[0]
    mutant = tmp_path / "mutant"
    mutant.mkdir()
    header = (folder / HEADER).read_text()
    assert header.count("#define SL_FILTER_PROCESS      0.5\n") == 1
    (mutant / HEADER).write_text(header.replace("#define SL_FILTER_PROCESS      0.5\n",
                                                "#define SL_FILTER_PROCESS      0.5000001\n"))
    (mutant / SOURCE).write_text((folder / SOURCE).read_text())
    c = CController(compile_shared(mutant, tmp_path / "mutant.so"))
    assert PROBES[0][:3] == (-10.0, 0.5, 1.0)
    result = compare_filter(c, 40)
    assert result.paths["widened"] >= 1  # the probe went through the innovation check
    assert result.max_relative["F"] > 1e-9 and result.max_relative["force integrals"] == 0


@needs_cc
def test_c_and_python_filtered_steps_agree_with_weights_and_recovery(exported):
    f = exported[1]["check"]["filtered_steps"]
    assert f["steps"] == 600 and all(v <= TOLERANCE for v in
                                     f["max_relative_difference"].values()), f
    # weighted samples, and the bounded full solve: converged, deferred over samples, and
    # given up after RECOVERY_SAMPLES deferred in a row (the fast draggy probes)
    assert f["weighted"] >= 300, f
    r = f["recovery"]
    assert r["recovered"] >= 1 and r["recovery deferred"] >= recovery.RECOVERY_SAMPLES, r
    assert r["recovery failed"] >= 1, r
    assert f["statuses"]["deferred"] >= r["recovery deferred"], f
    # and the weight's edges on a grid: no weight, weighted, the least weight
    assert all(v >= 50 for v in f["weight_grid"].values()), f["weight_grid"]


@pytest.fixture(scope="module")
def probe_steps():
    """The filtered samples of the probes' landings (the fast draggy ones whose push needs
    the bounded full solve among them)."""
    return filtered_calls(PAPER_ROBOT, 260).steps


@needs_cc
@pytest.mark.parametrize("name,value,changed", [
    ("FILTERED_REGRESSOR", "0.1000001", "weight"),
    pytest.param("MIN_WEIGHT", "1.000001e-06", "weight", marks=pytest.mark.slow),
    ("RECOVERY_SAMPLES", "5", "status")])
def test_the_filtered_step_comparison_sees_a_changed_constant(
        exported_filtered, probe_steps, tmp_path, name, value, changed):
    # an honest comparison: the weights' allowance or least weight off by 1e-6 shows in the
    # weights, one deferral fewer allowed in the statuses (the probes defer 6 samples in a
    # row)
    folder = exported_filtered[0]
    header = (folder / HEADER).read_text()
    line = re.search(rf"^#define SL_{name} +(\S+)$", header, re.M)
    python = {n: getattr(m, n) for m, n in layout.FILTERED_CONSTANTS}
    assert line and float(line.group(1)) == python[name] != float(value)
    mutant = tmp_path / "mutant"
    mutant.mkdir()
    (mutant / HEADER).write_text(header.replace(line.group(0),
                                                line.group(0).replace(line.group(1), value)))
    (mutant / SOURCE).write_text((folder / SOURCE).read_text())
    c = CController(compile_shared(mutant, tmp_path / "mutant.so"))
    result = compare_steps(c, probe_steps)
    assert result.outcomes["recovery deferred"] >= 6 and result.outcomes["recovery failed"]
    assert result.max_relative[changed] > 1e-9, result.max_relative
    if changed == "status":  # (the weights do not depend on it)
        assert result.max_relative["weight"] == 0


FILTER_C = """
#include <stdio.h>
#include <string.h>
#include "softlanding_controller.h"
int main(void) {
    double P[SL_NP], M[SL_NM], F[SL_NF], U[2], x[4] = {10.0, -3.0, 0.0, -3.0}, e[3], E[4];
    double h, u, a_f, w;
    int st, k, j, widened, fit, recovering = 0;
    memcpy(P, SL_ROBOT_NUMBERS, sizeof P);
    h = P[SL_P_PERIOD];
    sl_new_memory(M, 0.1, 0.1, P[SL_P_K], P[SL_P_CD], 1.0, 1.0, P[SL_P_NOISE]);
    st = sl_solve_plan(P, M, x);
    sl_filter_init(F, x);
    for (k = 0; k < 12; k++) {
        sl_force_integrals(P, M, h, U);  /* the force over the sample, before the step */
        u = sl_force(P, M, h);
        if (M[SL_M_PRED_OK] == 1.0) {  /* the plan's prediction, measured with noise */
            memcpy(x, M + SL_M_PRED, sizeof x);
        } else {
            x[0] += h * x[1];
            x[2] += h * x[3];
        }
        a_f = P[SL_P_AF0] + P[SL_P_BF] * u + P[SL_P_GF] * (P[SL_P_K] * -x[2]);
        for (j = 0; j < 3; j++)
            e[j] = SL_SENSOR_NOISE * (((k * 7 + j * 3) % 11 - 5) / 2.0);
        x[2] += e[0];
        x[3] += e[1];
        a_f += e[2];
        widened = sl_filter_step(F, x, a_f - P[SL_P_BF] * u, U[0], U[1], h, P[SL_P_BF],
                                 SL_SENSOR_NOISE);
        fit = F[SL_F_N] > SL_FILTER_PROVISIONAL;
        w = fit ? sl_filtered_weight(P, M, F, x, a_f, u) : 1.0;
        st = sl_filtered_step(P, M, x, a_f, u, h, fit, w, &recovering);
        sl_ground_estimate(P, M, E);
        printf("%d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %d\\n", st, widened,
               x[2], x[3], M[SL_M_TAU1], M[SL_M_TAU2], E[0], E[1], E[2], E[3], w, recovering);
    }
    return 0;
}
"""


@needs_cc
def test_a_c_program_filtering_as_the_readme_runs_as_python(exported_filtered, tmp_path):
    folder = exported_filtered[0]
    readme = (folder / README).read_text()
    assert "sl_filter_step(F, x, a_f - P[SL_P_BF] * u, U[0], U[1], h, P[SL_P_BF]," in readme
    assert "st = sl_filtered_step(P, M, x, a_f, u, h, fit, w, &recovering);" in readme
    (tmp_path / "robot.c").write_text(FILTER_C)
    exe = tmp_path / "robot"
    subprocess.run([*find_compiler(), *CFLAGS, "-pedantic", "-Wall", "-Werror", "-I",
                    str(folder), "-o", str(exe), str(tmp_path / "robot.c"),
                    str(folder / SOURCE), "-lm"], check=True)
    got = [[float(v) for v in ln.split()] for ln in subprocess.run(
        [str(exe)], capture_output=True, text=True, check=True).stdout.splitlines()]
    # the same in Python: the numba controller and filter, the Python schedule's integrals,
    # the filtered sample of control.recovery
    r = PAPER_ROBOT
    P = bb.robot_numbers(r.r_m, r.s, r.u_max, 1.0, 0.0, bb.ground_force_noise(r.r_m, NOISE, True),
                         creep=True)
    M = bb.new_memory(0.1, 0.1, (1.0, 0.0), (1.0, 1.0), float(P[bb.P_NOISE]))
    x, h, ws = np.array([10.0, -3.0, 0.0, -3.0]), float(P[bb.P_PERIOD]), bb.workspace()
    bb.solve_plan(P, M, x, *ws, np.inf)
    F = ff.new_filter(x)
    est = GroundEstimator(r)
    want = []
    recovering = 0
    for k in range(12):
        U = plan_force_integrals(P, M, h)
        u = float(plan_forces(P, M, h))
        if M[bb.M_PRED_OK] == 1.0:
            x = M[bb.M_PRED:bb.M_PRED + 4].copy()
        else:
            x = x + h * np.array([x[1], 0.0, x[3], 0.0])
        a_f = P[bb.P_AF0] + P[bb.P_BF] * u + P[bb.P_GF] * (P[bb.P_K] * -x[2])
        e = [NOISE * (((k * 7 + j * 3) % 11 - 5) / 2.0) for j in range(3)]
        x[2] += e[0]
        x[3] += e[1]
        a_f += e[2]
        G = F.copy()  # (without the innovation check: differs where it widened)
        ff.filter_step(G, x.copy(), a_f - P[bb.P_BF] * u, U[0], U[1], h, P[bb.P_BF], 0.0)
        ff.filter_step(F, x, a_f - P[bb.P_BF] * u, U[0], U[1], h, P[bb.P_BF], NOISE)
        fit = bool(F[ff.F_N] > ff.PROVISIONAL)
        w = recovery.sample_weight(P, M, F, x, a_f, u) if fit else 1.0
        st, recovering = recovery.filtered_step(P, M, x, a_f, u, h, fit, w, recovering, *ws)
        want.append([st, float(not np.array_equal(F, G)), x[2], x[3], M[bb.M_TAU1],
                     M[bb.M_TAU2], *ground_estimate(P, M, est), w, recovering])
    assert len(want) == 12 and got == want
    assert {w[0] for w in want} <= {bb.OK, bb.CONVERGING, bb.HOLDS}
    assert want[1][6] == 1.0 and want[2][6] != 1.0  # no fit from the provisional samples
    assert want[-1][8] < 0.1 * want[1][8]  # the estimate's uncertainty fell
    assert all(w[10] < 1 for w in want[2:])  # the fit's samples weighed by the filter's error


@pytest.mark.slow
@needs_cc
def test_c_and_numba_filters_and_filtered_steps_agree_on_5000_more_samples(exported, tmp_path):
    c = CController(compile_shared(exported[0], tmp_path / "lib.so"))
    calls = filtered_calls(PAPER_ROBOT, 5000, seed=1)
    result = compare_filter(c, 5000, 1, calls)
    assert result.steps == 5000 and result.worst() == 0.0, result.describe()
    assert result.paths["widened"] >= 100 and result.paths["redo"] >= 100, result.paths
    steps = compare_steps(c, calls.steps)  # and the filtered step on them
    assert steps.steps == 5000 and steps.worst() == 0.0, steps.describe()
    assert steps.weighted >= 2500 and steps.outcomes["recovered"] >= 1, steps.describe()


@needs_cc
def test_a_non_finite_input_is_refused_and_the_filter_goes_on(compiled):
    # one NaN sample left the exported filter NaN for good (status 0, "not widened"), and a
    # NaN weight gave a covered status with the estimate's covariance NaN
    c = compiled
    F = c.filter_init(np.array([10.0, -3.0, 0.0, -3.0]))
    x = np.array([10.0, -3.0, -0.03, -2.9])
    beta = bb.force_coefficients(PAPER_ROBOT.r_m)[0]
    for bad in (dict(g=np.nan), dict(U1=np.inf), dict(x2=np.nan), dict(h=0.0)):
        kw = dict(g=1.0, U1=0.08, U2=4e-4, h=0.01, x2=-0.03) | bad
        F0, xb = F.copy(), x.copy()
        xb[2] = kw["x2"]
        assert c.filter_step(F, xb, kw["g"], kw["U1"], kw["U2"], kw["h"], beta, 1e-3) == -1
        assert np.array_equal(F, F0, equal_nan=True)
    assert c.filter_step(F, x.copy(), 1.0, 0.08, 4e-4, 0.01, beta, 1e-3) in (0, 1)
    assert np.all(np.isfinite(F))
    P = np.ascontiguousarray(c.robot_numbers)
    M = c.new_memory(0.1, 0.05, (1.0, 0.0), (1.0, 1.0), float(P[bb.P_NOISE]))
    P0, M0 = P.copy(), M.copy()
    assert c.filtered_step(P, M, x, 2.0, 8.2, 0.01, True, np.nan, 0) == (-1, 0)
    assert np.array_equal(P, P0) and np.array_equal(M, M0)


@needs_cc
def test_the_exported_arrest_force_is_saturated_at_the_limit(compiled):
    # a plan whose body reaches the foot's stop fast with little stroke left: the arrest's
    # constant force would be far beyond u_max; sl_force gives u_max, as the Python schedule
    c = compiled
    P = np.ascontiguousarray(c.robot_numbers)
    M = c.new_memory(0.0, 0.05, (1.0, 0.0), (1.0, 1.0), float(P[bb.P_NOISE]))
    M[bb.M_XBT], M[bb.M_VBT], M[bb.M_XFT] = 0.5, -6.0, -1.0  # (stroke 1.5, v_b = -6)
    t = 0.06
    assert c.force(P, M, t) == P[bb.P_UMAX] == float(plan_forces(P, M, np.array([t]))[0])
    assert np.array_equal(c.force_integrals(P, M, 0.2), plan_force_integrals(P, M, 0.2))
