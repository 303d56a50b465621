"""The variant table refuses every option a variant would ignore; bad input is one line, exit 2,
checked before the heavy libraries load."""

import json
import subprocess
import sys

import pytest

from softlanding.cli.output import FIGURE_FORMATS
from softlanding.optimal.variants import PIPELINE_OPTIONS, all_variants

IGNORED = [  # (arguments, the option named in the refusal)
    (["--variant", "two-phase", "--mode", "drop"], "--mode"),
    (["--variant", "two-phase", "--extension", "5"], "--extension"),
    (["--variant", "two-phase", "--extra-arcs", "3"], "--extra-arcs"),
    (["--variant", "two-phase", "--nodes", "50"], "--nodes"),
    (["--variant", "two-phase", "--steps", "2", "--pmp"], "--pmp"),
    (["--variant", "two-phase", "--steps", "2", "--no-refine"], "--no-refine"),
    (["--variant", "paper", "--steps", "2"], "--steps"),
    (["--steps", "1"], "--steps"),  # the default value, but still not the paper's option
    (["--variant", "paper", "--rate-max", "1"], "--rate-max"),
    (["--variant", "leg-extension", "--mode", "drop", "--extension", "5"], "--extension"),
    (["--variant", "leg-extension", "--mode", "drop", "--rate-max", "1"], "--rate-max"),
    (["--variant", "leg-extension", "--ground", "drag", "--cd", "1"], "--ground"),
    (["--variant", "two-phase", "--steps", "2", "--ground", "drag", "--cd", "1"], "--ground"),
]


@pytest.mark.parametrize("args,option", IGNORED)
def test_an_option_the_variant_ignores_is_refused(cli, args, option):
    code, out, err = cli("solve", "--v0", "-3", *args)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and option in err and "does not apply" in err or (
        option == "--ground" and "linear ground" in err)


def test_every_variant_option_applies_somewhere():
    """An option its variant takes in no mode would be refused everywhere: a dead option."""
    for v in all_variants():
        claimed = set()
        for steps in (None, 2):
            for mode in (None, "drop"):
                claimed |= v.applicable({"steps": steps, "mode": mode})
        assert set(v.option_names()) <= claimed, v.name
        assert set(PIPELINE_OPTIONS) - {"no_refine"} <= claimed, v.name


BAD = [  # each a distinct class of bad input the CLI once called a bug or ignored
    ["solve", "--v0", "-3", "--plot", "fig.xyz"],
    ["demo", "--out", "demo.xyz"],
    ["map", "--v0", "-3", "--n", "5", "--out", "m.nc", "--scheduler", "garbage"],
    ["map", "--v0", "-3", "--n", "5", "--out", "m.nc", "--scheduler", "tcp://host:99999"],
    ["sweep", "--n", "1", "--grid", "11", "--objective", "cot"],
    ["solve", "--v0", "-3", "--variant", "leg-extension", "--extension", "abc"],
    ["solve", "--v0", "-3", "--variant", "leg-extension", "--extension", "nan"],
    ["solve", "--v0", "-3", "--variant", "leg-extension", "--rate-max", "-1"],
    ["solve", "--v0", "-3", "--variant", "leg-extension", "--rate-max", "1e308"],  # issue 47
    ["solve", "--v0", "-3", "--nodes", "1"],
    ["solve", "--v0", "-3", "--extra-arcs", "21"],
    ["hop", "--v0=-1e-300"],
    ["hop", "--v0", "-3", "--grid", "0"],
    ["hop", "--v0", "-3", "--leg", "impedance", "--grid", "100000"],
    ["hop", "--v0", "-3", "--leg", "impedance", "--grid", "1"],
    ["hop", "--v0", "-3", "--doublings", "5"],
    ["hop", "--v0", "-3", "--leg", "rigid", "--doublings", "1"],
    ["impedance", "--v0", "-3", "--grid", "100000"],
    ["compare", "--grid", "1"],
    ["solve-sweep", "--nodes", "0"],
    ["sweep", "--rm", "5", "--rm", "-1"],
]


@pytest.mark.parametrize("args", BAD, ids=[" ".join(a) for a in BAD])
def test_bad_input_is_one_line_exit_2(cli, tmp_path, monkeypatch, args):
    monkeypatch.chdir(tmp_path)
    code, out, err = cli(*args)
    assert code == 2, err
    assert err.count("\n") == 1 and "internal error" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_bad_input_is_refused_before_the_heavy_libraries_load(tmp_path):
    """Refusing input must not cost the 0.5-2 s of loading numba, CasADi or xarray."""
    code = (
        "import sys\n"
        "from softlanding.cli import main\n"
        "heavy = ('numba', 'casadi', 'xarray', 'matplotlib', 'scipy')\n"
        "out = {}\n"
        f"for args in {[a for a in BAD if a[0] != 'sweep' or '--rm' in a] + IGNORED_ARGV!r}:\n"
        "    try:\n"
        "        rc = main(args)\n"
        "    except SystemExit as e:\n"
        "        rc = e.code\n"
        "    out[' '.join(args)] = [rc, sorted({m.split('.')[0] for m in sys.modules} & "
        "set(heavy))]\n"
        "print(__import__('json').dumps(out))\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=tmp_path, check=True)
    for args, (rc, loaded) in json.loads(p.stdout.splitlines()[-1]).items():
        assert rc == 2 and loaded == [], (args, loaded)


IGNORED_ARGV = [["solve", "--v0", "-3", *a] for a, _ in IGNORED]


def test_figure_formats_are_matplotlibs():
    from matplotlib.backend_bases import FigureCanvasBase

    assert set(FIGURE_FORMATS) == set(FigureCanvasBase.get_supported_filetypes())


def test_sweep_with_no_feasible_gains_reports_it(cli):
    # an infeasible problem exits 1 with one line, as `solve --json` does (it exited 0 with
    # the observations {"feasible_velocities": 0} before an adversarial review)
    code, out, err = cli("sweep", "--n", "2", "--grid", "11", "--s", "0.1", "--json")
    assert code == 1 and out == ""
    assert err.count("\n") == 1 and "no gains in [0, 1]^2 keep the stroke" in err


@pytest.mark.parametrize(("given", "shown"), [("-1", "got -1"), ("1e9", "got 1000000000")])
def test_an_extension_outside_the_stroke_shows_the_value_given(cli, given, shown):
    code, _, err = cli("solve", "--v0", "-3", "--variant", "leg-extension", "--extension", given)
    assert code == 2 and err.rstrip().endswith(f"within the stroke [0, 20], {shown}"), err
