"""The variant table of ``softlanding solve --variant``: one row per landing variant.

A row names the variant-specific options it takes (given the others: ``--steps 2`` or
``--mode drop`` take fewer), how to solve it from the parsed options, its table rows and
its figure. :func:`variant_of` refuses an option the chosen variant would ignore (exit 2
naming the option) and fills in the defaults, so no option is ever silently dropped.
A new variant is one row here (and one name in the parser's ``--variant`` choices,
which are read from this table).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from softlanding.errors import ParameterError, check_count
from softlanding.model.robot import Impact, Robot

#: The variant-specific options of ``solve`` (argparse dests) and their defaults. The
#: parser leaves them None so that "given" and "not given" can be told apart.
VARIANT_OPTIONS: Mapping[str, object] = {
    "nodes": 100, "no_refine": False, "extra_arcs": 0, "pmp": False, "plot": None,
    "steps": 1, "mode": "impact", "extension": "free", "rate_max": None}

Rows = list[tuple[str, object]]


@dataclass(frozen=True)
class SolveVariant:
    """One row of the variant table.

    Attributes
    ----------
    name : str
        The ``--variant`` value.
    summary : str
        One line for ``--help``.
    takes : callable
        Parsed options -> the variant-specific options (:data:`VARIANT_OPTIONS` keys,
        and ``"ground"`` for a non-linear ground) that apply, given the others.
    solve : callable
        ``(options, robot, ground) -> result``, a result with ``depth``, ``notes``,
        ``to_dict()`` and ``unverified_reasons(certificate)``.
    rows : callable
        Result -> the ``label, value`` rows of the printed table.
    figures : callable
        ``(result, certificate) -> list of figures`` for ``--plot`` (the first is written
        to the file named, the next ones beside it with a ``-pmp`` suffix).
    """

    name: str
    summary: str
    takes: Callable[[argparse.Namespace], frozenset[str]]
    solve: Callable[[argparse.Namespace, Robot, Any], Any]
    rows: Callable[[Any], Rows]
    figures: Callable[[Any, Any], list[Any]]


# ----------------------------------------------------------------------- paper
def _paper_solve(a: argparse.Namespace, robot: Robot, ground: Any) -> Any:
    from softlanding.optimal.landing import solve_landing

    return solve_landing(Impact(a.v0), robot, ground, nodes=a.nodes, refine=not a.no_refine,
                         extra_arcs=a.extra_arcs)


def _paper_rows(res: Any) -> Rows:
    rows: Rows = [
        ("depth -x_f(T)" + (" (refined)" if res.refined is not None else ""), res.depth),
        ("depth, transcribed", res.depth_transcribed), ("final time T", res.T),
        ("arcs", " -> ".join(res.arcs)),
        ("switch times", ", ".join(f"{t:.12g}" for t in res.switch_times)),
        ("arrest force u_b", res.u_b), ("arrest condition active", res.arrest_active),
        ("Ipopt status", res.status), ("Ipopt iterations", res.iterations),
        ("solve time [s]", res.solve_time_s)]
    if res.replay is not None:
        rows += [("simulator replay depth", res.replay.depth),
                 ("replay difference", res.replay_difference),
                 ("replay feasible", res.replay.feasible)]
    return rows


def _paper_figures(res: Any, cert: Any) -> list[Any]:
    from softlanding.plots.paper import plot_bang_bang

    figs = [plot_bang_bang(res)]
    if cert is not None:
        from ocp import plot_certificate

        figs.append(plot_certificate(cert))
    return figs


# -------------------------------------------------------------- phased variants
def _phased_rows(res: Any) -> Rows:
    rows: Rows = [
        ("variant", res.VARIANT), ("depth -x_f", res.depth),
        ("depth, transcribed", res.depth_transcribed),
        ("paper's depth (same v0)", res.paper_depth)]
    rows += _own_rows(res)
    rows += [("arcs per phase", " | ".join(" -> ".join(a) for a in res.arcs) or "-"),
             ("phase start times", ", ".join(f"{t:.9g}" for t in res.phase_times)),
             ("solved by", res.path), ("Ipopt status", res.status)]
    if res.replay is not None:
        rows += [("simulator replay depth", res.replay.depth),
                 ("replay difference", res.replay_difference),
                 ("replay controller", res.replay_kind)]
    return rows


def _own_rows(res: Any) -> Rows:
    """The rows only one phased variant has: the arrest, or the touchdown state."""
    if hasattr(res, "steps"):
        return [("yielding steps allowed", res.steps), ("foot stops T1", res.T1),
                ("body stops T", res.T), ("arrest force (phase 2)", res.arrest_force),
                ("arrest force range", "{:.12g} .. {:.12g}".format(*res.arrest_force_range))]
    return [("mode", res.mode), ("leg length at touchdown", res.extension),
            ("relative velocity at touchdown", res.rate),
            ("centre of mass velocity at touchdown", res.com_velocity),
            ("depth gained", res.gain)]


def _phased_figures(res: Any, cert: Any) -> list[Any]:
    from softlanding.plots.phased import plot_phased_landing

    return [plot_phased_landing(res)]


def _two_phase_takes(a: argparse.Namespace) -> frozenset[str]:
    if a.steps == 2:  # the four-phase check prints a comparison, no figure or certificate
        return frozenset({"steps"})
    return frozenset({"steps", "no_refine", "pmp", "plot", "ground"})


def _two_phase_solve(a: argparse.Namespace, robot: Robot, ground: Any) -> Any:
    from softlanding.optimal.two_phase import solve_two_phase, two_step_check

    if a.steps == 2:
        return two_step_check(Impact(a.v0), robot, ground)
    return solve_two_phase(Impact(a.v0), robot, ground, refine=not a.no_refine)


def _two_phase_rows(res: Any) -> Rows:
    if hasattr(res, "one_step"):  # --steps 2
        rows: Rows = [
            ("one-step depth (refined)", res.one_step.depth),
            ("two-step depth (transcribed, best start)", res.depth),
            ("gain of a second step", res.gain), ("middle phases collapse", res.collapsed)]
        for st in res.starts:
            rows.append((f"start {st['start']}", f"depth {st['depth']:.10g}, phase durations "
                         + ", ".join(f"{d:.4g}" for d in st["durations"]) if "depth" in st
                         else f"failed ({st['error']})"))
        return rows
    return _phased_rows(res)


def _leg_extension_takes(a: argparse.Namespace) -> frozenset[str]:
    base = {"mode", "pmp", "plot"}
    if a.mode in (None, "impact"):  # a drop decides the touchdown state by its flight
        base |= {"extension", "rate_max"}
    return frozenset(base)


def _leg_extension_solve(a: argparse.Namespace, robot: Robot, ground: Any) -> Any:
    from softlanding.optimal.leg_extension import solve_leg_extension

    ext = None if a.extension == "free" else a.extension
    rate = None if a.rate_max is None else (-a.rate_max, a.rate_max)
    return solve_leg_extension(Impact(a.v0), robot, mode=a.mode, extension=ext, rate=rate)


VARIANTS: Mapping[str, SolveVariant] = {v.name: v for v in (
    SolveVariant("paper", "the paper's single-phase OCP (default)",
                 lambda a: frozenset({"nodes", "no_refine", "extra_arcs", "pmp", "plot",
                                      "ground"}),
                 _paper_solve, _paper_rows, _paper_figures),
    SolveVariant("two-phase", "yielding then static stance until the body stops, the arrest "
                              "optimised", _two_phase_takes, _two_phase_solve, _two_phase_rows,
                 _phased_figures),
    SolveVariant("leg-extension", "the leg's state at touchdown optimised (changes the paper's "
                                  "initial condition)", _leg_extension_takes,
                 _leg_extension_solve, _phased_rows, _phased_figures),
)}


def extension_value(text: str) -> str | float:
    """``--extension``: ``free`` or a finite leg length (an argparse ``type``, like
    :func:`softlanding.cli.parser.scheduler_address`: a bad value is a usage error).

    Parameters
    ----------
    text : str
        What the user typed.
    """
    if text == "free":
        return text
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'free' or a leg length, not {text!r}") from None
    if x != x or x in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"a finite leg length, not {text!r}")
    return x


#: Bounds of the variant-specific sizes, checked before any work.
_BOUNDS = {"nodes": (2, 5000), "extra_arcs": (0, 20)}


def _flag(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def variant_of(a: argparse.Namespace, ground: Any) -> SolveVariant:
    """The variant ``a`` names, after refusing the options it does not take.

    Fills the defaults of :data:`VARIANT_OPTIONS` into ``a`` once checked.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed ``solve`` options (the variant-specific ones None when not given).
    ground : Ground
        The ground the options name.

    Raises
    ------
    ParameterError
        Naming the first option the variant would ignore.
    """
    from softlanding.model.ground import LINEAR_GROUND

    v = VARIANTS[a.variant]
    takes = v.takes(a)
    for dest in VARIANT_OPTIONS:
        given = getattr(a, dest, None)
        if given not in (None, False) and dest not in takes:
            why = (" --steps 2" if a.variant == "two-phase" and a.steps == 2 else
                   " --mode drop" if a.variant == "leg-extension" and a.mode == "drop" else "")
            raise ParameterError(_flag(dest), f"does not apply to --variant {a.variant}{why}")
    if ground != LINEAR_GROUND and "ground" not in takes:
        raise ParameterError("--ground", f"--variant {a.variant}"
                             + (" --steps 2" if a.steps == 2 else "")
                             + " takes only the paper's linear ground")
    for dest, default in VARIANT_OPTIONS.items():
        if getattr(a, dest, None) is None:
            setattr(a, dest, default)
    for dest, (lo, hi) in _BOUNDS.items():
        setattr(a, dest, check_count(_flag(dest), getattr(a, dest), lo, hi))
    if a.rate_max is not None and not a.rate_max >= 0:
        raise ParameterError("--rate-max", f"must be >= 0, got {a.rate_max:g}")
    return v


__all__ = ["VARIANTS", "VARIANT_OPTIONS", "SolveVariant", "extension_value", "variant_of"]
