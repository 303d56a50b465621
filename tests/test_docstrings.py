"""Every public function and class has a numpydoc docstring whose parameters match its signature.

In the manner of python-control's docstring tests: the public names are each module's
``__all__``; a callable's "Parameters" section (or, for a class, "Parameters" or
"Attributes") must list exactly the parameters of its signature.
"""

import importlib
import inspect

import pytest
from numpydoc.docscrape import ClassDoc, FunctionDoc

MODULES = [
    "softlanding", "softlanding.model", "softlanding.controllers", "softlanding.ground",
    "softlanding.errors", "softlanding.dynamics", "softlanding.scaling",
    "softlanding.simulator", "softlanding.impedance", "softlanding.sweeps",
    "softlanding.landing", "softlanding.comparison", "softlanding.robustness",
    "softlanding.reproduce", "softlanding.summary", "softlanding.demo", "ocp.trajectory",
    "softlanding.terrain", "softlanding.groundcode", "softlanding.cli_ground",
    "softlanding.verification", "ocp",
]


def _public(module_name):
    mod = importlib.import_module(module_name)
    names = getattr(mod, "__all__", None)
    if names is None:
        names = [n for n, v in vars(mod).items() if not n.startswith("_")
                 and getattr(v, "__module__", None) == module_name]
    for name in names:
        obj = getattr(mod, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield f"{module_name}.{name}", obj


CASES = sorted({qual: obj for m in MODULES for qual, obj in _public(m)}.items())


def _signature_params(obj):
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return None
    out = []
    for p in sig.parameters.values():
        if p.name in ("self", "cls") or p.name.startswith("_"):
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
    documented = _documented(doc)
    missing = [p for p in params if p.lstrip("*") not in {d.lstrip("*") for d in documented}]
    assert not missing, f"{qual}: parameters {missing} are not documented"
    if not inspect.isclass(obj):
        extra = [d for d in documented if d.lstrip("*") not in {p.lstrip("*") for p in params}]
        assert not extra, f"{qual}: documents {extra}, which are not parameters"


def test_the_check_finds_something():
    assert len(CASES) > 40
