"""A researcher's own variant (issue 47): a module given as ``module:attribute`` is listed
with its options, names its own output and shows its objective in a sweep; a module that
fails (at import, in its declaration or in its solve) is one line naming it, exit 2, and the
other variants keep working."""

import json
import textwrap

import pytest

# A user's variant, quick to run: the rigid leg's depth 1 + sqrt(1 + v0^2) (paper, eq. 10)
# and a "peak" it minimises. Its result names itself "min-peak-force", as a copy of the
# packaged module's result class would.
QUICK = '''
import math
from softlanding.optimal import Option, Variant


class Result:
    notes = []
    path = "analytic"

    def __init__(self, v0, scale):
        self.depth = 1 + math.sqrt(1 + v0 ** 2)
        self.peak = scale * abs(v0)

    def rows(self):
        return [("variant", "min-peak-force"), ("depth", self.depth), ("peak", self.peak)]

    def to_dict(self):
        return {"variant": "min-peak-force", "depth": self.depth, "peak": self.peak}

    def figures(self, certificate=None):
        return []

    def certify(self):
        return None

    def uncertified_reason(self):
        return "no certificate: an analytic variant"

    def unverified_reasons(self, certificate=None):
        return []


def solve(impact, robot, ground, *, refine, warm_start, scale):
    if scale == 13:
        return 1 / 0  # a bug in the user's code
    if scale == 7:
        return {"depth": 1.0}  # not a result the command line can print
    return Result(impact.v0, scale)


VARIANT = Variant("quick-peak", "the rigid depth and a peak", solve,
                  objective=("peak", "peak force"),
                  options=(Option("scale", float, 2.0, "the peak per unit speed"),))
'''

BROKEN = {  # module text -> what the one line must say
    "raises": ("raise RuntimeError('boom at import')\n", "RuntimeError: boom at import"),
    "syntax": ("def broken(:\n    pass\n", "SyntaxError"),
    "options": ("from softlanding.optimal import Variant\n"
                "VARIANT = Variant('x', 'bad options', lambda *a, **k: None, "
                "options=('depth_max',))\n", "options must be a tuple of Option"),
    "exits": ("import sys\nsys.exit(7)\n", "called sys.exit(7)"),
}


@pytest.fixture
def modules(tmp_path, monkeypatch):
    """Write modules with names unique to the test (sys.modules keeps what it imported)."""
    monkeypatch.syspath_prepend(str(tmp_path))
    tag = tmp_path.name.replace("-", "_").lower()

    def write(stem, text):
        name = f"{stem}_{tag}"
        (tmp_path / f"{name}.py").write_text(textwrap.dedent(text))
        return name

    return write


@pytest.mark.parametrize("kind", list(BROKEN))
def test_a_broken_module_is_one_line_naming_it_exit_2(cli, modules, kind):
    text, said = BROKEN[kind]
    mod = modules(f"broken_{kind}", text)
    for args in (["solve", "--v0", "-3", "--variant", f"{mod}:VARIANT"],
                 ["solve-sweep", "--variant", f"{mod}:VARIANT"],
                 ["variants", "--variant", f"{mod}:VARIANT"]):
        code, out, err = cli(*args)
        assert code == 2 and out == "", (args, err)
        assert err.count("\n") == 1 and mod in err and said in err, err
        assert "internal error" not in err and "Traceback" not in err
    code, out, _ = cli("variants")  # the others keep working
    assert code == 0 and "min-peak-force" in out


def test_a_broken_installed_plug_in_leaves_the_others_listed(cli, modules, tmp_path):
    mod = modules("plugin", "raise ImportError('a missing dependency')\n")
    info = tmp_path / "brokenpkg-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: brokenpkg\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[softlanding.variants]\nbroken = {mod}:VARIANT\n")
    code, out, err = cli("variants", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert {"paper", "two-phase", "leg-extension", "min-peak-force"} <= {
        v["name"] for v in d["variants"]}
    assert len(d["not_loaded"]) == 1 and "brokenpkg" in d["not_loaded"][0]
    assert err.count("\n") == 1 and "a missing dependency" in err
    code, out, err = cli("solve", "--help")
    assert code == 0 and "--depth-max" in out and "brokenpkg" in err
    code, out, err = cli("solve", "--v0", "-3", "--variant", "broken")
    assert code == 2 and err.count("\n") == 1 and "a missing dependency" in err


def test_a_users_variant_is_listed_with_its_options(cli, modules):
    mod = modules("quick", QUICK)
    code, out, err = cli("variants", "--variant", f"{mod}:VARIANT")
    assert code == 0, err
    assert f"quick-peak ({mod}:VARIANT): the rigid depth and a peak" in out
    assert "--scale (number, default 2): the peak per unit speed" in out
    code, out, _ = cli("variants", "--json", "--variant", f"{mod}:VARIANT")
    mine = [v for v in json.loads(out)["variants"] if v["name"] == "quick-peak"]
    assert mine[0]["source"] == "module" and mine[0]["options"][0]["type"] == "number"
    code, out, _ = cli("solve", "--help", "--variant", f"{mod}:VARIANT")
    assert code == 0 and "--scale" in out and "quick-peak: the peak per unit speed" in out


def test_an_option_default_json_cannot_hold_is_listed_as_text(cli, modules):
    mod = modules("odd_default", "from softlanding.optimal import Option, Variant\n"
                  "VARIANT = Variant('odd', 'a complex default', 'x:y', options=("
                  "Option('z', complex, 1j, 'a complex number'),))\n")
    code, out, err = cli("variants", "--json", "--variant", f"{mod}:VARIANT")
    assert code == 0, err
    odd = [v for v in json.loads(out)["variants"] if v["name"] == "odd"][0]
    assert odd["options"][0]["default"] == "1j"


def test_a_users_variant_names_its_output_and_its_bug(cli, modules, tmp_path):
    """The name comes from the Variant that ran, not from the result class it reuses; a
    bug inside its solve is the user's (one line: module, file and line), not ours."""
    mod = modules("quick", QUICK)
    code, out, err = cli("solve", "--v0", "-3", "--variant", f"{mod}:VARIANT", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["variant"] == "quick-peak" and d["variant_from"] == f"{mod}:VARIANT"
    assert d["depth"] == pytest.approx(1 + 10 ** 0.5, abs=1e-15)
    code, out, err = cli("solve", "--v0", "-3", "--variant", f"{mod}:VARIANT")
    assert code == 0 and f"variant   quick-peak ({mod}:VARIANT)" in out
    assert "min-peak-force" not in out
    code, out, err = cli("solve", "--v0", "-3", "--variant", f"{mod}:VARIANT", "--scale", "13")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert f"{mod}:VARIANT: raised ZeroDivisionError ({mod}.py, line" in err
    assert "internal error" not in err
    code, out, err = cli("solve", "--v0", "-3", "--variant", f"{mod}:VARIANT", "--scale", "7")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "returned a dict without depth, notes, rows, to_dict" in err


def test_a_sweep_shows_the_variants_objective(cli, modules, tmp_path):
    mod = modules("quick", QUICK)
    png = tmp_path / "sweep.png"
    code, out, err = cli("solve-sweep", "--variant", f"{mod}:VARIANT", "--v0-min", "-3",
                         "--v0-max", "-1", "--n", "3", "--plot", png)
    assert code == 0, err
    lines = out.splitlines()
    assert "minimising peak force" in lines[0] and "peak force" in lines[1]
    assert lines[4].split()[:3] == ["-3.000", f"{1 + 10 ** 0.5:.10f}", "6.0000000000"]
    code, out, err = cli("solve-sweep", "--variant", f"{mod}:VARIANT", "--v0-min", "-3",
                         "--v0-max", "-1", "--n", "3", "--json")
    d = json.loads(out)
    assert d["objective"] == "peak" and [r["objective"] for r in d["sweep"]] == [2, 4, 6]
    from softlanding.plots.phased import plot_variant_sweep

    fig = plot_variant_sweep([-1, -3], [1, 2], "x", ("peak force", [2, 6]))
    assert [a.get_ylabel() for a in fig.axes][1] == "peak force"
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_another_variants_option_does_not_apply(cli):
    """`--nodes` with two-phase said "does not apply", `--depth-max` "unrecognized"."""
    for flag, value in (("--nodes", "50"), ("--depth-max", "2"), ("--steps", "2")):
        variant = "paper" if flag == "--steps" else "two-phase"
        code, out, err = cli("solve", "--v0", "-3", "--variant", variant, flag, value)
        assert code == 2 and out == "" and err.count("\n") == 1, err
        assert f"{flag}: does not apply to --variant {variant}" in err
    code, _, err = cli("solve", "--v0", "-3", "--variant", "two-phase", "--depht-max", "2")
    assert code == 2 and "unrecognized arguments: --depht-max" in err


def test_variants_show_one_default_and_a_readable_type(cli):
    code, out, _ = cli("variants")
    assert code == 0
    rate = next(ln for ln in out.splitlines() if "--rate-max" in ln)
    assert rate.count("default") == 1 and "(number, default 0)" in rate
    assert "extension_value" not in out and "--extension ('free' or a length, default free)" \
        in out
    for line in out.splitlines():
        assert line.count("default") <= 1, line


def test_a_long_figure_title_is_wrapped_inside_the_figure():
    """An unrefined result's title ran off both sides of its figure."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    from softlanding.plots.phased import plot_phases

    title = ("least peak force (transcribed, not refined), $v_0$=-3, $r_m$=5, $s$=20, "
             "$u_{max}$=8.2, drag, $c_d$ = 0.2, stiffness = 2: depth 2.016296 (depth "
             "budget: 2.016300)")
    t = np.linspace(0, 1, 5)
    fig = plot_phases(t, np.zeros((5, 4)), t, [(0.0, 1.0, "yielding")], title)
    fig.canvas.draw()
    box = fig._suptitle.get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width
    assert fig._suptitle.get_text().replace("\n", " ") == title
