"""``ocp``'s folders by role: the public names at the top, the flat paths of 0.3 kept for a
version with a DeprecationWarning, imports one way between the sub-packages."""

from __future__ import annotations

import ast
import importlib
import warnings
from pathlib import Path

import pytest

import ocp
from ocp.deprecated_paths import MOVED

OCP = Path(ocp.__file__).parent
# each sub-package imports only those before it (scenarios and search both sit on top of
# the transcriptions, beside structure and certificate)
ORDER = {"definition": 0, "transcriptions": 1, "structure": 2, "certificate": 3,
         "scenarios": 2, "search": 2}


def test_top_level_is_small_and_every_public_name_imports():
    entries = [p for p in OCP.iterdir() if p.name != "__pycache__"]
    assert len(entries) <= 10, sorted(p.name for p in entries)
    for name in ocp.__all__:
        assert getattr(ocp, name) is not None


@pytest.mark.parametrize("old", sorted(MOVED))
def test_old_path_warns_and_is_the_new_module(old):
    new = importlib.import_module(f"ocp.{MOVED[old]}")
    with pytest.warns(DeprecationWarning, match=f"ocp.{old} moved to ocp.{MOVED[old]}"):
        mod = importlib.import_module(f"ocp.{old}")
    assert mod is new


def test_from_old_path_import_name():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        import sys
        sys.modules.pop("ocp.pmp_checks", None)
        from ocp.pmp_checks import Tolerances  # noqa: F401  (the old path of 0.3)
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)
    from ocp.certificate.checks import Tolerances as new
    assert Tolerances is new


def test_unknown_name_is_still_an_import_error():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("ocp.no_such_module")


def test_sub_packages_import_one_way():
    bad = []
    for path in OCP.glob("*/*.py"):
        here = path.parent.name
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 2 and node.module:
                there = node.module.split(".")[0]
                if ORDER[there] > ORDER[here] or (ORDER[there] == ORDER[here] and there != here):
                    bad.append(f"{path.relative_to(OCP)} imports {node.module}")
    assert not bad, bad
