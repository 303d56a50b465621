"""Every public member of ``softlanding`` and ``ocp`` has a numpydoc docstring matching its
signature.

In the manner of python-control's ``docstrings_test.py``: the test walks every public module of
both packages (``pkgutil.walk_packages``; a module whose name starts with ``_`` is private), takes
the names each module exports (its ``__all__``, else every public function and class defined in
it), and for every public function, class and public method defined on such a class asks for a
docstring; a callable's "Parameters" section (for a class, "Parameters" or "Attributes") must list
exactly the parameters of its signature. A method that overrides a documented one with the
same parameters may leave them to the base's docstring (numpydoc's inheritance). What is left
out is listed in ``EXEMPT`` with the reason.
"""

import importlib
import inspect
import pkgutil

import pytest
from numpydoc.docscrape import ClassDoc, FunctionDoc

import ocp
import softlanding

EXEMPT_MODULES = {
    "softlanding.__main__": "runs the CLI on import (python -m softlanding)",
}
EXEMPT: dict[str, str] = {}
"""Qualified name -> why its docstring is not checked."""


def _modules():
    for pkg in (softlanding, ocp):
        yield pkg.__name__
        for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
            if info.name in EXEMPT_MODULES or any(p.startswith("_") for p in info.name.split(".")):
                continue
            yield info.name


def _public(module_name):
    mod = importlib.import_module(module_name)
    names = getattr(mod, "__all__", None)
    if names is None:
        names = [n for n, v in vars(mod).items() if not n.startswith("_")
                 and getattr(v, "__module__", None) == module_name]
    for name in names:
        obj = getattr(mod, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield f"{obj.__module__}.{obj.__qualname__}", obj
        if inspect.isclass(obj) and obj.__module__ == module_name:
            for mname, member in vars(obj).items():
                if mname.startswith("_") or not inspect.isfunction(member):
                    continue
                base = next((getattr(b, mname) for b in obj.__mro__[1:]
                             if inspect.isfunction(getattr(b, mname, None))), None)
                if base is not None:
                    INHERITED[member] = base
                yield f"{module_name}.{obj.__qualname__}.{mname}", member


INHERITED: dict = {}
"""Overriding method -> the base method whose docstring documents the same parameters."""


MODULES = list(_modules())
CASES = sorted({qual: obj for m in MODULES for qual, obj in _public(m)
                if qual not in EXEMPT}.items())


def _signature_params(obj):
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return None
    out = []
    for i, p in enumerate(sig.parameters.values()):
        if (i == 0 and p.name in ("self", "cls")) or p.name.startswith("_"):
            continue
        if p.kind is p.VAR_POSITIONAL:
            out.append("*" + p.name)
        elif p.kind is p.VAR_KEYWORD:
            out.append("**" + p.name)
        else:
            out.append(p.name)
    return out


def _documented(doc):
    names = []
    for section in ("Parameters", "Attributes") if isinstance(doc, ClassDoc) else ("Parameters",):
        for item in doc[section]:
            for n in item.name.split(","):
                n = n.strip()
                if n:
                    names.append(n)
    return names


@pytest.mark.parametrize("qual,obj", CASES, ids=[q for q, _ in CASES])
def test_public_callable_has_numpydoc_matching_its_signature(qual, obj):
    assert inspect.getdoc(obj), f"{qual} has no docstring"
    if getattr(obj, "_is_protocol", False):
        return  # a Protocol: its members are documented, it has no constructor
    params = _signature_params(obj)
    if inspect.isclass(obj) and (obj.__init__ is object.__init__ or issubclass(obj, Exception)
                                 and params in (["*args", "**kwargs"], None)):
        return  # nothing to document beyond the summary
    if not params:
        return
    doc = ClassDoc(obj) if inspect.isclass(obj) else FunctionDoc(obj)
    base = INHERITED.get(obj)
    if base is not None and not doc["Parameters"] and _signature_params(base) == params:
        doc = FunctionDoc(base)  # the override keeps the base's parameters and their docs
    documented = _documented(doc)
    if inspect.isclass(obj):  # fields documented on a base class of the project are documented
        for b in obj.__mro__[1:]:
            if b.__module__.split(".")[0] in ("softlanding", "ocp"):
                documented += _documented(ClassDoc(b))
    missing = [p for p in params if p.lstrip("*") not in {d.lstrip("*") for d in documented}]
    assert not missing, f"{qual}: parameters {missing} are not documented"
    if not inspect.isclass(obj):
        extra = [d for d in documented if d.lstrip("*") not in {p.lstrip("*") for p in params}]
        assert not extra, f"{qual}: documents {extra}, which are not parameters"


def test_the_walk_reaches_every_package():
    subpackages = {m.split(".")[1] for m in MODULES if m.startswith("softlanding.")}
    assert {"model", "simulation", "optimal", "studies", "plots", "report", "cli"} <= subpackages
    assert sum(m.startswith("ocp.") for m in MODULES) > 30
    assert len(CASES) > 300
