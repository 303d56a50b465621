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
import sys
from collections.abc import Sequence
from typing import Any

from softlanding.errors import ParameterError, SoftlandingError
from softlanding.optimal.variants import (
    PIPELINE_OPTIONS,
    Option,
    Variant,
    VariantError,
    built_in_names,
    built_in_variants,
    find_variant,
    survey_variants,
)

DEFAULT_VARIANT = "paper"
SUBCOMMANDS = ("solve", "solve-sweep")
"""The sub-commands that take ``--variant``."""


def _flag(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def named_variant(argv: Sequence[str] | None) -> str | None:
    """The ``--variant`` value in ``argv`` (a look before parsing; the last one given, as
    argparse takes it; None when not there).

    Parameters
    ----------
    argv : sequence of str or None
        The command line.
    """
    args = list(argv or [])
    found = None
    for i, arg in enumerate(args):  # the last, as argparse takes it
        if arg == "--variant" and i + 1 < len(args):
            found = args[i + 1]
        elif arg.startswith("--variant="):
            found = arg.split("=", 1)[1]
    return found


def _wanted(argv: Sequence[str] | None, command: str) -> list[Variant]:
    """The variants whose options the ``command`` parser needs for ``argv`` (for
    ``--help``: every one that loads, and the one named; a broken plug-in is one line on
    stderr, the rest still listed)."""
    args = list(argv or [])
    if command not in args:
        return built_in_variants()
    rest = args[args.index(command) + 1:]
    name = named_variant(rest)
    if "-h" in rest or "--help" in rest:
        found, failures = survey_variants([] if name is None else [name])
        warn_failures(failures)
        return found
    out = built_in_variants()
    if name is not None and name not in {v.name for v in out}:
        out.append(find_variant(name))
    return out


def warn_failures(failures: Sequence[VariantError]) -> None:
    """One line on stderr for each variant that does not load.

    Parameters
    ----------
    failures : sequence of VariantError
        From :func:`~softlanding.optimal.variants.survey_variants`.
    """
    for err in failures:
        print(f"softlanding: {err.label}: {err} (left out)", file=sys.stderr)


def variant_label(v: Variant) -> str:
    """The variant as the output names it: its own name, and where a user's module comes
    from (``min-peak-force (mymod:VARIANT)``).

    Parameters
    ----------
    v : Variant
        The variant that ran.
    """
    return v.name if v.spec == v.name else f"{v.name} ({v.spec})"


def labelled_rows(v: Variant, rows: Sequence[tuple[str, object]]) -> list[tuple[str, object]]:
    """A result's table with the variant named by its declaration (a copy of a packaged
    module keeps its result class, whose name would be the original's): its ``variant``
    row, or a first one for a user's variant whose result has none.

    Parameters
    ----------
    v : Variant
        The variant that ran.
    rows : sequence of (str, object)
        The result's rows.
    """
    if not any(r[0] == "variant" for r in rows) and v.source in ("built-in", "packaged"):
        return list(rows)
    return [("variant", variant_label(v))] + [r for r in rows if r[0] != "variant"]


def labelled_dict(v: Variant, d: dict[str, Any]) -> dict[str, Any]:
    """A result's JSON with the variant named by its declaration, and where it is declared.

    Parameters
    ----------
    v : Variant
        The variant that ran.
    d : dict
        The result's ``to_dict()``.
    """
    return {**d, "variant": v.name, "variant_from": f"{v.module}:{v.attribute}"}


def refusal_of_unknown(a: argparse.Namespace, extras: Sequence[str]) -> ParameterError | None:
    """For ``solve``/``solve-sweep``, an unknown option that another variant declares: the
    same refusal as an option the chosen variant does not take (None: not such a one).

    Parameters
    ----------
    a : argparse.Namespace
        What parsed.
    extras : sequence of str
        What did not.
    """
    if getattr(a, "command", None) not in SUBCOMMANDS:
        return None
    flags = [x.split("=", 1)[0] for x in extras if x.startswith("--")]
    if not flags:
        return None
    found, _ = survey_variants()  # only on this error: may import the packaged modules
    for flag in flags:
        owners = [v.name for v in found if flag in {o.flag for o in v.options}]
        if owners:
            return ParameterError(flag, f"does not apply to --variant {a.variant} (an option "
                                        f"of {', '.join(owners)})")
    return None


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
    except SoftlandingError as err:  # no such variant, or a user's module that fails
        if "--debug" in (argv or ()):  # parsed later: its traceback is wanted now
            raise
        p.error(f"--variant {err}" if isinstance(err, VariantError) else str(err))
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
        try:
            p.add_argument(o.flag, dest=name, help=f"{who}: {o.help} ({o.describe()})", **kw)
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
    """``softlanding solve-sweep [--variant NAME]``: any variant, the paper's too, over
    ``v0`` by continuation; one table, JSON and figure for all (the depth, the variant's
    objective when it minimises something else, and the rigid leg's depth for scale).

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
        The figure to write (depth, and the variant's objective, against ``v0``).
    """
    from softlanding.cli.output import EXIT_FAILURE, EXIT_OK, print_json, savefig
    from softlanding.optimal.variants import sweep_variant
    from softlanding.studies.comparison import rigid_depth

    res = sweep_variant(variant, v0, robot, ground, options, progress=not a.json)
    attr, what = variant.objective
    rows = []
    for x, r in zip(v0, res, strict=True):
        rd = rigid_depth(float(x), ground)
        d = labelled_dict(variant, r.to_dict())
        rows.append({"v0": float(x), **d, "path": getattr(r, "path", d.get("path", "-")),
                     "objective": float(getattr(r, attr)), "rigid_depth": rd,
                     "ratio_to_rigid": float(r.depth) / rd,
                     "unverified_reasons": r.unverified_reasons()})
    unverified = [r for r in rows if r["unverified_reasons"]]
    code = EXIT_OK if not unverified or a.accept_unverified else EXIT_FAILURE
    written = None
    if plot:
        import numpy as np

        from softlanding.plots.phased import plot_variant_sweep

        written = savefig(plot_variant_sweep(
            np.asarray(v0), np.array([r["depth"] for r in rows]), variant_label(variant),
            None if attr == "depth" else (what, np.array([r["objective"] for r in rows])),
            {"rigid leg": np.array([r["rigid_depth"] for r in rows])}), plot)
    if a.json:
        print_json({"verified": not unverified, "variant": variant.name, "objective": attr,
                    "sweep": rows})
        return code
    if unverified:
        print(f"UNVERIFIED at {len(unverified)} of {len(rows)} velocities: " + "; ".join(
            f"v0 = {r['v0']:g}: {r['unverified_reasons'][0]}" for r in unverified[:3]))
    _print_sweep(variant_label(variant), None if attr == "depth" else what, rows)
    if written:
        print(f"figure written to {written}")
    return code


def _flat(times: Any) -> list[float]:
    """Switch times, a phased variant's (a list per phase) in one list."""
    return [t for v in times for t in _flat(v)] if isinstance(times, list | tuple) else [times]


def _print_sweep(label: str, what: str | None, rows: list[dict[str, Any]]) -> None:
    """The sweep's table: ``v0``, depth, the objective (``what``, None: the depth), the
    rigid leg's depth and the ratio, the landing's time and switches where the variant
    reports them, and how each was solved."""
    timed = all(isinstance(r.get("T"), float) and "switch_times" in r for r in rows)
    print(f"variant {label}" + (f", minimising {what}" if what else ""))
    print(f"{'v0':>7} {'depth':>14}" + (f" {what[:14]:>14}" if what else "")
          + f" {'rigid':>10} {'ratio':>7}" + (f" {'T':>8}  switch  " if timed else "")
          + "  verified  solved by")
    for r in rows:
        by = "structure re-solve" if r["path"] == "structure" else str(r["path"])
        if "iterations" in r:
            by += f" ({r['iterations']} it.)"
        sw = ",".join(f"{t:.5f}" for t in _flat(r["switch_times"])) if timed else ""
        print(f"{r['v0']:>7.3f} {r['depth']:>14.10f}"
              + (f" {r['objective']:>14.10f}" if what else "")
              + f" {r['rigid_depth']:>10.6f} {r['ratio_to_rigid']:>7.4f}"
              + (f" {r['T']:>8.5f}  {sw:<7}" if timed else "")
              + f"  {'no' if r['unverified_reasons'] else 'yes':>8}  {by}")


def _cmd_variants(a: argparse.Namespace) -> int:
    from softlanding.cli.output import EXIT_OK, print_json

    named = list(a.variant or [])
    found, failures = survey_variants(named)
    for name in named:  # one the user named that does not load: their error, exit 2
        if not any(name in (v.name, v.spec) for v in found):
            bad = [f for f in failures if f.spec.split(" ")[0] == name]
            raise bad[0] if bad else VariantError(name, "does not load")
    warn_failures(failures)
    if a.json:
        print_json({"variants": [v.to_dict() for v in found],
                    "not_loaded": [str(f) for f in failures]})
        return EXIT_OK
    for v in found:
        print(f"{variant_label(v)}: {v.summary}")
        print(f"    from {v.module}:{v.attribute} ({v.source})")
        for o in v.options:
            print(f"    {o.flag} ({o.describe()}): {o.help}")
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
    p.add_argument("--variant", action="append", metavar="MODULE:ATTRIBUTE",
                   help="also list this variant (a Variant in any importable module; may be "
                        "given several times)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_variants)
    return p


__all__ = ["DEFAULT_VARIANT", "SUBCOMMANDS", "add_variant_options", "labelled_dict",
           "labelled_rows", "named_variant", "refusal_of_unknown", "sweep_command",
           "variant_label", "variant_of", "variants_parser", "warn_failures"]
