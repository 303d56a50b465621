"""Handlers of ``softlanding solve --variant two-phase|leg-extension`` and ``softlanding hop``.

They follow :mod:`softlanding.cli.main`'s conventions: output files are checked before
any work (``target``) and written atomically (``savefig``), ``--json`` prints one
object with ``verified`` and ``unverified_reasons``, and a result that failed a
check exits 1 unless ``--accept-unverified``.
"""

from __future__ import annotations

import argparse
from typing import Any

from softlanding.errors import ParameterError
from softlanding.model.robot import Impact


def _extension(a: argparse.Namespace) -> tuple[Any, Any]:
    """``--extension`` (free, or a leg length) and ``--rate-max`` as solver arguments."""
    ext = None if a.extension in (None, "free") else float(a.extension)
    rate = None if not a.rate_max else (-float(a.rate_max), float(a.rate_max))
    if a.rate_max is not None and a.rate_max < 0:
        raise ParameterError("rate-max", f"must be >= 0, got {a.rate_max:g}")
    return ext, rate


def _variant_rows(res: Any) -> list[tuple[str, object]]:
    rows: list[tuple[str, object]] = [
        ("variant", res.to_dict()["variant"]), ("depth -x_f", res.depth),
        ("depth, transcribed", res.depth_transcribed),
        ("paper's depth (same v0)", res.paper_depth)]
    if hasattr(res, "steps"):
        rows += [("yielding steps allowed", res.steps), ("foot stops T1", res.T1),
                 ("body stops T", res.T), ("arrest force (phase 2)", res.arrest_force),
                 ("arrest force range", "{:.12g} .. {:.12g}".format(*res.arrest_force_range))]
    else:
        rows += [("mode", res.mode), ("leg length at touchdown", res.extension),
                 ("relative velocity at touchdown", res.rate),
                 ("centre of mass velocity at touchdown", res.com_velocity),
                 ("depth gained", res.gain)]
    rows += [("arcs per phase", " | ".join(" -> ".join(a) for a in res.arcs) or "-"),
             ("phase start times", ", ".join(f"{t:.9g}" for t in res.phase_times)),
             ("solved by", res.path), ("Ipopt status", res.status)]
    if res.replay is not None:
        rows += [("simulator replay depth", res.replay.depth),
                 ("replay difference", res.replay_difference),
                 ("replay controller", res.replay_kind)]
    return rows


def cmd_solve_variant(a: argparse.Namespace, robot: Any, plot: Any) -> int:
    """``solve --variant two-phase|leg-extension``.

    Parameters
    ----------
    a : argparse.Namespace
        The parsed arguments.
    robot : Robot
        The robot of the model arguments.
    plot : Path or None
        The figure to write (checked already).
    """
    from softlanding.cli.ground import ground_of
    from softlanding.cli.output import EXIT_FAILURE, EXIT_OK, print_json, print_table, savefig
    from softlanding.model.ground import LINEAR_GROUND

    ground = ground_of(a)
    if ground != LINEAR_GROUND and (a.variant != "two-phase" or a.steps == 2):
        raise ParameterError("ground", "only --variant two-phase (one step) takes another "
                                       "ground than the paper's linear spring")
    res: Any
    if a.variant == "two-phase" and a.steps == 2:
        return _two_steps(a, robot)
    if a.variant == "two-phase":
        from softlanding.optimal.two_phase import solve_two_phase

        res = solve_two_phase(Impact(a.v0), robot, ground)
    else:
        from softlanding.optimal.leg_extension import solve_leg_extension

        ext, rate = _extension(a)
        res = solve_leg_extension(Impact(a.v0), robot, mode=a.mode, extension=ext, rate=rate)
    cert = res.certify() if a.pmp else None
    written = None
    if plot:
        from softlanding.plots.phased import plot_phased_landing

        written = savefig(plot_phased_landing(res), plot)
    reasons = res.unverified_reasons(cert)
    if a.json:
        d = res.to_dict()
        if cert is not None:
            d["pmp"] = cert.to_dict()
        print_json({"verified": not reasons, "unverified_reasons": reasons, **d})
    else:
        status = "yes" if not reasons else "NO: " + "; ".join(reasons)
        rows = [("verified", status)] + _variant_rows(res)
        if cert is not None:
            rows += [("PMP verdict", cert.verdict),
                     ("max |H - H_expected| / H_scale", cert.H_max_abs),
                     ("junction costate gaps", ", ".join(f"{g:.2e}" for g in
                                                         cert.junction_gaps))]
        print_table(rows)
        for n in res.notes:
            print(f"note: {n}")
        for r_ in (cert.reasons if cert is not None else []):
            print(f"PMP: {r_}")
        if written:
            print(f"figure written to {written}")
    return EXIT_OK if not reasons or a.accept_unverified else EXIT_FAILURE


def _two_steps(a: argparse.Namespace, robot: Any) -> int:
    """``--steps 2``: the four-phase landing from several starts against the two-phase one."""
    from softlanding.cli.output import EXIT_FAILURE, EXIT_OK, print_json, print_table
    from softlanding.optimal.two_phase import two_step_check

    c = two_step_check(Impact(a.v0), robot)
    reasons = c.one_step.unverified_reasons()
    if a.json:
        print_json({"verified": not reasons, "unverified_reasons": reasons, "depth": c.depth,
                     **c.to_dict()})
    else:
        print_table([("verified (one-step optimum)", "yes" if not reasons else
                       "NO: " + "; ".join(reasons)),
                      ("one-step depth (refined)", c.one_step.depth),
                      ("two-step depth (transcribed, best start)", c.depth),
                      ("gain of a second step", c.gain),
                      ("middle phases collapse", c.collapsed)])
        for st in c.starts:
            print(f"start {st['start']}: " + (f"depth {st['depth']:.10g}, phase durations "
                  + ", ".join(f"{d:.4g}" for d in st["durations"]) if "depth" in st
                  else f"failed ({st['error']})"))
    return EXIT_OK if not reasons or a.accept_unverified else EXIT_FAILURE


def _hop_rows(c: Any) -> list[tuple[str, object]]:
    rows: list[tuple[str, object]] = [
        ("energy per cycle", c.energy), ("energy / apex height", c.specific_energy),
        ("positive work", c.work.positive), ("negative work", c.work.negative),
        ("ground loss d^2/2", c.depth ** 2 / 2), ("crater depth", c.depth),
        ("paper's CoT of the landing", c.cot), ("energy (optimiser's slack)",
                                                 c.energy_transcribed),
        ("apex posture error", c.apex_error), ("energy balance error", c.balance_error)]
    rows += [(k, v) for k, v in c.gains.items()]
    rows += [(f"time: {k}", v) for k, v in c.times.items()]
    return rows


def cmd_hop(a: argparse.Namespace) -> int:
    """``softlanding hop``: the hop cycle of one or all legs.

    Parameters
    ----------
    a : argparse.Namespace
        The parsed arguments.
    """
    from softlanding.cli.output import (
        EXIT_FAILURE,
        EXIT_OK,
        print_json,
        print_table,
        robot_of,
        savefig,
        target,
    )
    from softlanding.errors import InfeasibleLandingError
    from softlanding.optimal.hopping import best_impedance_hop, rigid_hop, solve_hop

    robot = robot_of(a)
    plot = target(a)
    legs = ("free", "impedance", "rigid") if a.leg == "all" else (a.leg,)
    cycles: dict[str, Any] = {}
    for leg in legs:
        if leg == "free":
            cycles[leg] = solve_hop(Impact(a.v0), robot, a.eta)
        elif leg == "rigid":
            cycles[leg] = rigid_hop(Impact(a.v0), robot, a.eta)
        else:
            cycles[leg] = best_impedance_hop(Impact(a.v0), robot, a.eta, grid=a.grid)
            if cycles[leg] is None:
                raise InfeasibleLandingError(
                    f"no impedance in the {a.grid} x {a.grid} gain grid (k_p in [0.05, 2], "
                    f"k_d in [0, 2]) hops to the apex: no thrust within u_max = "
                    f"{robot.u_max:g} restores it inside the stroke")
    reasons = {k: c.unverified_reasons() for k, c in cycles.items()}
    bad = any(reasons.values())
    written = None
    if plot:
        from softlanding.plots.phased import plot_hop

        written = savefig(plot_hop(cycles[legs[0]]), plot)
    if a.json:
        first = cycles[legs[0]]
        print_json({"verified": not bad, "unverified_reasons": reasons,
                     "energy": first.energy, "cot": first.cot, "depth": first.depth,
                     "leg": legs[0], "eta": a.eta, "v0": a.v0, "apex_height": first.apex_height,
                     "cycles": {k: c.to_dict() for k, c in cycles.items()}})
    else:
        for leg, c in cycles.items():
            ok = "yes" if not reasons[leg] else "NO: " + "; ".join(reasons[leg])
            print(f"== {leg} leg, v0 = {a.v0:g} (apex {c.apex_height:.6g}), eta = {a.eta:g}")
            print_table([("verified", ok)] + _hop_rows(c))
            for n in c.notes:
                print(f"note: {n}")
        if written:
            print(f"figure written to {written}")
    return EXIT_OK if not bad or a.accept_unverified else EXIT_FAILURE


__all__ = ["cmd_hop", "cmd_solve_variant"]
