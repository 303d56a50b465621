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
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, replace
from typing import Any, Protocol, runtime_checkable

from softlanding.errors import ParameterError

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
    """

    name: str
    type: Callable[[str], Any] = float
    default: Any = None
    help: str = ""
    check: Callable[[Any], str | None] | None = None
    required: bool = False
    choices: tuple[Any, ...] | None = None
    metavar: str | None = None

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
        """JSON-able description."""
        return {"name": self.name, "flag": self.flag,
                "type": getattr(self.type, "__name__", str(self.type)),
                "default": self.default, "required": self.required, "help": self.help,
                "choices": list(self.choices) if self.choices is not None else None}


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
    source : str
        Where it was found: ``"built-in"``, ``"packaged"``, ``"module"`` or
        ``"entry point (distribution)"`` (filled in by the registry).
    module, attribute : str
        Where it is declared (filled in by the registry).
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
    source: str = ""
    module: str = ""
    attribute: str = ""

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
        return self.solver()(impact, robot, ground, refine=refine, warm_start=warm_start,
                             **options)

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
    except ImportError as err:
        raise ParameterError(what, f"cannot import {mod!r} ({err})") from None
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ParameterError(what, f"module {mod!r} has no attribute {attr!r}") from None
    return obj


def _as_variant(obj: Any, spec: str, source: str, what: str) -> Variant:
    if not isinstance(obj, Variant):
        raise ParameterError(what, f"{spec} is a {type(obj).__name__}, not a "
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
        except Exception as err:  # a broken third-party package: say which, one line
            raise ParameterError("--variant", f"entry point {name!r} ({ep.value}) of "
                                 f"{dist} does not load: {err}") from None
        return _as_variant(obj, ep.value, f"entry point ({dist})", "--variant")
    known = built_in_names() + sorted(eps)
    raise ParameterError("--variant", f"no variant {name!r} (known: {', '.join(known)}; or "
                                      "module:attribute)")


def all_variants() -> list[Variant]:
    """Every variant: built in, packaged, and installed (entry points), in that order."""
    out = built_in_variants() + [find_variant(n) for n in PACKAGED]
    seen = {v.name for v in out}
    out += [find_variant(n) for n in sorted(entry_points()) if n not in seen]
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
           "VariantResult", "all_variants", "built_in_names", "built_in_variants",
           "entry_points", "find_variant", "resolve", "sweep_variant"]
