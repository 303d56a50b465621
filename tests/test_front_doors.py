"""The packages' front doors: every exported name resolves, none is shadowed by a submodule,
and the light names stay light."""

import importlib
import importlib.util
import subprocess
import sys

import pytest

FRONT_DOORS = ["ocp", "softlanding", "softlanding.model", "softlanding.simulation",
               "softlanding.optimal", "softlanding.studies", "softlanding.plots",
               "softlanding.report", "softlanding.cli"]


@pytest.mark.parametrize("name", FRONT_DOORS)
def test_every_exported_name_resolves(name):
    pkg = importlib.import_module(name)
    exported = getattr(pkg, "__all__", [])
    assert exported, f"{name} has no __all__"
    missing = [n for n in exported if not hasattr(pkg, n)]
    assert missing == []


@pytest.mark.parametrize("name", FRONT_DOORS)
def test_no_exported_name_is_a_submodule(name):
    """A submodule named like an exported function replaces it in the package's namespace
    once imported (``ocp.multistart`` did), so that ``from pkg import f`` depends on what was
    imported before."""
    pkg = importlib.import_module(name)
    clashes = [n for n in getattr(pkg, "__all__", [])
               if importlib.util.find_spec(f"{name}.{n}") is not None]
    assert clashes == []


def test_value_objects_load_without_casadi_or_numba():
    code = ("import sys, softlanding as s; s.Robot, s.Impact, s.Impedance, s.PAPER_ROBOT, "
            "s.LinearGround, s.paper_rig; "
            "print(sorted(m for m in ('casadi', 'numba', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
