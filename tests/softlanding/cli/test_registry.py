"""Variants are one module each: the CLI's options and `softlanding variants` come from the
registry; a variant outside the package runs through `--variant module:attribute`; the
packaged `min-peak-force` answers the inverse of the two-phase landing's depth."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from softlanding.optimal.variants import Option, find_variant

PACKAGED = Path(__file__).resolve().parents[3] / "softlanding" / "optimal" / "min_peak_force.py"
V0 = -3.0
LEAST = 1.516295632282  # the two-phase least depth at v0 = -3 (tests/softlanding/cli)


def test_variants_json_lists_every_variant_with_its_options_and_origin(cli):
    code, out, err = cli("variants", "--json")
    assert code == 0, err
    found = {v["name"]: v for v in json.loads(out)["variants"]}
    assert {"paper", "two-phase", "leg-extension", "min-peak-force"} <= set(found)
    mpf = found["min-peak-force"]
    assert (mpf["module"], mpf["attribute"]) == ("softlanding.optimal.min_peak_force",
                                                 "VARIANT")
    assert [(o["flag"], o["required"]) for o in mpf["options"]] == [("--depth-max", True)]
    assert found["two-phase"]["options"][0]["choices"] == [1, 2]
    code, out, _ = cli("variants")
    assert code == 0 and "--depth-max (number, required)" in out


BAD_DEPTH = [["--depth-max", "abc"], ["--depth-max", "-1"], ["--depth-max", "nan"],
             ["--depth-max", "inf"], []]


@pytest.mark.parametrize("args", BAD_DEPTH, ids=[" ".join(a) or "missing" for a in BAD_DEPTH])
def test_bad_depth_budget_is_one_line_exit_2(cli, args):
    code, out, err = cli("solve", "--v0", "-3", "--variant", "min-peak-force", *args)
    assert code == 2 and out == "", err
    assert err.count("\n") == 1 and "depth" in err and "internal error" not in err


def test_a_variant_that_cannot_be_found_is_one_line_exit_2(cli, tmp_path, monkeypatch):
    (tmp_path / "notavariant.py").write_text("X = 3\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("nope", "nope_module_xyz:VARIANT", "notavariant:Y", "notavariant:X"):
        code, out, err = cli("solve", "--v0", "-3", "--variant", name)
        assert code == 2 and out == "" and err.count("\n") == 1, (name, err)


def test_option_values_are_typed_and_checked():
    o = Option("depth_max", float, check=lambda d: None if d > 0 else "must be > 0",
               required=True)
    assert o.flag == "--depth-max" and o.value("2.5") == 2.5
    for bad in ("x", "-1", "nan", None):
        with pytest.raises(ValueError, match="--depth-max"):
            o.value(bad)


def _solve_json(args, env=None):
    p = subprocess.run([sys.executable, "-m", "softlanding", "solve", *args, "--json"],
                       capture_output=True, text=True, env=env)
    return p.returncode, json.loads(p.stdout) if p.stdout else None, p.stderr


@pytest.mark.slow
def test_a_copy_outside_the_package_runs_like_the_packaged_variant(tmp_path, monkeypatch):
    """The packaged module copied under another name into a folder outside the project, its
    Variant renamed: the same depth, peak, verdict and figure through --variant
    othername:VARIANT, under the new name."""
    import os

    text = PACKAGED.read_text()
    declared = 'VARIANT = Variant(\n    "min-peak-force",'
    assert declared in text
    (tmp_path / "othername.py").write_text(text.replace(  # renamed in its Variant only
        declared, 'VARIANT = Variant(\n    "my-peak-force",'))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path), str(PACKAGED.parents[2]), os.environ.get("PYTHONPATH", "")])}
    out = {}
    for name in ("min-peak-force", "othername:VARIANT"):
        png = tmp_path / f"{name.replace(':', '_')}.png"
        code, d, err = _solve_json(["--v0", str(V0), "--variant", name, "--depth-max",
                                    str(LEAST + 0.5), "--plot", str(png)], env)
        assert d is not None, err
        out[name] = (code, d, png.stat().st_size)
    (c1, a, s1), (c2, b, s2) = out.values()
    assert c1 == c2 and a["verified"] == b["verified"]
    assert a["unverified_reasons"] == b["unverified_reasons"]
    # issue 47: the output is named by the Variant that ran, not by the result class
    assert (a["variant"], b["variant"]) == ("min-peak-force", "my-peak-force")
    assert b["variant_from"] == "othername:VARIANT"
    assert abs(a["depth"] - b["depth"]) < 1e-12 and abs(a["peak"] - b["peak"]) < 1e-12
    assert s1 > 10_000 and abs(s1 - s2) < 0.02 * s1  # the same figure (same title, data)
    found = find_variant("min-peak-force")
    assert (found.module, found.source) == ("softlanding.optimal.min_peak_force", "packaged")


@pytest.mark.slow
def test_min_peak_force_is_the_inverse_of_the_two_phase_depth(cli):
    """The least peak P for the budget D = least depth + 0.5, refined with exact arcs (the
    peak with the switching times and phase durations) and certified like the two-phase
    landing: the two-phase landing with u_max = P lands at depth D (1e-6; the two problems
    are dual), and a budget below the least depth is refused."""
    budget = LEAST + 0.5
    code, out, err = cli("solve", "--v0", str(V0), "--variant", "min-peak-force",
                         "--depth-max", str(budget), "--pmp", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["verified"] is True and "refined" in d, d["unverified_reasons"]
    assert d["pmp"]["verdict"] == "bang-bang certified", d["pmp"]
    assert d["depth"] == pytest.approx(budget, abs=1e-9)
    assert d["replay"]["difference"] < 1e-9
    assert 0 < d["peak"] < 8.2
    code, out, err = cli("solve", "--v0", str(V0), "--variant", "two-phase", "--umax",
                         repr(d["peak"]), "--json")
    assert code == 0, err
    assert json.loads(out)["depth"] == pytest.approx(budget, abs=1e-6)
    # a budget below the least depth is an impossible limit: one line, exit 2
    code, out, err = cli("solve", "--v0", str(V0), "--variant", "min-peak-force",
                         "--depth-max", str(LEAST - 0.01))
    assert code == 2 and out == "" and "below the least depth" in err


NO_REFINE = [("paper", []), ("two-phase", []), ("leg-extension", []),
             ("min-peak-force", ["--depth-max", str(LEAST + 0.5)])]


@pytest.mark.slow
@pytest.mark.parametrize("name,extra", NO_REFINE, ids=[n for n, _ in NO_REFINE])
def test_every_variant_transcribed_only_plots_and_is_checked(cli, tmp_path, name, extra):
    """--no-refine --plot: the transcribed result is replayed (its piecewise-constant force,
    exactly), drawn, and verified to the transcription's accuracy."""
    png = tmp_path / "f.png"
    code, out, err = cli("solve", "--v0", "-3", "--variant", name, *extra, "--no-refine",
                         "--plot", png, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["verified"] is True and "refined" not in d
    assert d["replay"]["difference"] < 1e-6
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_a_sweep_over_v0_for_a_variant_is_continuation(cli):
    code, out, err = cli("solve-sweep", "--variant", "two-phase", "--v0-min", "-2",
                         "--v0-max", "-1", "--n", "3", "--json")
    assert code == 0, err
    rows = json.loads(out)["sweep"]
    assert [r["v0"] for r in rows] == [-1.0, -1.5, -2.0]
    assert [r["path"] for r in rows][1:] == ["structure", "structure"]  # warm from the last
    code, out, _ = cli("solve", "--v0", "-1.5", "--variant", "two-phase", "--json")
    assert json.loads(out)["depth"] == pytest.approx(rows[1]["depth"], abs=1e-9)


def test_an_installed_package_registers_a_variant_by_entry_point(cli, tmp_path, monkeypatch):
    """A distribution on sys.path with an entry point in the group softlanding.variants:
    listed by `softlanding variants` with its origin, and found by its name."""
    (tmp_path / "mypkg_variants.py").write_text(
        "from dataclasses import replace\n"
        "from softlanding.optimal.builtin_variants import TWO_PHASE\n"
        "VARIANT = replace(TWO_PHASE, name='my-two-phase', summary='two-phase, renamed')\n")
    info = tmp_path / "mypkg-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: mypkg\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[softlanding.variants]\nmy-two-phase = mypkg_variants:VARIANT\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    code, out, err = cli("variants", "--json")
    assert code == 0, err
    mine = [v for v in json.loads(out)["variants"] if v["name"] == "my-two-phase"]
    assert len(mine) == 1
    assert (mine[0]["module"], mine[0]["attribute"]) == ("mypkg_variants", "VARIANT")
    assert mine[0]["source"] == "entry point (mypkg)"
    assert find_variant("my-two-phase").summary == "two-phase, renamed"
    code, out, err = cli("solve", "--v0", "-3", "--variant", "my-two-phase", "--steps", "3")
    assert code == 2 and "--steps" in err and err.count("\n") == 1


def test_the_worked_example_uses_public_names_and_the_guide_shows_it_whole():
    """Absolute imports of public names only (no private module or name, nothing relative),
    and the how-to includes the module itself, so the page cannot drift from it."""
    import ast

    tree = ast.parse(PACKAGED.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module != "__future__":
            assert node.level == 0 and node.module is not None
            assert not any(p.startswith("_") for p in node.module.split("."))
            assert not any(a.name.startswith("_") for a in node.names), node.module
            if node.module.startswith("softlanding.optimal."):  # a public module's __all__
                import importlib

                mod = importlib.import_module(node.module)
                assert {a.name for a in node.names} <= set(mod.__all__), node.module
    guide = (PACKAGED.parents[2] / "docs" / "guides" / "hybrid.md").read_text()
    assert "```{literalinclude} ../../softlanding/optimal/min_peak_force.py" in guide


def test_every_name_the_worked_example_imports_has_an_api_page():
    """Issue 47: the example's building blocks (add_yielding, add_static, ...) had no API
    page. docs/conf.py writes one page per front door (FRONT_DOORS) from its __all__, and
    docs/api/index.rst lists the pages: each name the example imports is on one."""
    import ast
    import importlib

    docs = PACKAGED.parents[2] / "docs"
    conf = ast.parse((docs / "conf.py").read_text())
    doors = next(ast.literal_eval(n.value) for n in conf.body if isinstance(n, ast.Assign)
                 and getattr(n.targets[0], "id", "") == "FRONT_DOORS")
    homes = next(ast.literal_eval(n.value) for n in conf.body if isinstance(n, ast.Assign)
                 and getattr(n.targets[0], "id", "") == "HOME_ORDER")
    index = (docs / "api" / "index.rst").read_text().split()
    assert set(doors) <= set(index) and set(homes) <= set(doors)

    def exports(name):
        mod = importlib.import_module(name)
        return getattr(mod, "__all__", [n for n in dir(mod) if not n.startswith("_")])

    documented = {n for d in homes for n in exports(d)}  # each object's page is under these
    for node in ast.walk(ast.parse(PACKAGED.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module.split(".")[0] in ("softlanding",
                                                                             "ocp"):
            missing = {a.name for a in node.names} - documented
            assert not missing, (node.module, missing)
