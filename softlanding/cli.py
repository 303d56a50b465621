"""The ``softlanding`` command.

Every sub-command prints a readable table by default and one JSON object with
``--json``. Bad input ends with a one-line message on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence

from ._jsonutil import json_safe as _json_safe
from .errors import ParameterError

EXIT_BAD_INPUT = 2
EXIT_FAILURE = 1


class _Parser(argparse.ArgumentParser):
    """argparse, but usage errors are one line and exit with code 2."""

    def error(self, message: str) -> None:  # noqa: D102
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def _fmt(x) -> str:
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return f"{x:.10g}" if math.isfinite(x) else str(x)
    return str(x)


def _print_table(rows: Sequence[tuple[str, object]]) -> None:
    w = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{w}}  {_fmt(v)}")


# ------------------------------------------------------------------- simulate
def _cmd_simulate(a: argparse.Namespace) -> int:
    from .scaling import DimensionlessParams
    from .simulate import Impedance, Rigid, simulate

    p = DimensionlessParams(r_m=a.rm, s=a.s, v0=a.v0, u_max=a.umax)
    if a.rigid:
        if a.kp is not None or a.kd is not None:
            raise ParameterError("rigid", "--rigid takes no --kp/--kd")
        policy = Rigid()
    else:
        if a.kp is None or a.kd is None:
            raise ParameterError("kp", "give both --kp and --kd, or --rigid")
        policy = Impedance(a.kp, a.kd, a.umax)
    res = simulate(p, policy)
    if a.plot:
        from .figures import plot_trajectory

        plot_trajectory(res).savefig(a.plot, dpi=130)
    if a.json:
        print(json.dumps(res.to_dict()))
    else:
        e = res.energy
        _print_table([
            ("policy", policy.describe()), ("v0", p.v0), ("r_m", p.r_m), ("s", p.s),
            ("depth -x_f(T)", res.depth), ("intrusion steps", res.steps),
            ("feasible (0<=stroke<=s)", res.feasible), ("status", res.status),
            ("first foot stop tau", res.t_first_stop), ("final rest tau T", res.T),
            ("peak |u|", res.u_peak), ("stroke min", res.stroke_min),
            ("stroke max", res.stroke_max), ("E(0)", e.E0), ("E(T)", e.ET),
            ("ground loss", e.ground), ("actuator loss", e.actuator), ("CoT", e.cot),
        ])
        if a.plot:
            print(f"figure written to {a.plot}")
    return 0 if res.rest_proven else EXIT_FAILURE


# ---------------------------------------------------------------------- solve
def _cmd_solve(a: argparse.Namespace) -> int:
    from .landing import solve_landing

    res = solve_landing(a.v0, a.rm, a.s, a.umax, nodes=a.nodes, refine=not a.no_refine,
                        extra_arcs=a.extra_arcs)
    cert = None
    if a.pmp:
        from ocp import certify

        cert = certify(res.transcribed, res.refined)
    if a.plot:
        from .figures import plot_bang_bang

        plot_bang_bang(res).savefig(a.plot, dpi=130)
        if cert is not None:
            from ocp.pmp import plot_certificate

            stem, dot, ext = a.plot.rpartition(".")
            pmp_plot = f"{stem}-pmp.{ext}" if dot else f"{a.plot}-pmp.png"
            plot_certificate(cert).savefig(pmp_plot, dpi=130)
    ok = res.replay is None or res.replay_difference <= 1e-6 or a.no_refine
    if a.json:
        d = res.to_dict()
        if cert is not None:
            d["pmp"] = cert.to_dict()
        print(json.dumps(_json_safe(d)))
    else:
        rows = [("depth -x_f(T)" + ("" if a.no_refine else " (refined)"), res.depth),
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
        if cert is not None:
            rows += [("PMP verdict", cert.verdict), ("PMP costate source", cert.source),
                     ("max |H - H_expected| / H_scale", cert.H_max_abs),
                     ("H variation / H_scale", cert.H_variation),
                     ("sigma sign agreement", cert.sigma_sign_agreement),
                     ("switch to sigma-zero gap", cert.switch_sigma_gap),
                     ("costate estimates gap", cert.costate_estimates_gap),
                     ("singular intervals", cert.singular_intervals or "none"),
                     ("state-constrained intervals",
                      cert.state_constraint_active_intervals or "none")]
        _print_table(rows)
        for n in res.notes:
            print(f"note: {n}")
        if cert is not None:
            for r_ in cert.reasons:
                print(f"PMP: {r_}")
        if a.plot:
            print(f"figure written to {a.plot}" + (f" and {pmp_plot}" if cert else ""))
    return 0 if ok else EXIT_FAILURE


def _cmd_solve_sweep(a: argparse.Namespace) -> int:
    import numpy as np

    from .landing import sweep_landing

    v = np.linspace(a.v0_max, a.v0_min, a.n)  # from the easy end: continuation
    res = sweep_landing(v, a.rm, a.s, a.umax, nodes=a.nodes, progress=not a.json)
    rigid = [1 + math.sqrt(1 + x * x) for x in v]
    rows = [{"v0": r.params.v0, "depth": r.depth, "depth_transcribed": r.depth_transcribed,
             "rigid_depth": rd, "ratio_to_rigid": r.depth / rd, "T": r.T,
             "switch_times": r.switch_times, "arcs": r.arcs, "iterations": r.iterations}
            for r, rd in zip(res, rigid, strict=True)]
    if a.plot:
        from .figures import plot_depth_vs_velocity

        plot_depth_vs_velocity(v, {"rigid leg": np.array(rigid),
                                   "bang-bang (refined)": np.array([r.depth for r in res])}
                               ).savefig(a.plot, dpi=130)
    if a.json:
        print(json.dumps(_json_safe({"sweep": rows})))
        return 0
    print(f"{'v0':>7} {'depth':>14} {'rigid':>10} {'ratio':>7} {'T':>8}  switch  iters")
    for r in rows:
        sw = ",".join(f"{t:.5f}" for t in r["switch_times"])
        print(f"{r['v0']:>7.3f} {r['depth']:>14.10f} {r['rigid_depth']:>10.6f} "
              f"{r['ratio_to_rigid']:>7.4f} {r['T']:>8.5f}  {sw}  {r['iterations']}")
    if a.plot:
        print(f"figure written to {a.plot}")
    return 0


# ------------------------------------------------------------------ impedance
def _cmd_impedance(a: argparse.Namespace) -> int:
    from .impedance import optimize_impedance

    o = optimize_impedance(a.v0, a.rm, a.s, objective=a.objective, grid=a.grid, u_max=a.umax)
    if a.json:
        print(json.dumps(_json_safe(o.to_dict())))
        return 0
    _print_table([
        ("objective", o.objective), ("v0", o.v0), ("optimal k_p", o.kp), ("optimal k_d", o.kd),
        (f"{o.objective} at the optimum", o.value), ("depth", o.depth),
        ("intrusion steps", o.steps), ("peak |u|", o.u_peak), ("stroke min", o.stroke_min),
        ("stroke max", o.stroke_max), ("CoT (dissipative)", o.cot),
        ("CoT (lossless)", o.cot_lossless), ("on stroke boundary", o.on_stroke_boundary),
        ("active constraint", o.active_constraint or "none"),
        ("best grid point", f"k_p={o.grid_best['kp']:g}, k_d={o.grid_best['kd']:g}, "
                            f"{o.objective}={o.grid_best['value']:.10g}"),
        ("landings simulated", o.evaluations)])
    return 0


def _cmd_map(a: argparse.Namespace) -> int:
    from .impedance import optimize_impedance
    from .sweeps import depth_map, save_dataset

    ds = depth_map(a.v0, a.rm, a.s, n=a.n, scheduler=a.scheduler)
    save_dataset(ds, a.out)
    opt = optimize_impedance(a.v0, a.rm, a.s, grid=a.n)
    if a.plot:
        from .figures import plot_depth_map

        plot_depth_map(ds, opt).savefig(a.plot, dpi=130)
    summary = {"out": a.out, "plot": a.plot, "landings": int(ds.depth.size),
               "feasible_fraction": float(ds.strictly_feasible.mean()),
               "optimum": opt.to_dict()}
    if a.json:
        print(json.dumps(_json_safe(summary)))
    else:
        print(f"{summary['landings']} landings, {summary['feasible_fraction']:.1%} feasible; "
              f"dataset written to {a.out}")
        print(f"optimum: k_p = {opt.kp:.8f}, k_d = {opt.kd:.8f}, depth {opt.depth:.10f} "
              f"({opt.steps} step(s), on stroke boundary: {_fmt(opt.on_stroke_boundary)})")
        if a.plot:
            print(f"figure written to {a.plot}")
    return 0


def _cmd_sweep(a: argparse.Namespace) -> int:
    import numpy as np

    from .sweeps import optimal_impedance_curves, paper_observations, save_dataset

    v0 = np.linspace(a.v0_max, a.v0_min, a.n)
    if a.objective != "depth":
        v0 = v0[v0 < 0]
    curves = optimal_impedance_curves(v0, a.rm or [5.0], a.s or [20.0], objective=a.objective,
                                      grid=a.grid, scheduler=a.scheduler,
                                      progress=not a.json)
    if a.out:
        save_dataset(curves, a.out)
    if a.plot:
        from .figures import plot_optimal_curves

        plot_optimal_curves(curves).savefig(a.plot, dpi=130)
    r0, s0 = float(curves.r_m[0]), float(curves.s[0])
    obs = paper_observations(curves, r0, s0)
    if a.json:
        c = curves.sel(r_m=r0, s=s0)
        print(json.dumps(_json_safe({
            "v0": c.v0.values.tolist(), "kp": c.kp.values.tolist(),
            "kd": c.kd.values.tolist(), "depth": c.depth.values.tolist(),
            "u_peak": c.u_peak.values.tolist(), "cot": c.cot.values.tolist(),
            "on_stroke_boundary": c.on_stroke_boundary.values.tolist(),
            "observations": obs, "out": a.out})))
        return 0
    for r in curves.r_m.values:
        for s in curves.s.values:
            c = curves.sel(r_m=r, s=s)
            print(f"r_m = {r:g}, s = {s:g}, objective {a.objective}")
            print(f"{'v0':>7} {'k_p*':>11} {'k_d*':>11} {'depth':>11} {'steps':>5} "
                  f"{'peak|u|':>8} {'CoT':>8} boundary")
            for i in range(c.v0.size):
                if not bool(c.feasible[i]):
                    print(f"{float(c.v0[i]):>7.2f}   no gains in [0, 1]^2 keep the stroke")
                    continue
                print(f"{float(c.v0[i]):>7.2f} {float(c.kp[i]):>11.7f} {float(c.kd[i]):>11.7f} "
                      f"{float(c.depth[i]):>11.7f} {int(c.steps[i]):>5d} "
                      f"{float(c.u_peak[i]):>8.4f} {float(c.cot[i]):>8.4f} "
                      f"{_fmt(bool(c.on_stroke_boundary[i]))}")
    print(f"paper's observations at r_m = {r0:g}, s = {s0:g}: {obs}")
    if a.out:
        print(f"dataset written to {a.out}")
    if a.plot:
        print(f"figure written to {a.plot}")
    return 0


def _cmd_compare(a: argparse.Namespace) -> int:
    import numpy as np

    from .comparison import compare_controllers

    v = np.linspace(a.v0_max, a.v0_min, a.n)
    rows = compare_controllers(v, a.rm, a.s, a.umax, grid=a.grid, progress=not a.json)
    if a.plot:
        from .comparison import comparison_arrays
        from .figures import plot_controller_comparison

        plot_controller_comparison(comparison_arrays(rows), a.umax, a.rm, a.s).savefig(
            a.plot, dpi=130)
    if a.json:
        print(json.dumps(_json_safe({"rows": rows, "r_m": a.rm, "s": a.s, "u_max": a.umax})))
        return 0
    print(f"Depth -x_f(T) at r_m = {a.rm:g}, s = {a.s:g} (bang-bang with u_max = {a.umax:g})")
    print(f"{'v0':>7} {'rigid':>10} {'impedance':>11} {'(k_p*, k_d*)':>22} {'bang-bang':>11} "
          f"{'imp/rigid':>9} {'bb/rigid':>9}")
    for r in rows:
        gains = f"({r['impedance_kp']:.4f}, {r['impedance_kd']:.4f})"
        print(f"{r['v0']:>7.2f} {r['rigid']:>10.5f} {r['impedance']:>11.6f} {gains:>22} "
              f"{r['bang_bang']:>11.6f} {r['impedance'] / r['rigid']:>9.4f} "
              f"{r['bang_bang'] / r['rigid']:>9.4f}")
    if a.plot:
        print(f"figure written to {a.plot}")
    return 0


# ---------------------------------------------------------------------- scale
def _cmd_scale(a: argparse.Namespace) -> int:
    from .scaling import DimensionlessParams, PhysicalParams, paper_rig

    if a.to_si:
        d = DimensionlessParams(r_m=a.rm, s=a.s, v0=a.v0, u_max=a.umax, k_p=a.kp, k_d=a.kd)
        ph = d.to_physical(a.mt, a.kg, a.g)
    else:
        if a.preset == "paper":
            ph = paper_rig(v0=a.v0_si if a.v0_si is not None else -1.2,
                           **({"K_p": a.Kp} if a.Kp is not None else {}),
                           **({"K_d": a.Kd} if a.Kd is not None else {}))
        else:
            missing = [n for n in ("mb", "mf", "kg", "stroke") if getattr(a, n) is None]
            if missing:
                raise ParameterError(missing[0], "is required (or use --preset paper)")
            ph = PhysicalParams(m_b=a.mb, m_f=a.mf, k_g=a.kg, stroke=a.stroke,
                                v0=0.0 if a.v0_si is None else a.v0_si, u_max=a.umax_si,
                                K_p=a.Kp, K_d=a.Kd, g=a.g)
        d = ph.to_dimensionless()
    scales = {"x_s_m": ph.length_scale, "tau_s_s": ph.time_scale, "u_s_N": ph.force_scale,
              "v_s_m_per_s": ph.velocity_scale, "E_s_J": ph.energy_scale}
    out = {"physical": ph.as_dict(), "dimensionless": d.as_dict(), "scales": scales}
    if a.json:
        print(json.dumps(out))
    else:
        rows = [(f"SI {k}", v) for k, v in ph.as_dict().items() if v is not None]
        rows += [(f"scale {k}", v) for k, v in scales.items()]
        rows += [(f"dimensionless {k}", v) for k, v in d.as_dict().items() if v is not None]
        _print_table(rows)
    return 0


# ----------------------------------------------------------------------- demo
DEMO_V0 = (0.0, -1.0, -3.0, -5.0, -10.0)
DEMO_GAINS = (0.5, 0.5)


def _cmd_demo(a: argparse.Namespace) -> int:
    import numpy as np

    from .scaling import DimensionlessParams
    from .simulate import Impedance, Rigid, simulate

    kp, kd = DEMO_GAINS
    rows = []
    for v0 in DEMO_V0:
        p = DimensionlessParams(r_m=5, s=20, v0=v0)
        rig = simulate(p, Rigid())
        imp = simulate(p, Impedance(kp, kd))
        rows.append({"v0": v0, "rigid_depth": rig.depth,
                     "rigid_depth_analytic": 1 + math.sqrt(1 + v0 * v0),
                     "impedance_depth": imp.depth, "impedance_steps": imp.steps,
                     "impedance_feasible": imp.feasible, "impedance_u_peak": imp.u_peak,
                     "impedance_cot": imp.energy.cot})
    stepped = [simulate(DimensionlessParams(r_m=5, s=20, v0=-1.0), Impedance(0.2, k))
               for k in (0.4, 0.18, 0.0)]
    if a.out:
        import matplotlib.pyplot as plt

        from .figures import plot_depth_vs_velocity, plot_stepped_intrusions

        v = np.linspace(-10, 0, 41)
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2))
        plot_depth_vs_velocity(v, {
            "rigid leg": np.array([simulate(DimensionlessParams(v0=x), Rigid()).depth
                                   for x in v]),
            f"impedance $k_p$={kp}, $k_d$={kd}": np.array(
                [simulate(DimensionlessParams(v0=x), Impedance(kp, kd)).depth for x in v]),
        }, ax=ax1)
        ax1.set_title("depth against impact velocity ($r_m$=5, $s$=20)", fontsize=9)
        plot_stepped_intrusions(stepped, ax=ax2)
        ax2.set_title("stepped intrusions, $v_0$=-1, $k_p$=0.2", fontsize=9)
        fig.tight_layout()
        fig.savefig(a.out, dpi=110)
        plt.close(fig)
    if a.json:
        print(json.dumps({"table": rows, "stepped_intrusions": [
            {"k_d": r.policy.k_d, "steps": r.steps, "depth": r.depth} for r in stepped],
            "figure": a.out}))
        return 0
    print(f"Landings at r_m = 5, s = 20 (dimensionless units); impedance k_p = {kp}, k_d = {kd}")
    print(f"{'v0':>6} {'rigid depth':>12} {'1+sqrt(1+v0^2)':>15} {'imp. depth':>11} "
          f"{'steps':>5} {'feasible':>8} {'peak |u|':>9} {'CoT':>7}")
    for r in rows:
        print(f"{r['v0']:>6.1f} {r['rigid_depth']:>12.6f} {r['rigid_depth_analytic']:>15.6f} "
              f"{r['impedance_depth']:>11.6f} {r['impedance_steps']:>5d} "
              f"{_fmt(r['impedance_feasible']):>8} {r['impedance_u_peak']:>9.4f} "
              f"{r['impedance_cot']:>7.3f}")
    print("\nStepped intrusions (paper, Fig. 3a): v0 = -1, k_p = 0.2")
    for r in stepped:
        print(f"  k_d = {r.policy.k_d:<5g} -> {r.steps} step(s), depth {r.depth:.6f}")
    if a.out:
        print(f"\nfigure written to {a.out}")
    return 0


# ------------------------------------------------------------------- reproduce
def _cmd_reproduce(a: argparse.Namespace) -> int:
    from pathlib import Path

    from .reproduce import reproduce

    out = Path(a.out)
    if out.exists() and not out.is_dir():
        raise ParameterError("out", f"{out} exists and is not a folder")
    log = None if a.json else print
    if not a.json:
        print(f"Reproducing the paper into {out} ({'quick' if a.quick else 'full'} run)")
    s = reproduce(out, quick=a.quick, progress=not a.json, log=log)
    if a.json:
        print(json.dumps(_json_safe(s)))
        return 0
    bb, cmp = s["bang_bang_example"], s["comparison"]
    print(f"\nbang-bang at v0 = -3: depth {bb['depth']:.9f}, switch {bb['switch_times'][0]:.6f}, "
          f"PMP: {bb['pmp_verdict']}")
    print(f"bang-bang / rigid depth {cmp['bang_bang_over_rigid'][0]:.4f} to "
          f"{cmp['bang_bang_over_rigid'][1]:.4f}; impedance / rigid "
          f"{cmp['impedance_over_rigid'][0]:.4f} to {cmp['impedance_over_rigid'][1]:.4f}")
    worst = {}
    for r in s["robustness"]["table"]:
        if r["margin"] == 0:
            worst.setdefault(r["controller"], []).append(r["worst_depth_ratio"])
    print("robustness (+-30 %, no margin), worst depth / redesigned depth: " + ", ".join(
        f"{c} {max(v):.3f}" for c, v in worst.items()))
    print(f"{len(s['files'])} files written to {out} (see summary.md); "
          f"total {s['meta']['elapsed_s']:.1f} s")
    return 0


# ---------------------------------------------------------------------- parser
def _model_args(p: argparse.ArgumentParser, umax: float | None, umax_help: str) -> None:
    """The model parameters shared by the sub-commands, and --json."""
    p.add_argument("--rm", type=float, default=5.0, help="mass ratio m_b / m_f (default 5)")
    p.add_argument("--s", type=float, default=20.0, help="stroke S / x_s (default 20)")
    p.add_argument("--umax", type=float, default=umax, help=umax_help)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _v0_range_args(p: argparse.ArgumentParser, n: int) -> None:
    """--v0-min, --v0-max, --n: the impact velocities a sweep visits."""
    p.add_argument("--v0-min", type=float, default=-10.0, help="default -10")
    p.add_argument("--v0-max", type=float, default=0.0, help="default 0")
    p.add_argument("--n", type=int, default=n, help=f"number of velocities (default {n})")


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(
        prog="softlanding",
        description=(
            "Soft landing of a two-mass legged robot on yielding ground (one-way plastic "
            "spring), after Lynch, Lynch & Umbanhowar. All quantities are dimensionless "
            "unless named otherwise: lengths in x_s = m_t g / k_g, time in sqrt(m_t / k_g), "
            "force in m_t g. Exit codes: 0 ok, 1 run failed (e.g. rest not proven), "
            "2 bad input."),
    )
    sub = ap.add_subparsers(dest="command", required=True, parser_class=_Parser)

    s = sub.add_parser("simulate", help="simulate one landing exactly (event-driven)",
                       description="Simulate one landing with a rigid or impedance-controlled "
                                   "leg. Exact: matrix exponentials and root-found events.")
    s.add_argument("--v0", type=float, required=True,
                   help="impact velocity (<= 0, negative = downward)")
    g = s.add_mutually_exclusive_group()
    g.add_argument("--rigid", action="store_true", help="body and foot locked together")
    s.add_argument("--kp", type=float, help="impedance stiffness k_p = K_p / k_g (>= 0)")
    s.add_argument("--kd", type=float, help="impedance damping k_d = K_d / sqrt(m_t k_g) (>= 0)")
    _model_args(s, None, "saturate the impedance force at +-umax (default: no limit)")
    s.add_argument("--plot", metavar="FILE.png", help="write the trajectory figure")
    s.set_defaults(func=_cmd_simulate)

    c = sub.add_parser("scale", help="convert a physical robot to dimensionless numbers and back",
                       description="SI -> dimensionless (default) or dimensionless -> SI "
                                   "(--to-si). Velocities are negative when moving down.")
    c.add_argument("--preset", choices=["paper"], help="the paper's rig (m_b 2.5, m_f 0.5 kg, "
                                                        "k_g 4.4 kN/m)")
    c.add_argument("--mb", type=float, help="body mass [kg]")
    c.add_argument("--mf", type=float, help="foot mass [kg]")
    c.add_argument("--kg", type=float, help="ground stiffness [N/m]")
    c.add_argument("--stroke", type=float, help="actuator stroke S [m]")
    c.add_argument("--umax-si", type=float, help="actuator force limit [N]")
    c.add_argument("--v0-si", type=float, help="impact velocity [m/s] (<= 0)")
    c.add_argument("--Kp", type=float, help="leg stiffness [N/m]")
    c.add_argument("--Kd", type=float, help="leg damping [N s/m]")
    c.add_argument("--g", type=float, default=9.81, help="gravity [m/s^2] (default 9.81)")
    c.add_argument("--to-si", action="store_true", help="convert dimensionless -> SI")
    c.add_argument("--mt", type=float, default=3.0, help="total mass for --to-si [kg]")
    c.add_argument("--rm", type=float, default=5.0, help="mass ratio for --to-si")
    c.add_argument("--s", type=float, default=20.0, help="stroke for --to-si")
    c.add_argument("--v0", type=float, default=-1.0, help="impact velocity for --to-si")
    c.add_argument("--umax", type=float, help="force limit for --to-si")
    c.add_argument("--kp", type=float, help="stiffness for --to-si")
    c.add_argument("--kd", type=float, help="damping for --to-si")
    c.add_argument("--json", action="store_true", help="print one JSON object")
    c.set_defaults(func=_cmd_scale)

    o = sub.add_parser("solve", help="minimum-depth landing by optimal control (bang-bang)",
                       description="Solve the paper's soft-landing OCP (min -x_f(T), free T, "
                                   "|u| <= umax, 0 <= stroke <= s, v_f <= 0, v_f(T) = 0, "
                                   "body-arrest condition) by multiple shooting and Ipopt, "
                                   "then refine the switching times with exact arcs and "
                                   "replay the schedule in the exact simulator.")
    o.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    _model_args(o, 8.2, "force limit (default 8.2)")
    o.add_argument("--nodes", type=int, default=100, help="shooting intervals (default 100)")
    o.add_argument("--no-refine", action="store_true",
                   help="report the transcribed solution only")
    o.add_argument("--extra-arcs", type=int, default=0,
                   help="also try this many more bang arcs (default 0)")
    o.add_argument("--pmp", action="store_true",
                   help="check Pontryagin's conditions (costates, H, switching function) "
                        "and give a bang-bang verdict")
    o.add_argument("--plot", metavar="FILE.png",
                   help="write the bang-bang trajectory figure (and FILE-pmp.png with --pmp)")
    o.set_defaults(func=_cmd_solve)

    w = sub.add_parser("solve-sweep", help="bang-bang depth against impact velocity",
                       description="Solve the OCP over v0 from --v0-max down to --v0-min "
                                   "with continuation (each solve warm-starts the next).")
    _v0_range_args(w, 21)
    _model_args(w, 8.2, "force limit (default 8.2)")
    w.add_argument("--nodes", type=int, default=100)
    w.add_argument("--plot", metavar="FILE.png", help="write depth against v0")
    w.set_defaults(func=_cmd_solve_sweep)

    i = sub.add_parser("impedance", help="optimal impedance gains for one impact velocity",
                       description="Minimise depth (or CoT) over the gains (k_p, k_d) in "
                                   "[0, 1]^2, excluding landings that leave the stroke: the "
                                   "paper's grid, then a zooming feasible-grid refinement "
                                   "(to 1e-8) and a bisection onto the stroke limit.")
    i.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    _model_args(i, None, "force saturation (default none)")
    i.add_argument("--objective", choices=["depth", "cot", "cot-lossless"], default="depth",
                   help="depth; CoT with actuator and ground losses; or ground losses only")
    i.add_argument("--grid", type=int, default=101, help="starting grid per axis (default 101)")
    i.set_defaults(func=_cmd_impedance)

    m = sub.add_parser("map", help="the (k_p, k_d) depth map at one impact velocity",
                       description="Simulate the (k_p, k_d) grid, save every figure of every "
                                   "landing as a labelled netCDF dataset, and plot depth "
                                   "normalised by its minimum (infeasible blank, optimum "
                                   "starred).")
    m.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    m.add_argument("--n", type=int, default=101, help="points per axis (default 101)")
    m.add_argument("--rm", type=float, default=5.0)
    m.add_argument("--s", type=float, default=20.0)
    m.add_argument("--out", required=True, metavar="FILE.nc", help="netCDF dataset to write")
    m.add_argument("--plot", metavar="FILE.png", help="write the map figure")
    m.add_argument("--scheduler", metavar="tcp://host:port",
                   help="run on a Dask cluster instead of the local cores")
    m.add_argument("--json", action="store_true", help="print one JSON object")
    m.set_defaults(func=_cmd_map)

    w2 = sub.add_parser("sweep", help="optimal gains against impact velocity (and r_m, s)",
                        description="Optimal impedance at each v0 from --v0-max to --v0-min, "
                                    "for every --rm and --s given (repeat the flags for "
                                    "families), with the paper's observations checked.")
    _v0_range_args(w2, 21)
    w2.add_argument("--rm", type=float, action="append", help="mass ratio (repeatable)")
    w2.add_argument("--s", type=float, action="append", help="stroke (repeatable)")
    w2.add_argument("--objective", choices=["depth", "cot", "cot-lossless"], default="depth")
    w2.add_argument("--grid", type=int, default=101, help="starting grid per axis")
    w2.add_argument("--out", metavar="FILE.nc", help="netCDF dataset to write")
    w2.add_argument("--plot", metavar="FILE.png", help="write the curves figure")
    w2.add_argument("--scheduler", metavar="tcp://host:port", help="Dask scheduler address")
    w2.add_argument("--json", action="store_true", help="print one JSON object")
    w2.set_defaults(func=_cmd_sweep)

    cp = sub.add_parser("compare", help="rigid vs optimal impedance vs bang-bang, against v0",
                        description="The paper's comparison: penetration depth against impact "
                                    "velocity for a rigid leg (analytic), the depth-optimal "
                                    "impedance, and optimal bang-bang force control.")
    _v0_range_args(cp, 11)
    _model_args(cp, 8.2, "force limit of the bang-bang controller (default 8.2)")
    cp.add_argument("--grid", type=int, default=101, help="impedance starting grid per axis")
    cp.add_argument("--plot", metavar="FILE.png", help="write depth against v0")
    cp.set_defaults(func=_cmd_compare)

    d = sub.add_parser("demo", help="rigid vs impedance landings at several impact velocities",
                       description="Simulate rigid and impedance landings at v0 = 0, -1, -3, "
                                   "-5, -10, print a table (with the analytic rigid depth "
                                   "as a check) and write a figure.")
    d.add_argument("--out", default="softlanding-demo.png", metavar="FILE.png",
                   help="figure path (default softlanding-demo.png; '' for none)")
    d.add_argument("--json", action="store_true", help="print one JSON object")
    d.set_defaults(func=_cmd_demo)

    r = sub.add_parser("reproduce", help="every figure of the paper, summary tables, robustness",
                       description="Regenerate every figure of the paper (PNG and PDF), "
                                   "summary.md and summary.json with the headline numbers, "
                                   "and a robustness study of the nominal bang-bang and "
                                   "impedance controllers under +-30 % model error. The full "
                                   "run takes several minutes on 2 cores; --quick (coarser "
                                   "grids, fewer velocities) about one.")
    r.add_argument("--out", required=True, metavar="DIR", help="folder to write (created)")
    r.add_argument("--quick", action="store_true", help="coarser grids, about a minute")
    r.add_argument("--json", action="store_true", help="print summary.json's contents")
    r.set_defaults(func=_cmd_reproduce)
    return ap


def _infeasible_error():
    from .landing import InfeasibleLandingError

    return InfeasibleLandingError


def _solve_error():
    from ocp import SolveError

    return SolveError


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``softlanding`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except BrokenPipeError:
        # output piped into e.g. `head`, which closed early: not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except ParameterError as exc:
        print(f"softlanding: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except _infeasible_error() as exc:
        print(f"softlanding: infeasible: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except _solve_error() as exc:
        print(f"softlanding: solver failed: {exc} (Ipopt status {exc.status})", file=sys.stderr)
        return EXIT_FAILURE
    except (OSError, ValueError) as exc:
        print(f"softlanding: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    raise SystemExit(main())
