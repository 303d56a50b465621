"""The built-in landing variants, declared light (no numerical library loads here): the
paper's single-phase landing, the two-phase landing and leg extension. Each solve
function is named ``"module:function"`` and imported when the variant runs, so that the
command line refuses bad input before loading CasADi or numba. A packaged or user
variant is one module instead (see :mod:`softlanding.optimal.min_peak_force`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from softlanding.errors import LIMITS
from softlanding.optimal.variants import Option, Variant


def _within(lo: int, hi: int) -> Any:
    def check(v: int) -> str | None:
        return None if lo <= v <= hi else f"must be {lo} to {hi}, got {v}"
    return check


def extension_value(text: str) -> str | float:
    """``--extension``: ``free`` or a finite leg length.

    Parameters
    ----------
    text : str
        What the user typed.
    """
    if text == "free":
        return text
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"'free' or a leg length, not {text!r}") from None


def _rate(v: float) -> str | None:
    """A relative velocity bound: >= 0, and within the model's velocities (as ``v0``'s
    range: 1e308 reached Ipopt as an infinite bound and failed)."""
    top = -LIMITS["v0"][0]
    return None if 0 <= v <= top else f"must be 0 to {top:g}, got {v:g}"


PAPER = Variant(
    "paper", "the paper's single-phase OCP (default)", "softlanding.optimal.landing:solve_landing",
    options=(Option("nodes", int, 100, "shooting intervals (2 to 5000)", _within(2, 5000)),
             Option("extra_arcs", int, 0, "also try this many more bang arcs (at most 20)",
                    _within(0, 20))),
    ground=True, certificate_figure=True)


def _two_phase_takes(values: Mapping[str, Any]) -> set[str]:
    if values.get("steps") == 2:  # the four-phase check prints a comparison
        return {"steps"}
    return {"steps", "no_refine", "pmp", "plot", "ground"}


def _two_phase_refusal(values: Mapping[str, Any]) -> str:
    return " --steps 2" if values.get("steps") == 2 else ""


TWO_PHASE = Variant(
    "two-phase", "yielding then static stance until the body stops, the arrest optimised",
    "softlanding.optimal.two_phase:solve_two_phase_variant",
    options=(Option("steps", int, 1, "yielding steps allowed (2: yielding, static, "
                                     "yielding, static, compared with one step)",
                    choices=(1, 2)),),
    ground=True, takes=_two_phase_takes, refusal=_two_phase_refusal)


def _leg_takes(values: Mapping[str, Any]) -> set[str]:
    base = {"mode", "no_refine", "pmp", "plot"}
    if values.get("mode") in (None, "impact"):  # a drop decides the touchdown by its flight
        base |= {"extension", "rate_max"}
    return base


def _leg_refusal(values: Mapping[str, Any]) -> str:
    return " --mode drop" if values.get("mode") == "drop" else ""


LEG_EXTENSION = Variant(
    "leg-extension", "the leg's state at touchdown optimised (changes the paper's initial "
                     "condition)",
    "softlanding.optimal.leg_extension:solve_leg_extension_variant",
    options=(Option("mode", str, "impact", "decide the leg's state at impact directly "
                                           "(impact: both masses at v0), or by a flight "
                                           "phase from the drop height v0^2/2 (drop)",
                    choices=("impact", "drop")),
             Option("extension", extension_value, "free",
                    "impact mode: 'free' (within the stroke) or a leg length at impact (s/2 "
                    "is the paper's)", kind="'free' or a length", metavar="L"),
             Option("rate_max", float, 0.0, "impact mode: also free the relative velocity "
                                            "at impact within +-RATE_MAX (0: the paper's, "
                                            "both masses at v0)", _rate)),
    takes=_leg_takes, refusal=_leg_refusal)

VARIANTS: Mapping[str, Variant] = {"PAPER": PAPER, "TWO_PHASE": TWO_PHASE,
                                   "LEG_EXTENSION": LEG_EXTENSION}
"""Attribute name -> variant (the attribute is what ``softlanding variants`` names)."""

__all__ = ["LEG_EXTENSION", "PAPER", "TWO_PHASE", "VARIANTS", "extension_value"]
