"""``softlanding scale``: a physical robot in the paper's dimensionless numbers, and back."""

from __future__ import annotations

import argparse
from typing import Any

from softlanding.cli.output import EXIT_OK, print_json, print_table
from softlanding.errors import ParameterError
from softlanding.model.robot import G_EARTH, PAPER_ROBOT, Impact, Robot

SI_FLAGS = ("mb", "mf", "stroke", "umax_si", "v0_si", "Kp", "Kd")
TO_SI_FLAGS = ("rm", "s", "v0", "umax", "kp", "kd")


def _scale_from_si(a: argparse.Namespace) -> Any:
    from softlanding.model.scaling import PhysicalParams, paper_rig

    given = {name: getattr(a, flag) for flag, name in
             (("mb", "m_b"), ("mf", "m_f"), ("kg", "k_g"), ("stroke", "stroke"),
              ("umax_si", "u_max"), ("Kp", "K_p"), ("Kd", "K_d"), ("g", "g"),
              ("v0_si", "v0")) if getattr(a, flag) is not None}
    if getattr(a, "medium", None) is not None or getattr(a, "foot_diameter", None) is not None:
        from softlanding.cli.ground import rft_stiffness_of

        given["k_g"] = rft_stiffness_of(a)
    if a.preset == "paper":
        return paper_rig(**given)  # every flag given overrides the preset
    missing = [f for f, n in (("mb", "m_b"), ("mf", "m_f"), ("kg", "k_g"),
                              ("stroke", "stroke")) if n not in given]
    if missing:
        raise ParameterError(missing[0], "is required (or use --preset paper)")
    return PhysicalParams(**given)


def scale_command(a: argparse.Namespace) -> int:
    """``softlanding scale``: SI to dimensionless numbers, or back with ``--to-si``.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    from softlanding.model.controllers import Impedance
    from softlanding.model.robot import Units
    from softlanding.model.scaling import PhysicalParams

    if a.to_si:
        wrong = [f for f in SI_FLAGS if getattr(a, f) is not None] + (
            ["preset"] if a.preset else [])
        if wrong:
            raise ParameterError(wrong[0], "is an SI input; with --to-si give the "
                                           "dimensionless numbers and --mt, --kg, --g")
        if a.kg is None:
            raise ParameterError("kg", "is required with --to-si (ground stiffness in N/m)")
        units = Units(a.mt, a.kg, G_EARTH if a.g is None else a.g)
        gains = None if a.kp is None and a.kd is None else Impedance(
            0.0 if a.kp is None else a.kp, 0.0 if a.kd is None else a.kd)
        ph = PhysicalParams.from_dimensionless(
            Robot(r_m=PAPER_ROBOT.r_m if a.rm is None else a.rm,
                  s=PAPER_ROBOT.s if a.s is None else a.s, u_max=a.umax),
            Impact(-1.0 if a.v0 is None else a.v0), units, gains)
    else:
        wrong = [f for f in TO_SI_FLAGS if getattr(a, f) is not None]
        if wrong:
            raise ParameterError(wrong[0], "is a dimensionless input; use it with --to-si")
        ph = _scale_from_si(a)
    robot, impact, controller, _ = ph.to_dimensionless()
    gain_dict = {} if controller is None else {k: v for k, v in controller.to_dict().items()
                                               if k in ("k_p", "k_d")}
    dimensionless = {**robot.to_dict(), **impact.to_dict(), **gain_dict}
    out = {"physical": ph.to_dict(), "dimensionless": dimensionless,
           "scales": ph.units.to_dict()}
    if getattr(a, "medium", None) is not None:
        from softlanding.model.terrain import PAPER_K_G

        out["rft"] = {"medium": a.medium, "k_g_rft": ph.units.k_g, "k_g_paper": PAPER_K_G,
                      "ratio": ph.units.k_g / PAPER_K_G}
    if a.json:
        print_json(out)
    else:
        rows = [(f"SI {k}", v) for k, v in ph.to_dict().items() if v is not None]
        if "rft" in out:
            rows += [("RFT k_g [N/m]", out["rft"]["k_g_rft"]),
                     ("paper's measured k_g [N/m]", out["rft"]["k_g_paper"]),
                     ("RFT / measured", out["rft"]["ratio"])]
        rows += [(f"scale {k}", v) for k, v in ph.units.to_dict().items()]
        rows += [(f"dimensionless {k}", v) for k, v in dimensionless.items() if v is not None]
        print_table(rows)
    return EXIT_OK


__all__ = ["SI_FLAGS", "TO_SI_FLAGS", "scale_command"]
