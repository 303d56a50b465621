"""The landing variants: what one declares, and where the command line finds them.

A variant is one module holding a :class:`Variant`: its name, a one-line summary, its
options (:class:`Option`: name, type, default, help, check) and its solve function
``solve(impact, robot, ground, *, refine, warm_start, **options)``. Its result follows
:class:`VariantResult` (table rows, ``to_dict``, figures, certificate), so that every
variant gets the same command line: transcription, switching refinement, certificate (or
one line on why there is none), exact replay, JSON, ``--plot`` and sweeps over ``v0``
(:func:`sweep_variant`).

Where variants come from (:func:`find_variant`, :func:`all_variants`):

* built in: :data:`BUILT_IN` (declared light, so that the command line starts fast) and
  the packaged modules of :data:`PACKAGED`;
* an importable module: ``module:attribute`` (``softlanding solve --variant mymod:VARIANT``);
* installed packages: the entry-point group ``softlanding.variants``.

This module loads no numerical library.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import math
import os
import sys
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from softlanding.errors import ParameterError, SoftlandingError

ENTRY_POINT_GROUP = "softlanding.variants"
"""The ``importlib.metadata`` entry-point group an installed package registers variants in."""

PIPELINE_OPTIONS = ("no_refine", "pmp", "plot")
"""Options every variant takes (given by the pipeline, not declared): ``--no-refine``
(only for variants with ``refine=True``), ``--pmp`` and ``--plot``."""


@dataclass(frozen=True)
class Option:
    """One option of a variant (``--name-with-dashes`` on the command line).

    Attributes
    ----------
    name : str
        Python name (the keyword the solve function takes), e.g. ``"depth_max"``.
    type : callable
        Text -> value (``float``, ``int``, ``str``...; ``bool``: a flag without a value).
    default : object
        Value when not given (ignored when ``required``).
    help : str
        One line for ``--help`` and ``softlanding variants``.
    check : callable, optional
        ``value -> None`` when good, else what is wrong with it (one line).
    required : bool
        The variant cannot run without it.
    choices : tuple, optional
        The values allowed (after ``type``).
    metavar : str, optional
        Name of the value in ``--help``.
    kind : str, optional
        What a value is, in words, for ``--help`` and ``softlanding variants`` (default
        from ``type``: number, integer, text or flag; ``"value"`` for another function).

    Raises
    ------
    TypeError
        A field of the wrong type (e.g. a name that is not an identifier).
    """

    name: str
    type: Callable[[str], Any] = float
    default: Any = None
    help: str = ""
    check: Callable[[Any], str | None] | None = None
    required: bool = False
    choices: tuple[Any, ...] | None = None
    metavar: str | None = None
    kind: str | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise TypeError(f"Option: name must be a Python identifier, got {self.name!r}")
        for what, value in (("type", self.type), ("check", self.check)):
            if value is not None and not callable(value):
                raise TypeError(f"Option {self.name!r}: {what} must be callable, got "
                                f"{type(value).__name__}")
        if not isinstance(self.help, str):
            raise TypeError(f"Option {self.name!r}: help must be text")
        if self.choices is not None:
            object.__setattr__(self, "choices", tuple(self.choices))

    @property
    def type_name(self) -> str:
        """What a value is, in words (``kind``, else from ``type``)."""
        if self.kind:
            return self.kind
        return _TYPE_NAMES.get(self.type, "value")

    def describe(self) -> str:
        """Its type, choices and default in words: ``integer, default 100``."""
        what = self.type_name
        if self.choices is not None:
            what += ": one of " + ", ".join(map(str, self.choices))
        if self.is_flag:
            return what
        sep = "; " if self.choices is not None else ", "
        if self.required:
            return f"{what}{sep}required"
        shown = ("none" if self.default is None else f"{self.default:g}"
                 if isinstance(self.default, float) else str(self.default))
        return f"{what}{sep}default {shown}"

    @property
    def flag(self) -> str:
        """The command-line spelling, ``--depth-max``."""
        return "--" + self.name.replace("_", "-")

    @property
    def is_flag(self) -> bool:
        """A switch without a value (``type`` is ``bool``)."""
        return self.type is bool

    def value(self, given: Any) -> Any:
        """The checked value of what the user gave (text, or the value itself).

        Parameters
        ----------
        given : str or object
            What was given (None: not given).

        Raises
        ------
        ParameterError
            Not of the type, not among the choices, refused by ``check``, or missing.
        """
        if given is None:
            if self.required:
                raise ParameterError(self.flag, "is required")
            return self.default
        v = given
        if isinstance(given, str) and not self.is_flag:
            try:
                v = self.type(given)
            except (TypeError, ValueError) as err:
                if self.type in (float, int):
                    why = f"expected a{'n' if self.type is int else ''} "\
                          f"{self.type.__name__}, got {given!r}"
                else:
                    why = str(err) or f"bad value {given!r}"
                raise ParameterError(self.flag, why) from None
        if isinstance(v, float) and not math.isfinite(v):
            raise ParameterError(self.flag, f"must be finite, got {given!r}")
        if self.choices is not None and v not in self.choices:
            raise ParameterError(self.flag, "must be one of "
                                 + ", ".join(str(c) for c in self.choices) + f", got {v!r}")
        if self.check is not None:
            refused = self.check(v)
            if refused:
                raise ParameterError(self.flag, refused)
        return v

    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (a default or choice JSON cannot hold is given as text)."""
        return {"name": self.name, "flag": self.flag, "type": self.type_name,
                "default": _jsonable(self.default), "required": self.required,
                "help": self.help, "choices": None if self.choices is None else
                [_jsonable(c) for c in self.choices]}


_TYPE_NAMES: dict[Any, str] = {float: "number", int: "integer", str: "text", bool: "flag"}


def _jsonable(value: Any) -> Any:
    """``value`` if JSON holds it as it is, else its text (an object, NaN)."""
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        return str(value)
    return value


@runtime_checkable
class VariantResult(Protocol):
    """What every variant's result offers the command line (one protocol, no dispatch).

    ``depth`` and ``notes`` (what the solve noticed), ``rows()`` (the printed table),
    ``to_dict()`` (JSON), ``figures(certificate)`` (for ``--plot``), ``certify()`` (the
    PMP certificate or None), ``uncertified_reason()`` (one line: why ``certify()`` gives
    None) and ``unverified_reasons(certificate)`` (empty: every check passed).
    """

    depth: float
    notes: list[str]

    def rows(self) -> list[tuple[str, object]]:
        """The ``label, value`` rows of the printed table."""
        ...

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (``--json``)."""
        ...

    def figures(self, certificate: Any = None) -> list[Any]:
        """The figures ``--plot`` writes (the first to the file named).

        Parameters
        ----------
        certificate : object, optional
            The certificate, for a variant that draws it.
        """
        ...

    def certify(self) -> Any:
        """The PMP certificate, or None (then :meth:`uncertified_reason` says why)."""
        ...

    def uncertified_reason(self) -> str:
        """One line: why :meth:`certify` gives None (empty when it gives a certificate)."""
        ...

    def unverified_reasons(self, certificate: Any = None) -> list[str]:
        """Why the result cannot be taken as proven (empty: every check passed).

        Parameters
        ----------
        certificate : object, optional
            Its certificate, whose verdict counts too.
        """
        ...


Solve = Callable[..., Any]

_RESULT_MEMBERS = ("depth", "notes", "rows", "to_dict", "figures", "certify",
                   "uncertified_reason", "unverified_reasons")


@dataclass(frozen=True)
class Variant:
    """A landing variant: its name, options and solve function.

    Attributes
    ----------
    name : str
        The ``--variant`` value (lower case, dashes).
    summary : str
        One line for ``--help``.
    solve : callable or str
        ``solve(impact, robot, ground, *, refine, warm_start, **options) -> result`` (a
        :class:`VariantResult`), or ``"module:function"`` naming it (imported on first use,
        so that a table of variants loads no numerical library).
    options : tuple of Option
        Its own options (the pipeline's, :data:`PIPELINE_OPTIONS`, come for free).
    refine : bool
        ``--no-refine`` applies (the switching times are refined unless it is given).
    ground : bool
        It takes a non-linear ground (``--ground``); else only the paper's linear one.
    certificate_figure : bool
        Its figures include the certificate's (``--plot F --pmp`` also writes ``F-pmp``).
    takes : callable, optional
        ``values -> names``: the options that apply given the values of the others (e.g.
        a mode that makes some options moot); default: all of them.
    refusal : callable, optional
        ``values -> str``: what to add to "does not apply to --variant NAME" (e.g.
        ``" --steps 2"``).
    objective : tuple of (str, str)
        What it minimises: the attribute of its result and how to call it (default
        ``("depth", "depth")``); a sweep over ``v0`` shows it beside the depth.
    source : str
        Where it was found: ``"built-in"``, ``"packaged"``, ``"module"`` or
        ``"entry point (distribution)"`` (filled in by the registry).
    module, attribute : str
        Where it is declared (filled in by the registry).

    Raises
    ------
    TypeError
        A field of the wrong type (options that are not :class:`Option`, two options of
        one name, a solve that is neither callable nor ``"module:function"``).
    """

    name: str
    summary: str
    solve: Solve | str
    options: tuple[Option, ...] = ()
    refine: bool = True
    ground: bool = False
    certificate_figure: bool = False
    takes: Callable[[Mapping[str, Any]], Iterable[str]] | None = None
    refusal: Callable[[Mapping[str, Any]], str] | None = None
    objective: tuple[str, str] = ("depth", "depth")
    source: str = ""
    module: str = ""
    attribute: str = ""

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.strip() and not
                any(c.isspace() or c == ":" for c in self.name)):
            raise TypeError(f"Variant: name must be a word (no spaces, no ':'), got "
                            f"{self.name!r}")
        if not (callable(self.solve) or isinstance(self.solve, str) and ":" in self.solve):
            raise TypeError(f"Variant {self.name!r}: solve must be a function or "
                            f"'module:function', got {self.solve!r:.60}")
        if isinstance(self.options, Option) or not isinstance(self.options, tuple | list) \
                or not all(isinstance(o, Option) for o in self.options):
            raise TypeError(f"Variant {self.name!r}: options must be a tuple of Option, got "
                            f"{self.options!r:.60}")
        names = [o.name for o in self.options]
        twice = sorted({n for n in names if names.count(n) > 1} | set(names) & set(
            PIPELINE_OPTIONS))
        if twice:
            raise TypeError(f"Variant {self.name!r}: option {twice[0]!r} declared twice (or "
                            "one the pipeline gives)")
        object.__setattr__(self, "options", tuple(self.options))
        if not (isinstance(self.objective, tuple) and len(self.objective) == 2
                and all(isinstance(t, str) for t in self.objective)):
            raise TypeError(f"Variant {self.name!r}: objective must be (attribute, label)")

    def option_names(self) -> tuple[str, ...]:
        """Its own options' names, then the pipeline's that apply."""
        pipe = [n for n in PIPELINE_OPTIONS if n != "no_refine" or self.refine]
        return tuple(o.name for o in self.options) + tuple(pipe)

    def applicable(self, values: Mapping[str, Any]) -> frozenset[str]:
        """The options (own and pipeline, and ``"ground"``) that apply given ``values``.

        Parameters
        ----------
        values : mapping
            Option name -> given value (None: not given).
        """
        if self.takes is not None:
            return frozenset(self.takes(values))
        return frozenset(self.option_names()) | ({"ground"} if self.ground else set())

    def solver(self) -> Solve:
        """The solve function (imported now when named by ``"module:function"``)."""
        if callable(self.solve):
            return self.solve
        return resolve(self.solve, f"--variant {self.name}")

    def run(self, impact: Any, robot: Any, ground: Any, options: Mapping[str, Any],
            refine: bool = True, warm_start: Any = None) -> Any:
        """Solve one landing with checked ``options`` (see :meth:`values`).

        Parameters
        ----------
        impact, robot, ground
            The landing.
        options : mapping
            The variant's own options (checked values).
        refine : bool
            Refine the switching times.
        warm_start : result, optional
            A neighbour's result (continuation).
        """
        solve = self.solver()
        try:
            res = solve(impact, robot, ground, refine=refine, warm_start=warm_start, **options)
        except Exception as err:
            solver_errors = sys.modules.get("ocp.definition.errors")
            if isinstance(err, SoftlandingError) or solver_errors is not None and \
                    isinstance(err, solver_errors.SolveError):
                raise  # bad input, an infeasible landing, Ipopt's verdict: said as they are
            blamed = self.blame(err)
            if blamed is None:
                raise
            raise VariantError(self.spec, f"raised {type(err).__name__} ({blamed}): {err}; "
                                          "--debug shows the traceback") from err
        if self.source not in ("", "built-in", "packaged") and \
                not isinstance(res, VariantResult):  # the user's, else it fails in ours
            missing = [m for m in _RESULT_MEMBERS if not hasattr(res, m)]
            raise VariantError(self.spec, f"its solve returned a {type(res).__name__} without "
                                          f"{', '.join(missing)} (see "
                                          "softlanding.optimal.VariantResult)")
        return res

    @property
    def spec(self) -> str:
        """How the user names it: ``module:attribute`` for a module's, else its name."""
        return f"{self.module}:{self.attribute}" if self.source == "module" else self.name

    def blame(self, err: BaseException) -> str | None:
        """Where in a user's module (a ``module:attribute`` or an installed one) ``err``
        was raised, ``"mymod.py, line 12"``; None when the error is not the user's (a
        built-in or packaged variant, or raised within softlanding or ocp).

        The user's when the innermost frame in either the user's files or this project's
        is theirs, or when theirs called ours with a wrong value or type (a ``TypeError`` or
        ``ValueError``, such as ocp's ``ProblemDefinitionError``).

        Parameters
        ----------
        err : BaseException
            An error the solve raised.
        """
        if self.source in ("", "built-in", "packaged") or not self.module:
            return None
        theirs = _module_root(self.module)
        if theirs is None:
            return None
        ours = tuple(p + os.sep for p in project_roots())
        first_ours = None
        for frame, line in reversed(list(traceback.walk_tb(err.__traceback__))):
            path = str(Path(frame.f_code.co_filename).resolve())
            if path.startswith(ours):
                first_ours = True if first_ours is None else first_ours
            elif path == theirs or path.startswith(theirs + os.sep):
                if first_ours and not isinstance(err, TypeError | ValueError):
                    return None  # failed inside this project: a bug to report here
                return f"{Path(path).name}, line {line}"
        return None

    def values(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """The checked values of its own options (defaults filled in).

        Parameters
        ----------
        given : mapping
            Option name -> what the user gave (None: not given).

        Raises
        ------
        ParameterError
            A bad or missing value (one line, naming the option).
        """
        return {o.name: o.value(given.get(o.name)) for o in self.options}

    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (``softlanding variants --json``)."""
        return {"name": self.name, "summary": self.summary, "module": self.module,
                "attribute": self.attribute, "source": self.source,
                "options": [o.to_dict() for o in self.options],
                "pipeline_options": [n for n in PIPELINE_OPTIONS
                                     if n != "no_refine" or self.refine],
                "ground": self.ground}


class VariantError(SoftlandingError):
    """A user's variant (``module:attribute`` or an installed one) failed: it does not
    import, is not a :class:`Variant`, or raised inside its own code. Bad input to the
    command line (exit 2): the fix is in the user's module, not in this project.

    Parameters
    ----------
    spec : str
        The variant as the user named it.
    message : str
        What went wrong (one line).
    """

    exit_code = 2
    label = "variant"

    def __init__(self, spec: str, message: str) -> None:
        self.spec = spec
        super().__init__(f"{spec}: {message}")


@cache
def project_roots() -> tuple[str, ...]:
    """The folders of the ``softlanding`` and ``ocp`` packages (resolved; found without
    importing ``ocp``)."""
    roots = [str(Path(__file__).resolve().parents[1])]
    spec = importlib.util.find_spec("ocp")
    if spec is not None and spec.submodule_search_locations:
        roots += [str(Path(p).resolve()) for p in spec.submodule_search_locations]
    return tuple(roots)


def _module_root(module: str) -> str | None:
    """The file or folder of the top-level package of ``module`` (None if not found)."""
    try:
        spec = importlib.util.find_spec(module.split(".")[0])
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    if spec.submodule_search_locations:
        return str(Path(next(iter(spec.submodule_search_locations))).resolve())
    return str(Path(spec.origin).resolve()) if spec.origin else None


def _import_failure(mod: str, err: BaseException) -> str:
    """One line on why importing ``mod`` failed: the error and, when known, where."""
    if isinstance(err, SystemExit):
        return f"importing {mod!r} called sys.exit({err.code!r})"
    if isinstance(err, ModuleNotFoundError) and err.name == mod.split(".")[0]:
        return f"no module {mod!r} on the path"
    where = ""
    if isinstance(err, SyntaxError) and err.filename:
        where = f" ({Path(err.filename).name}, line {err.lineno})"
    else:
        frames = [(f, n) for f, n in traceback.walk_tb(err.__traceback__)
                  if not f.f_code.co_filename.startswith("<frozen")]
        if frames:
            f, n = frames[-1]
            where = f" ({Path(f.f_code.co_filename).name}, line {n})"
    text = err.msg if isinstance(err, SyntaxError) else str(err)
    return (f"cannot import {mod!r}{where}: {type(err).__name__}: {text}; --debug shows the "
            "traceback")


def resolve(spec: str, what: str) -> Any:
    """The object ``"module:attribute"`` names (``attribute`` may be dotted).

    Parameters
    ----------
    spec : str
        ``module:attribute``.
    what : str
        How to name it in an error.

    Raises
    ------
    ParameterError
        Malformed, not importable, or no such attribute (one line).
    """
    mod, sep, attr = spec.partition(":")
    if not sep or not mod or not attr:
        raise ParameterError(what, f"expected module:attribute, got {spec!r}")
    try:
        obj: Any = importlib.import_module(mod)
    except (Exception, SystemExit) as err:  # whatever a module does on import: one line
        raise VariantError(spec, _import_failure(mod, err)) from err
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ParameterError(what, f"module {mod!r} has no attribute {attr!r}") from None
    return obj


def _as_variant(obj: Any, spec: str, source: str, what: str) -> Variant:
    if not isinstance(obj, Variant):
        raise VariantError(spec, f"is a {type(obj).__name__}, not a "
                                 "softlanding.optimal.Variant")
    mod, _, attr = spec.partition(":")
    return replace(obj, source=source, module=mod, attribute=attr)


BUILT_IN = "softlanding.optimal.builtin_variants:VARIANTS"
"""The table of built-in variants (attribute name -> :class:`Variant`; named, like
:data:`PACKAGED`, so that this module depends on no variant)."""


def built_in_variants() -> list[Variant]:
    """The built-in variants (declared light: loads no numerical library)."""
    table = resolve(BUILT_IN, "built-in variants")
    mod = BUILT_IN.partition(":")[0]
    return [replace(v, source="built-in", module=mod, attribute=attr)
            for attr, v in table.items()]


PACKAGED: Mapping[str, str] = {"min-peak-force": "softlanding.optimal.min_peak_force:VARIANT"}
"""Packaged variants, each its own module (imported only when chosen or listed)."""


def entry_points() -> dict[str, Any]:
    """The installed packages' variants: name -> entry point (not loaded)."""
    from importlib.metadata import entry_points as eps

    return {ep.name: ep for ep in eps(group=ENTRY_POINT_GROUP)}


def built_in_names() -> list[str]:
    """The names of the variants known without importing anything heavy (built-in and
    packaged; not the installed packages')."""
    return [v.name for v in built_in_variants()] + list(PACKAGED)


def find_variant(name: str) -> Variant:
    """The variant named ``name``: built in, packaged, ``module:attribute``, or installed.

    Parameters
    ----------
    name : str
        A variant's name or ``module:attribute``.

    Raises
    ------
    ParameterError
        No such variant (one line, with the names there are).
    VariantError
        A user's or installed module that does not import or holds no :class:`Variant`.
    """
    for v in built_in_variants():
        if v.name == name:
            return v
    if name in PACKAGED:
        return _as_variant(resolve(PACKAGED[name], "--variant"), PACKAGED[name], "packaged",
                           "--variant")
    if ":" in name:
        return _as_variant(resolve(name, "--variant"), name, "module", "--variant")
    eps = entry_points()
    if name in eps:
        ep = eps[name]
        dist = getattr(getattr(ep, "dist", None), "name", "?")
        try:
            obj = ep.load()
        except (Exception, SystemExit) as err:  # a broken third-party package: one line
            raise VariantError(f"{name} (entry point {ep.value} of {dist})", _import_failure(
                ep.value.partition(":")[0], err)) from err
        return _as_variant(obj, ep.value, f"entry point ({dist})", "--variant")
    known = built_in_names() + sorted(eps)
    raise ParameterError("--variant", f"no variant {name!r} (known: {', '.join(known)}; or "
                                      "module:attribute)")


def survey_variants(extra: Iterable[str] = ()) -> tuple[list[Variant], list[VariantError]]:
    """Every variant that loads, and why each other does not (a broken plug-in does not
    hide the rest).

    Parameters
    ----------
    extra : iterable of str
        Variants named besides the registered ones (``module:attribute``).

    Returns
    -------
    variants : list of Variant
        Built in, packaged, installed (entry points), then ``extra``, in that order.
    failures : list of VariantError
        One for each that does not load.
    """
    out = built_in_variants()
    failures: list[VariantError] = []
    for name in [*PACKAGED, *sorted(entry_points()), *extra]:
        if name in {v.name for v in out} or name in {v.spec for v in out}:
            continue
        try:
            out.append(find_variant(name))
        except VariantError as err:
            failures.append(err)
    return out, failures


def all_variants() -> list[Variant]:
    """Every variant: built in, packaged, and installed (entry points), in that order.

    Raises
    ------
    VariantError
        An installed variant that does not load (:func:`survey_variants` lists the rest).
    """
    out, failures = survey_variants()
    if failures:
        raise failures[0]
    return out


def sweep_variant(variant: Variant, v0_values: Iterable[float], robot: Any, ground: Any,
                  options: Mapping[str, Any], *, refine: bool = True,
                  progress: bool | None = False) -> list[Any]:
    """Solve ``variant`` over impact velocities by continuation (each from the last).

    Parameters
    ----------
    variant : Variant
        Any registered variant.
    v0_values : iterable of float
        Impact velocities, in the order to solve (start from the easy end).
    robot, ground
        The landing.
    options : mapping
        The variant's own options (checked values, :meth:`Variant.values`).
    refine : bool
        Refine the switching times.
    progress : bool or None
        Progress bar (None: only on a terminal).
    """
    from softlanding.model.robot import Impact
    from softlanding.optimal.pipeline import continuation

    def one(imp: Any, prev: Any) -> Any:
        return variant.run(imp, robot, ground, options, refine=refine, warm_start=prev)

    return continuation([Impact.of(v) for v in v0_values], one, progress,
                        f"{variant.name} sweep")


__all__ = ["BUILT_IN", "ENTRY_POINT_GROUP", "PACKAGED", "PIPELINE_OPTIONS", "Option", "Variant",
           "VariantError", "VariantResult", "all_variants", "built_in_names",
           "built_in_variants", "entry_points", "find_variant", "project_roots", "resolve",
           "survey_variants", "sweep_variant"]
