"""The flat module paths of ocp 0.3 (``ocp.switching``, ``ocp.pmp``, ...), kept for one version.

``import ocp.switching`` (or ``from ocp.pmp import certify``) still works: a finder on
``sys.meta_path`` answers for the old name with the module at its new path, the very same
module object (so monkeypatching either name patches both), after a
:class:`DeprecationWarning` that names the new path. Nothing is imported until an old
path is asked for.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from types import ModuleType

# old module name -> its path under the package since 0.4
MOVED = {
    "active_set_newton": "structure.active_set_newton",
    "arcs": "structure.arcs",
    "chattering": "certificate.chattering",
    "collocation": "transcriptions.collocation",
    "compiled": "definition.compiled",
    "constraint_kinds": "structure.constraint_kinds",
    "control_set": "structure.control_set",
    "costates": "certificate.costates",
    "discretization": "transcriptions.discretization",
    "errors": "definition.errors",
    "flows": "structure.flows",
    "gridview": "transcriptions.gridview",
    "guess": "definition.guess",
    "integrators": "transcriptions.integrators",
    "local_optima": "search.multistart",
    "mesh": "transcriptions.mesh",
    "multiphase": "definition.multiphase",
    "nlp": "transcriptions.nlp",
    "phase_pmp": "certificate.phases",
    "phase_refinement": "structure.phase_refinement",
    "pmp": "certificate.certify",
    "pmp_certificate": "certificate.result",
    "pmp_checks": "certificate.checks",
    "pmp_refined": "certificate.from_refined",
    "pmp_transcription": "certificate.from_transcription",
    "problem": "definition.problem",
    "refinement": "structure.refinement",
    "scaling": "definition.scaling",
    "scenario": "scenarios.scenario",
    "scenario_result": "scenarios.result",
    "scenario_stack": "scenarios.stack",
    "shooting": "transcriptions.shooting",
    "sizes": "definition.sizes",
    "solution": "transcriptions.solution",
    "switching": "structure.switching",
    "symbols": "definition.symbols",
    "trajectory": "definition.trajectory",
    "transcription": "transcriptions.transcription",
    "verify": "transcriptions.verify",
}


class OldPathFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``<package>.<old name>`` and loads it as the module at its new path.

    Parameters
    ----------
    package : str
        The package whose old module paths it answers for (``"ocp"``).
    """

    def __init__(self, package: str) -> None:
        self.package = package

    def new_path(self, fullname: str) -> str | None:
        """The new dotted path of an old module name.

        Parameters
        ----------
        fullname : str
            A dotted module name (``"ocp.switching"``).

        Returns
        -------
        str or None
            Its path since 0.4 (``"ocp.structure.switching"``), or None if it is not an
            old path of the package.
        """
        head, _, old = fullname.rpartition(".")
        if head != self.package or old not in MOVED:
            return None
        return f"{self.package}.{MOVED[old]}"

    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        """A spec for an old module path, loaded by this finder (the import protocol).

        Parameters
        ----------
        fullname : str
            The dotted name being imported.
        path : object, optional
            The parent package's search path (unused).
        target : object, optional
            A module being reloaded (unused).

        Returns
        -------
        importlib.machinery.ModuleSpec or None
            None for every name that is not an old path of the package.
        """
        if self.new_path(fullname) is None:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        """The module at the new path, after a :class:`DeprecationWarning`.

        Parameters
        ----------
        spec : importlib.machinery.ModuleSpec
            The spec of the old name (from :meth:`find_spec`).

        Returns
        -------
        types.ModuleType
            The module at the new path, imported if it was not.
        """
        new = self.new_path(spec.name)
        assert new is not None  # find_spec answered only for moved names
        warnings.warn(
            f"{spec.name} moved to {new}; import public names from {self.package} "
            f"(the old path goes in the next version)",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(new)

    def exec_module(self, module: ModuleType) -> None:
        """Nothing to do: the module at the new path is already executed.

        Parameters
        ----------
        module : types.ModuleType
            The module :meth:`create_module` returned.
        """


def install(package: str) -> None:
    """Answer for ``package``'s old module paths (once per interpreter).

    Parameters
    ----------
    package : str
        The package (``"ocp"``); its old names are the keys of :data:`MOVED`.
    """
    if not any(isinstance(f, OldPathFinder) and f.package == package for f in sys.meta_path):
        sys.meta_path.append(OldPathFinder(package))
