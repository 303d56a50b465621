"""The ``softlanding`` command.

Every sub-command prints a readable table by default and one JSON object with
``--json``. The commands only parse, call the API and print: every number
comes from :mod:`softlanding`. Exit codes: 0 ok, 1 a well-posed run that
failed (rest not proven, solver failure), 2 bad input, 3 internal error (a
bug: ``--debug`` shows the traceback), 130 interrupted, 143 terminated (SIGTERM),
129 hung up (SIGHUP).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from typing import Any

from softlanding.cli.cache import cache_command
from softlanding.cli.export import export_command
from softlanding.cli.ground import ground_text
from softlanding.cli.mpc import mpc_command
from softlanding.cli.output import (
    EXIT_FAILURE,
    EXIT_OK,
    CliParser,
    fmt,
    ground_of_args,
    print_json,
    print_table,
    report_error,
    robot_of,
    savefig,
    target,
)
from softlanding.cli.parser import DEMO_FIGURE, DEMO_FOLDER, dask_timeout
from softlanding.cli.robust import robust_command
from softlanding.cli.scale import scale_command
from softlanding.errors import InfeasibleLandingError, ParameterError, check_count
from softlanding.model.robot import PAPER_ROBOT, Impact, Robot
from softlanding.simulation.kernel_cache import interpret_unless_cached

# ------------------------------------------------------------------- simulate
_DEPTH_LABEL = {"final": "depth -x_f(T)", "limit": "depth limit (t -> inf)",
                "reached": "depth reached (rest not proven)"}


def _cmd_simulate(a: argparse.Namespace) -> int:
    from softlanding.model.controllers import Impedance, Rigid

    if a.rigid and (a.kp is not None or a.kd is not None):
        raise ParameterError("rigid", "--rigid takes no --kp/--kd (choose one leg)")
    if not a.rigid and (a.kp is None or a.kd is None):
        raise ParameterError("kp", "give both --kp and --kd, or --rigid")
    controller = Rigid() if a.rigid else Impedance(a.kp, a.kd)
    plot, robot, impact, ground = target(a), robot_of(a), Impact(a.v0), ground_of_args(a)
    from softlanding.simulation.simulator import simulate

    res = simulate(robot, impact, controller, ground)
    written = None
    if plot:
        from softlanding.plots.paper import plot_trajectory

        written = savefig(plot_trajectory(res), plot)
    if a.json:
        print_json(res.to_dict())
    else:
        e = res.energy
        print_table([
            ("controller", controller.describe()), ("v0", a.v0), ("r_m", a.rm), ("s", a.s),
            (_DEPTH_LABEL[res.depth_kind], res.depth), ("intrusion steps", res.steps),
            ("stroke held (0<=stroke<=s)", res.stroke_held), ("rest proven", res.rest_proven),
            ("feasible (held and at rest)", res.feasible), ("status", res.status),
            ("first foot stop tau", res.t_first_stop), ("final rest tau T", res.T),
            ("peak |u|", res.u_peak), ("stroke min", res.stroke_min),
            ("stroke max", res.stroke_max), ("E(0)", e.E0), ("E(T)", e.ET),
            ("ground loss", e.ground), ("actuator loss", e.actuator), ("CoT", e.cot),
        ] + ([("ground model", res.ground.name), ("drag loss", e.drag),
              ("grain loss", e.grains)] if e.integrated else []))
        if written:
            print(f"figure written to {written}")
    return EXIT_OK if res.rest_proven else EXIT_FAILURE


# ---------------------------------------------------------------------- solve
def _certificate_rows(cert: Any) -> list[tuple[str, object]]:
    if hasattr(cert, "rows"):  # a certificate that lays out its own rows (per arc)
        return cert.rows()
    if hasattr(cert, "junction_gaps"):  # the phases' certificate
        return [("PMP verdict", cert.verdict),
                ("max |H - H_expected| / H_scale", cert.H_max_abs),
                ("junction costate gaps", ", ".join(f"{g:.2e}" for g in cert.junction_gaps))]
    side = getattr(cert, "final_time_at_bound", 0)  # (H held to a side of it, not to it)
    return [("PMP verdict", cert.verdict), ("PMP costate source", cert.source),
            ("max |H - H_expected| / H_scale" if not side else
             f"H's excess past H_expected (T at its {'upper' if side > 0 else 'lower'} "
             "bound) / H_scale", cert.H_max_abs),
            ("H variation / H_scale", cert.H_variation),
            ("sigma sign agreement", cert.sigma_sign_agreement),
            ("switch to sigma-zero gap", cert.switch_sigma_gap),
            ("costate estimates gap", cert.costate_estimates_gap),
            ("singular intervals", cert.singular_intervals or "none"),
            ("state-constrained intervals", cert.state_constraint_active_intervals or "none")]


def _cmd_solve(a: argparse.Namespace) -> int:
    """Every ``--variant`` through one flow: check, solve, certify, plot, print (the
    result's protocol, :class:`softlanding.optimal.variants.VariantResult`)."""
    from softlanding.cli.variants import labelled_dict, labelled_rows, variant_of
    from softlanding.util.files import output_path

    robot, ground = robot_of(a), ground_of_args(a)
    variant, options = variant_of(a, ground)  # refuses what the variant would ignore
    plot = target(a)
    pmp_plot = None
    if plot is not None and a.pmp and variant.certificate_figure:
        pmp_plot = output_path(plot.with_name(f"{plot.stem}-pmp{plot.suffix}"), "plot", a.force)
    from softlanding.optimal.limits import force_limit

    impact = Impact(a.v0)
    force_limit(robot)  # checked before the solver loads
    res = variant.run(impact, robot, ground, options, refine=not a.no_refine)
    cert = res.certify() if a.pmp else None
    no_cert = res.uncertified_reason() if a.pmp and cert is None else ""
    written = [savefig(fig, path) for fig, path in
               zip(res.figures(cert) if plot else [], (plot, pmp_plot), strict=False)
               if path is not None]
    unverified = res.unverified_reasons(cert)
    if a.json:
        d = labelled_dict(variant, res.to_dict())
        if cert is not None:
            d["pmp"] = cert.to_dict()
        elif a.pmp:
            d["pmp"] = {"verdict": None, "why_none": no_cert}
        print_json({"verified": not unverified, "unverified_reasons": unverified, **d})
    else:
        status = "yes" if not unverified else "NO: " + "; ".join(unverified)
        print_table([("verified", status)] + labelled_rows(variant, res.rows())
                    + (_certificate_rows(cert) if cert is not None else []))
        for n in res.notes:
            print(f"note: {n}")
        for r_ in (cert.reasons if cert is not None else [no_cert] if no_cert else []):
            print(f"PMP: {r_}")
        if written:
            print(f"figure written to {' and '.join(written)}")
    return EXIT_OK if not unverified or a.accept_unverified else EXIT_FAILURE


def _v0_grid(a: argparse.Namespace) -> Any:
    """The sweep's impact velocities, from the easy end (continuation)."""
    import numpy as np

    n = check_count("n", a.n, 1, 10_000)
    for name in ("v0_min", "v0_max"):
        try:
            Impact(getattr(a, name))
        except ParameterError as err:  # named by the option given, not the Impact's "v0"
            raise ParameterError(name, str(err).partition(": ")[2]) from None
    if a.v0_min > a.v0_max:
        raise ParameterError("v0_min", f"must not exceed --v0-max ({a.v0_max:g})")
    if a.v0_min == a.v0_max and n > 1:  # (it solved the one velocity n times)
        raise ParameterError("n", f"{n} velocities over the one --v0-min = --v0-max = "
                                  f"{a.v0_min:g}: give --n 1 or a range")
    return np.linspace(a.v0_max, a.v0_min, n)


def _cmd_solve_sweep(a: argparse.Namespace) -> int:
    from softlanding.cli.variants import sweep_command, variant_of

    v, plot, ground, robot = _v0_grid(a), target(a), ground_of_args(a), robot_of(a)
    variant, options = variant_of(a, ground)
    return sweep_command(a, variant, options, v, robot, ground, plot)


# ------------------------------------------------------------------ impedance
def _cmd_impedance(a: argparse.Namespace) -> int:
    from softlanding.cli.ground import grounds_of

    robot, impact, ground = robot_of(a), Impact(a.v0), grounds_of(a)
    grid = check_count("grid", a.grid, 2, 2001)
    from softlanding.studies.impedance import optimize_impedance

    o = optimize_impedance(impact, robot, ground, objective=a.objective, grid=grid)
    if a.json:
        print_json(o.to_dict())
        return EXIT_OK
    g = o.grid_best
    several = len(o.grounds) > 1
    rows: list[tuple[str, Any]] = [
        ("objective", o.objective + (" (worst case over the grounds)" if several else "")),
        ("v0", o.v0), ("optimal k_p", o.k_p),
        ("optimal k_d", o.k_d), (f"{o.objective} at the optimum", o.value), ("depth", o.depth),
        ("intrusion steps", o.steps), ("peak |u|", o.u_peak), ("stroke min", o.stroke_min),
        ("stroke max", o.stroke_max), ("CoT (dissipative)", o.cot),
        ("CoT (lossless)", o.cot_lossless), ("on stroke boundary", o.on_stroke_boundary),
        ("active constraint", o.active_constraint or "none"),
        ("best grid point", f"k_p={g['k_p']:g}, k_d={g['k_d']:g}, "
                            f"{o.objective}={g['value']:.10g}"),
        ("landings simulated", o.evaluations)]
    if several:
        rows.insert(6, ("worst ground(s)", "; ".join(ground_text(o.grounds[i])
                                                     for i in o.worst)))
        rows += [(f"depth on {ground_text(gr)}", f"{d:.10g} (stroke margin {m:.3g})")
                 for gr, d, m in zip(o.grounds, o.ground_depths, o.ground_margins,
                                     strict=True)]
    print_table(rows)
    return EXIT_OK


def _cmd_map(a: argparse.Namespace) -> int:
    robot, impact, ground = robot_of(a), Impact(a.v0), ground_of_args(a)
    out, plot = target(a, "out"), target(a)
    check_count("n", a.n, 2, 2001)
    timeout = dask_timeout(a)
    from softlanding.studies.impedance import optimize_impedance
    from softlanding.studies.sweeps import depth_map, save_dataset
    from softlanding.util.files import atomic

    ds = depth_map(impact, robot, ground, n=a.n, scheduler=a.scheduler, dask_timeout=timeout)
    opt = optimize_impedance(impact, robot, ground, grid=a.n)
    with atomic(out) as tmp:  # nothing is written unless the whole run succeeded
        save_dataset(ds, tmp)
    written = None
    if plot:
        from softlanding.plots.paper import plot_depth_map

        written = savefig(plot_depth_map(ds, opt), plot)
    summary = {"out": str(out), "plot": written, "landings": int(ds.depth.size),
               "feasible_fraction": float(ds.strictly_feasible.mean()),
               "optimum": opt.to_dict()}
    if a.json:
        print_json(summary)
    else:
        print(f"{summary['landings']} landings, {summary['feasible_fraction']:.1%} feasible; "
              f"dataset written to {out}")
        print(f"optimum: k_p = {opt.k_p:.8f}, k_d = {opt.k_d:.8f}, depth {opt.depth:.10f} "
              f"({opt.steps} step(s), on stroke boundary: {fmt(opt.on_stroke_boundary)})")
        if written:
            print(f"figure written to {written}")
    return EXIT_OK


def _print_curves(curves: Any, objective: str) -> None:
    for r in curves.r_m.values:
        for s in curves.s.values:
            c = curves.sel(r_m=r, s=s)
            print(f"r_m = {r:g}, s = {s:g}, objective {objective}")
            print(f"{'v0':>7} {'k_p*':>11} {'k_d*':>11} {'depth':>11} {'steps':>5} "
                  f"{'peak|u|':>8} {'CoT':>8} boundary")
            for i in range(c.v0.size):
                if not bool(c.feasible[i]):
                    print(f"{float(c.v0[i]):>7.2f}   no gains in [0, 1]^2 keep the stroke")
                    continue
                print(f"{float(c.v0[i]):>7.2f} {float(c.k_p[i]):>11.7f} "
                      f"{float(c.k_d[i]):>11.7f} {float(c.depth[i]):>11.7f} "
                      f"{int(c.steps[i]):>5d} {float(c.u_peak[i]):>8.4f} "
                      f"{float(c.cot[i]):>8.4f} {fmt(bool(c.on_stroke_boundary[i]))}")


def _cmd_sweep(a: argparse.Namespace) -> int:
    v0 = _v0_grid(a)
    if a.objective != "depth":
        if not (v0 < 0).any():
            raise ParameterError("v0-min", f"--objective {a.objective} divides by the impact "
                                           "energy: give velocities below 0")
        if not (v0 < 0).all():
            print(f"softlanding: v0 = 0 left out: --objective {a.objective} divides by the "
                  "impact energy", file=sys.stderr)
        v0 = v0[v0 < 0]
    robot = Robot(r_m=(a.rm or [PAPER_ROBOT.r_m])[0], s=(a.s or [PAPER_ROBOT.s])[0],
                  u_max=a.umax)
    for rm in a.rm or [robot.r_m]:  # every family, before the work
        for s in a.s or [robot.s]:
            Robot(r_m=rm, s=s, u_max=a.umax)
    out, plot, ground = target(a, "out"), target(a), ground_of_args(a)
    grid = check_count("grid", a.grid, 2, 2001)
    timeout = dask_timeout(a)
    from softlanding.studies.sweeps import (
        optimal_impedance_curves,
        paper_observations,
        save_dataset,
    )
    from softlanding.util.files import atomic

    curves = optimal_impedance_curves(v0, robot, ground, r_m=a.rm, s=a.s,
                                      objective=a.objective, grid=grid, scheduler=a.scheduler,
                                      progress=not a.json, dask_timeout=timeout)
    if not curves.feasible.values.any():  # nothing to write or draw: a failure, not a result
        raise InfeasibleLandingError("no gains in [0, 1]^2 keep the stroke at any velocity "
                                     "(every landing leaves the stroke limits or never rests)")
    if out:
        with atomic(out) as tmp:
            save_dataset(curves, tmp)
    written = None
    if plot:
        from softlanding.plots.paper import plot_optimal_curves

        written = savefig(plot_optimal_curves(curves), plot)
    obs = paper_observations(curves, robot)
    if a.json:
        c = curves.sel(r_m=robot.r_m, s=robot.s)
        d: dict[str, Any] = {name: c[name].values.tolist() for name in (
            "v0", "k_p", "k_d", "depth", "u_peak", "cot", "on_stroke_boundary")}
        print_json({**d, "observations": obs, "out": a.out})
        return EXIT_OK
    _print_curves(curves, a.objective)
    print(f"paper's observations at r_m = {robot.r_m:g}, s = {robot.s:g}: {obs}")
    if a.out:
        print(f"dataset written to {a.out}")
    if written:
        print(f"figure written to {written}")
    return EXIT_OK


def _cmd_compare(a: argparse.Namespace) -> int:
    robot, v0, plot, ground = robot_of(a), _v0_grid(a), target(a), ground_of_args(a)
    check_count("grid", a.grid, 2, 2001)
    from softlanding.studies.comparison import compare_controllers

    rows = compare_controllers(v0, robot, ground, grid=a.grid, progress=not a.json)
    written = None
    if plot:
        from softlanding.plots.paper import plot_controller_comparison
        from softlanding.studies.comparison import comparison_arrays

        written = savefig(plot_controller_comparison(comparison_arrays(rows), robot, ground),
                          plot)
    if a.json:
        print_json({"rows": rows, "robot": robot.to_dict(), "ground": ground.to_dict()})
        return EXIT_OK
    print(f"Depth -x_f(T) at r_m = {robot.r_m:g}, s = {robot.s:g} "
          f"(bang-bang with u_max = {robot.u_max:g}), ground {ground.name}")
    print(f"{'v0':>7} {'rigid':>10} {'impedance':>11} {'(k_p*, k_d*)':>22} {'bang-bang':>11} "
          f"{'imp/rigid':>9} {'bb/rigid':>9}")
    for r in rows:
        gains = f"({r['impedance_k_p']:.4f}, {r['impedance_k_d']:.4f})"
        print(f"{r['v0']:>7.2f} {r['rigid']:>10.5f} {r['impedance']:>11.6f} {gains:>22} "
              f"{r['bang_bang']:>11.6f} {r['impedance'] / r['rigid']:>9.4f} "
              f"{r['bang_bang'] / r['rigid']:>9.4f}")
    if written:
        print(f"figure written to {written}")
    return EXIT_OK


# ----------------------------------------------------------------------- demo
def _cmd_demo(a: argparse.Namespace) -> int:
    from softlanding.util.files import atomic_folder, own_folder

    # the default output is the demo's own folder: a re-run replaces it (not a user's file)
    own = own_folder(DEMO_FOLDER, (DEMO_FIGURE,), "out") if a.out is None else None
    out = target(a, "out") if a.out else None
    # a hundred landings: on an empty cache compiling them costs more than running them
    python = a.own_process and interpret_unless_cached()
    from softlanding.report.demo import (
        DEMO_GAINS,
        DEMO_LANDINGS,
        STEPPED_KD,
        STEPPED_KP,
        STEPPED_V0,
        demo_table,
        plot_demo,
        stepped_intrusions,
    )
    from softlanding.util.progress import activity

    with activity("demo", total=DEMO_LANDINGS, unit="landing"):
        rows = demo_table()
        stepped = stepped_intrusions()
        written = savefig(plot_demo(stepped=stepped), out) if out else None
        if own is not None:
            with atomic_folder(own, force=True) as tmp:
                savefig(plot_demo(stepped=stepped), tmp / DEMO_FIGURE)
            written = str(own / DEMO_FIGURE)
    if a.json:
        print_json({"table": rows, "stepped_intrusions": [
            {"k_d": kd, "steps": s.steps, "depth": s.depth}
            for kd, s in zip(STEPPED_KD, stepped, strict=True)], "figure": written,
            "simulator": "python" if python else "compiled"})
        return EXIT_OK
    print(f"Landings at r_m = {PAPER_ROBOT.r_m:g}, s = {PAPER_ROBOT.s:g} (dimensionless units); "
          f"impedance k_p = {DEMO_GAINS.k_p:g}, k_d = {DEMO_GAINS.k_d:g}")
    print(f"{'v0':>6} {'rigid depth':>12} {'1+sqrt(1+v0^2)':>15} {'imp. depth':>11} "
          f"{'steps':>5} {'feasible':>8} {'peak |u|':>9} {'CoT':>7}")
    for r in rows:
        print(f"{r['v0']:>6.1f} {r['rigid_depth']:>12.6f} {r['rigid_depth_analytic']:>15.6f} "
              f"{r['impedance_depth']:>11.6f} {r['impedance_steps']:>5d} "
              f"{fmt(r['impedance_feasible']):>8} {r['impedance_u_peak']:>9.4f} "
              f"{r['impedance_cot']:>7.3f}")
    print(f"\nStepped intrusions (paper, Fig. 3a): v0 = {STEPPED_V0:g}, k_p = {STEPPED_KP:g}")
    for kd, s in zip(STEPPED_KD, stepped, strict=True):
        print(f"  k_d = {kd:<5g} -> {s.steps} step(s), depth {s.depth:.6f}")
    if written:
        print(f"\nfigure written to {written}")
    return EXIT_OK


# ------------------------------------------------------------------- reproduce
def _cmd_reproduce(a: argparse.Namespace) -> int:
    from softlanding.report.reproduction import reproduce
    from softlanding.util.files import output_folder

    out = output_folder(a.out, "out", a.force)
    if not a.json:
        print(f"Reproducing the paper into {out} ({'quick' if a.quick else 'full'} run)")
    s = reproduce(out, quick=a.quick, progress=not a.json, log=None if a.json else print,
                  force=a.force)
    if a.json:
        print_json(s)
        return EXIT_OK
    bb, cmp = s["bang_bang_example"], s["comparison"]
    print(f"\nbang-bang at v0 = {bb['v0']:g}: depth {bb['depth']:.9f}, "
          f"switch {bb['switch_times'][0]:.6f}, PMP: {bb['pmp_verdict']}")
    print(f"bang-bang / rigid depth {cmp['bang_bang_over_rigid'][0]:.4f} to "
          f"{cmp['bang_bang_over_rigid'][1]:.4f}; impedance / rigid "
          f"{cmp['impedance_over_rigid'][0]:.4f} to {cmp['impedance_over_rigid'][1]:.4f}")
    worst: dict[str, list[float]] = {}
    for r in s["robustness"]["table"]:
        if r["margin"] == 0:
            worst.setdefault(r["controller"], []).append(r["worst_depth_ratio"])
    print("robustness (+-30 %, no margin), worst depth / redesigned depth: " + ", ".join(
        f"{c} {max(v):.3f}" for c, v in worst.items()))
    print(f"{len(s['files'])} files written to {out} (see summary.md); "
          f"total {s['meta']['elapsed_s']:.1f} s")
    return EXIT_OK


# ------------------------------------------------------------------------ hop
def _hop_optimum(c: Any) -> str:
    if not c.converged:
        return "discretised"
    if c.exact_arcs:
        return "converged (exact arcs; a local optimum, not certified)"
    return "converged"


def _hop_rows(c: Any) -> list[tuple[str, object]]:
    rows: list[tuple[str, object]] = [
        ("energy per cycle", c.energy), ("energy / apex height", c.specific_energy),
        ("positive work", c.work.positive), ("negative work", c.work.negative),
        ("ground loss d^2/2", c.depth ** 2 / 2), ("crater depth", c.depth),
        ("paper's CoT of the landing", c.cot)]
    if not math.isnan(c.energy_transcribed):  # an impedance cycle has no optimiser's figure
        rows.append(("energy (refined NLP)" if c.exact_arcs else "energy (optimiser's slack)",
                     c.energy_transcribed))
    rows += [("apex posture error", c.apex_error), ("energy balance error", c.balance_error)]
    if len(c.grids) > 1:  # the grid sequence behind the continuous optimum's estimate
        rows += [("grids (energy each)", ", ".join(
                    f"{'/'.join(map(str, g['nodes']))}: {g['energy']:.7g}" for g in c.grids)),
                 ("grids' extrapolation" if c.exact_arcs else "continuous optimum (estimate)",
                  c.energy_estimate),
                 ("its error (estimate)", c.energy_error)]
    if c.exact_arcs:  # the second computation of the refined schedule's energy
        rows.append(("refined NLP vs replay", c.refined_gap))
    if c.starts:  # a non-convex problem: how far apart its local optima are
        rows += [("starts (energy each)", ", ".join(
                    f"{st['energy']:.6g}" if "energy" in st else st["error"] for st in c.starts))]
        if not math.isnan(c.local_optima_spread):  # NaN: fewer than two converged starts
            rows.append(("local optima spread", c.local_optima_spread))
    rows += [(k, v) for k, v in c.gains.items()]
    rows += [(f"time: {k}", v) for k, v in c.times.items()]
    return rows


def _cmd_hop(a: argparse.Namespace) -> int:
    robot, plot = robot_of(a), target(a)
    legs = ("free", "impedance", "rigid") if a.leg == "all" else (a.leg,)
    if a.grid is not None and "impedance" not in legs:
        raise ParameterError("--grid", f"is the impedance gain grid; --leg {a.leg} takes none")
    grid = check_count("--grid", 9 if a.grid is None else a.grid, 2, 41)
    if a.doublings is not None and "free" not in legs:
        raise ParameterError("--doublings", f"refines the free leg's grid; --leg {a.leg} has "
                                            "none")
    doublings = check_count("--doublings", 1 if a.doublings is None else a.doublings, 0, 4)
    from softlanding.optimal.limits import hop_input

    hop_input(robot, a.v0, a.eta)  # checked before the solver loads
    from softlanding.optimal.hopping import best_impedance_hop, rigid_hop, solve_hop
    from softlanding.util.progress import activity

    cycles: dict[str, Any] = {}
    for leg in legs:  # tens of seconds each: a bar on a terminal (the solves report steps)
        with activity(f"hop, {leg} leg"):
            if leg == "free":
                cycles[leg] = solve_hop(Impact(a.v0), robot, a.eta, doublings=doublings)
            elif leg == "rigid":
                cycles[leg] = rigid_hop(Impact(a.v0), robot, a.eta)
            else:
                cycles[leg] = best_impedance_hop(Impact(a.v0), robot, a.eta, grid=grid)
        if leg == "impedance" and cycles[leg] is None:
            raise InfeasibleLandingError(
                f"no impedance in the {grid} x {grid} gain grid (k_p in [0.05, 2], "
                f"k_d in [0, 2]) hops to the apex: no thrust within u_max = "
                f"{robot.u_max:g} restores it inside the stroke")
    # a verified cycle: its replay closes (apex, energy balance) and its energy is the
    # continuous optimum, not a grid's value
    reasons = {k: c.unverified_reasons() + [r for r in [c.unconverged_reason()] if r]
               for k, c in cycles.items()}
    bad = any(reasons.values())
    no_cert = {k: c.uncertified_reason() for k, c in cycles.items()} if a.pmp else {}
    written = None
    if plot:
        from softlanding.plots.phased import plot_hop

        written = savefig(plot_hop(cycles[legs[0]]), plot)
    if a.json:
        first = cycles[legs[0]]
        print_json({"verified": not bad, "unverified_reasons": reasons,
                     "converged": all(c.converged for c in cycles.values()),
                     "optimum": "converged" if first.converged else "discretised",
                     "energy": first.energy, "energy_estimate": first.energy_estimate,
                     "energy_error": first.energy_error, "cot": first.cot,
                     "depth": first.depth,
                     "leg": legs[0], "eta": a.eta, "v0": a.v0, "apex_height": first.apex_height,
                     "cycles": {k: c.to_dict() for k, c in cycles.items()},
                     **({"pmp": {k: {"verdict": None, "why_none": why}
                                 for k, why in no_cert.items()}} if a.pmp else {})})
    else:
        for leg, c in cycles.items():
            ok = "yes" if not reasons[leg] else "NO: " + "; ".join(reasons[leg])
            print(f"== {leg} leg, v0 = {a.v0:g} (apex {c.apex_height:.6g}), eta = {a.eta:g}")
            print_table([("verified", ok), ("optimum", _hop_optimum(c))] + _hop_rows(c))
            for n in c.notes:
                print(f"note: {n}")
            if a.pmp:
                print(f"PMP: {no_cert[leg]}")
        if written:
            print(f"figure written to {written}")
    return EXIT_OK if not bad or a.accept_unverified else EXIT_FAILURE



HANDLERS = {"simulate": _cmd_simulate, "solve": _cmd_solve, "solve-sweep": _cmd_solve_sweep,
            "impedance": _cmd_impedance, "map": _cmd_map, "sweep": _cmd_sweep,
            "compare": _cmd_compare, "scale": scale_command, "demo": _cmd_demo,
            "reproduce": _cmd_reproduce, "hop": _cmd_hop, "mpc": mpc_command,
            "robust": robust_command, "export-controller": export_command,
            "cache": cache_command}


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, file: Any = None, line: str | None = None) -> None:
    """A warning as the console script's one line (``softlanding: warning: ...``): the
    module path and source line Python adds are the package's, not the user's."""
    print(f"softlanding: warning: {category.__name__}: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None, *, own_process: bool = False) -> int:
    """Entry point of the ``softlanding`` console script.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments (default: ``sys.argv[1:]``).
    own_process : bool
        The process is the command's and ends with it (the console script): the demo may then
        run the simulator as Python on an empty cache, which lasts for the process.

    Returns
    -------
    int
        The exit code.
    """
    from softlanding.cli.parser import build_parser

    parser = build_parser(HANDLERS, CliParser, sys.argv[1:] if argv is None else argv)
    args, extras = parser.parse_known_args(argv)
    args.own_process = own_process
    if extras:  # another variant's option: refused as one the chosen variant ignores
        from softlanding.cli.variants import refusal_of_unknown

        refused = refusal_of_unknown(args, extras)
        if refused is not None:
            return report_error(refused)
        parser.error(f"unrecognized arguments: {' '.join(extras)}")
    from softlanding.util import progress as _progress

    _progress.FORCE = bool(args.progress)
    _quiet_matplotlib_caches()
    files = getattr(args, "plot", None) or getattr(args, "out", None) or args.command == "demo"
    previous, warnings.showwarning = warnings.showwarning, _one_line_warning
    try:
        with _files_backend(bool(files)):
            return _run(args)
    finally:  # (main is also called in-process: the caller's hook comes back)
        warnings.showwarning = previous


def console_main() -> int:
    """The ``softlanding`` console script and ``python -m softlanding``: :func:`main`, made
    safe against a second signal while the process winds down (and an interruption during
    start-up, before :func:`main` runs the command, reported as one line).

    A signal that arrives after the interruption was reported (a repeated Ctrl-C, or one
    that a solver library re-raises on its way out) would end the process with the signal's
    own status instead of 130 or 143; once :func:`main` has reported, both are ignored.

    Returns
    -------
    int
        The exit code.
    """
    import signal

    from softlanding.util.signals import (
        EXIT_INTERRUPTED,
        TERMINATING,
        report_interrupt,
        reported_interrupt,
    )

    try:
        code = main(own_process=True)
    except KeyboardInterrupt as exc:  # before the run (start-up), or a second one after it
        code = reported_interrupt() or report_interrupt(exc)
    if code >= EXIT_INTERRUPTED and threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, *TERMINATING):
            signal.signal(signum, signal.SIG_IGN)
    return code


_MPL_CACHE_NOTES = ("is not a writable directory", "created a temporary cache directory",
                    "Could not save font_manager cache", "building the font cache")


def _not_a_cache_note(record: logging.LogRecord) -> bool:
    return not any(note in str(record.msg) for note in _MPL_CACHE_NOTES)


def _quiet_matplotlib_caches() -> None:
    """matplotlib's notes on its own caches (a full or read-only home: "Could not save
    font_manager cache", a temporary config folder) are not the run's business: a run's
    errors are one line. Set before matplotlib's import (its loggers exist already)."""
    for name in ("matplotlib", "matplotlib.font_manager"):
        logger = logging.getLogger(name)
        if _not_a_cache_note not in logger.filters:
            logger.addFilter(_not_a_cache_note)


@contextlib.contextmanager
def _files_backend(files: bool) -> Iterator[None]:
    """Figures to files only: no window, also without a display. Set for matplotlib's first
    import (importing it here would cost 0.2 s even when the arguments turn out bad), and
    undone after, so that a caller's later figures (a notebook's kernel) stay inline."""
    if not files:
        yield
        return
    if "matplotlib" in sys.modules:
        import matplotlib

        matplotlib.use("Agg")
        yield
        return
    old = os.environ.get("MPLBACKEND")
    os.environ["MPLBACKEND"] = "Agg"
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("MPLBACKEND", None)
        else:
            os.environ["MPLBACKEND"] = old


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command: its exit code, every error one line."""
    from softlanding.util.files import output_run
    from softlanding.util.signals import handle_signals, report_interrupt

    try:  # SIGTERM cleans up like Ctrl-C; a failed run leaves none of its outputs
        if getattr(args, "force", False) and not any(
                getattr(args, k, None) for k in ("plot", "out")):
            raise ParameterError("force", "overwrites an output file: give --plot or --out "
                                          "too (nothing is written without)")
        with handle_signals(), output_run(force=bool(getattr(args, "force", False))):
            return int(args.func(args))
    except BrokenPipeError:
        # output piped into e.g. `head`, which closed early: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except KeyboardInterrupt as exc:
        return report_interrupt(exc)
    except Exception as exc:
        if args.debug:
            raise
        return report_error(exc, args)


if __name__ == "__main__":
    raise SystemExit(main())
