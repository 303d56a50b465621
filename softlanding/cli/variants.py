"""``softlanding solve --variant``'s options and ``softlanding variants``, built from the
registered variants (:mod:`softlanding.optimal.variants`): adding a variant touches no
file here.

The parser holds every built-in variant's options, and those of the variant named on the
command line (packaged, ``module:attribute`` or an installed entry point), found by a
look at the arguments before parsing; ``--help`` and ``softlanding variants`` list them
all. Every variant option is parsed as text and converted and checked by its variant
(:meth:`softlanding.optimal.variants.Option.value`), so that two variants may share an
option's name. :func:`variant_of` refuses an option the chosen variant would ignore
(exit 2 naming it), so no option is ever silently dropped.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from softlanding.errors import ParameterError
from softlanding.optimal.variants import (
    PIPELINE_OPTIONS,
    Option,
    Variant,
    all_variants,
    built_in_names,
    built_in_variants,
    find_variant,
)

DEFAULT_VARIANT = "paper"
SUBCOMMANDS = ("solve", "solve-sweep")
"""The sub-commands that take ``--variant``."""


def _flag(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def named_variant(argv: Sequence[str] | None) -> str | None:
    """The ``--variant`` value in ``argv`` (a look before parsing; None when not there).

    Parameters
    ----------
    argv : sequence of str or None
        The command line.
    """
    args = list(argv or [])
    for i, arg in enumerate(args):
        if arg == "--variant" and i + 1 < len(args):
            return args[i + 1]
        if arg.startswith("--variant="):
            return arg.split("=", 1)[1]
    return None


def _wanted(argv: Sequence[str] | None, command: str) -> list[Variant]:
    """The variants whose options the ``command`` parser needs for ``argv``."""
    args = list(argv or [])
    if command not in args:
        return built_in_variants()
    rest = args[args.index(command) + 1:]
    if "-h" in rest or "--help" in rest:
        return all_variants()
    out = built_in_variants()
    name = named_variant(rest)
    if name is not None and name not in {v.name for v in out}:
        out.append(find_variant(name))
    return out


def add_variant_options(p: argparse.ArgumentParser, argv: Sequence[str] | None,
                        command: str) -> None:
    """``--variant`` and the options of the variants ``argv`` may use, on ``p``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    argv : sequence of str or None
        The command line (to find a variant named ``module:attribute`` or installed).
    command : str
        The sub-command (``solve`` or ``solve-sweep``).
    """
    try:
        wanted = _wanted(argv, command)
    except ParameterError as err:
        p.error(str(err))
    p.add_argument("--variant", default=DEFAULT_VARIANT, metavar="NAME",
                   help="the landing variant: " + ", ".join(built_in_names())
                        + " (default paper), module:attribute (a Variant in any importable "
                          "module), or an installed one; `softlanding variants` lists them "
                          "with their options")
    owners: dict[str, list[str]] = {}
    first: dict[str, Option] = {}
    for v in wanted:
        for o in v.options:
            owners.setdefault(o.name, []).append(v.name)
            first.setdefault(o.name, o)
    for name, o in first.items():
        who = ", ".join(owners[name])
        kw: dict[str, Any] = (
            {"action": "store_true", "default": None} if o.is_flag else
            {"default": None, "metavar": o.metavar})
        extra = f" (one of {', '.join(map(str, o.choices))})" if o.choices else ""
        try:
            p.add_argument(o.flag, dest=name, help=f"{who}: {o.help}{extra}", **kw)
        except argparse.ArgumentError:
            p.error(f"--variant {owners[name][0]}: its option {o.flag} clashes with "
                    f"{command}'s own")
    p.set_defaults(variant_options=tuple(first))


def variant_of(a: argparse.Namespace, ground: Any) -> tuple[Variant, dict[str, Any]]:
    """The variant ``a`` names and its checked options, after refusing the options it
    does not take.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed options (the variant options None when not given).
    ground : Ground
        The ground the options name.

    Raises
    ------
    ParameterError
        An option the variant would ignore, a bad value, or no such variant (one line).
    """
    from softlanding.model.ground import LINEAR_GROUND

    v = find_variant(a.variant)
    names = tuple(getattr(a, "variant_options", ())) + PIPELINE_OPTIONS
    given = {n: getattr(a, n, None) for n in names}
    values = v.values(given)  # typed, checked, defaults filled: what decides what applies
    known = {**given, **values}
    takes = v.applicable(known)
    why = v.refusal(known) if v.refusal is not None else ""
    for n, value in given.items():
        if value not in (None, False) and n not in takes:
            raise ParameterError(_flag(n), f"does not apply to --variant {v.name}{why}")
    if ground != LINEAR_GROUND and "ground" not in takes:
        raise ParameterError("--ground", f"--variant {v.name}{why} takes only the paper's "
                                         "linear ground")
    return v, values


def sweep_command(a: argparse.Namespace, variant: Variant, options: dict[str, Any],
                  v0: Any, robot: Any, ground: Any, plot: Any) -> int:
    """``softlanding solve-sweep --variant NAME``: any variant over ``v0`` by continuation.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed options (``json``, ``accept_unverified``).
    variant : Variant
        The variant.
    options : dict
        Its checked options.
    v0 : array
        Impact velocities, from the easy end.
    robot, ground
        The landing.
    plot : Path or None
        The figure to write (depth against ``v0``).
    """
    from softlanding.cli.output import EXIT_FAILURE, EXIT_OK, print_json, savefig
    from softlanding.optimal.variants import sweep_variant

    res = sweep_variant(variant, v0, robot, ground, options, progress=not a.json)
    rows = [{"v0": float(x), **r.to_dict(), "unverified_reasons": r.unverified_reasons()}
            for x, r in zip(v0, res, strict=True)]
    unverified = [r for r in rows if r["unverified_reasons"]]
    code = EXIT_OK if not unverified or a.accept_unverified else EXIT_FAILURE
    written = None
    if plot:
        import numpy as np

        from softlanding.plots.paper import plot_depth_vs_velocity

        written = savefig(plot_depth_vs_velocity(
            np.asarray(v0), {variant.name: np.array([r.depth for r in res])}), plot)
    if a.json:
        print_json({"verified": not unverified, "variant": variant.name, "sweep": rows})
        return code
    if unverified:
        print(f"UNVERIFIED at {len(unverified)} of {len(rows)} velocities: " + "; ".join(
            f"v0 = {r['v0']:g}: {r['unverified_reasons'][0]}" for r in unverified[:3]))
    print(f"{'v0':>7} {'depth':>14}  verified  solved by")
    for r in rows:
        print(f"{r['v0']:>7.3f} {r['depth']:>14.10f}  "
              f"{'no' if r['unverified_reasons'] else 'yes':>8}  {r.get('path', '-')}")
    if written:
        print(f"figure written to {written}")
    return code


def _cmd_variants(a: argparse.Namespace) -> int:
    from softlanding.cli.output import EXIT_OK, print_json

    found = all_variants()
    if a.json:
        print_json({"variants": [v.to_dict() for v in found]})
        return EXIT_OK
    for v in found:
        print(f"{v.name}: {v.summary}")
        print(f"    from {v.module}:{v.attribute} ({v.source})")
        for o in v.options:
            req = "required" if o.required else f"default {o.default}"
            print(f"    {o.flag} ({getattr(o.type, '__name__', 'value')}, {req}): {o.help}")
        pipe = [_flag(n) for n in PIPELINE_OPTIONS if n != "no_refine" or v.refine]
        print(f"    and {', '.join(pipe)}" + (", --ground" if v.ground else ""))
    return EXIT_OK


def variants_parser(sub: Any) -> argparse.ArgumentParser:
    """The ``softlanding variants`` sub-command.

    Parameters
    ----------
    sub : argparse subparsers
        Where to add it.
    """
    p = sub.add_parser("variants", help="list the landing variants and their options",
                       description="Every landing variant `softlanding solve --variant` "
                                   "takes: built in, packaged, and installed (entry-point "
                                   "group softlanding.variants), with its options and "
                                   "where it is declared. A variant in any importable "
                                   "module is also taken as --variant module:attribute.")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_variants)
    return p


__all__ = ["DEFAULT_VARIANT", "SUBCOMMANDS", "add_variant_options", "named_variant",
           "sweep_command", "variant_of", "variants_parser"]
