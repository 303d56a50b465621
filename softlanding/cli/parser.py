"""The argument parser of the ``softlanding`` command (one small builder per sub-command)."""

from __future__ import annotations

import argparse
import contextlib
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from softlanding.cli.ground import ground_args, numbers
from softlanding.cli.variants import add_variant_options, variants_parser
from softlanding.errors import LIMITS, ParameterError, plain
from softlanding.model.robot import PAPER_ROBOT

Handlers = Mapping[str, Callable[[argparse.Namespace], int]]

DESCRIPTION = (
    "Soft landing of a two-mass legged robot on yielding ground (one-way plastic spring), "
    "after Lynch, Lynch & Umbanhowar. All quantities are dimensionless unless named "
    "otherwise: lengths in x_s = m_t g / k_g, time in sqrt(m_t / k_g), force in m_t g. "
    "Exit codes: 0 ok, 1 a run that failed (rest not proven, solver failure), 2 bad input, "
    "3 internal error (a bug; --debug shows the traceback), 130 interrupted "
    "(143 SIGTERM, 129 SIGHUP).")


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("softlanding")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        from softlanding._version import __version__

        return __version__


def scheduler_address(text: str) -> str:
    """``--scheduler``: a Dask scheduler address, ``[tcp://]host:port`` (an argparse type).

    Parameters
    ----------
    text : str
        What the user typed.

    Raises
    ------
    argparse.ArgumentTypeError
        Not of that form (a one-line usage error, exit 2, before any work).
    """
    m = re.fullmatch(r"(?:(?:tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[^\s/:\[\]]+):(\d+)",
                     text)
    if m is None or not 0 < int(m.group(2)) < 65536:
        raise argparse.ArgumentTypeError(f"a scheduler address tcp://host:port, not {text!r}")
    return text


def _range(name: str) -> str:
    lo, hi = LIMITS[name]
    return f"{lo:g} to {hi:g}"


def _model_args(p: argparse.ArgumentParser, umax: float | None, umax_help: str) -> None:
    """The robot's parameters shared by the sub-commands, and --json."""
    p.add_argument("--rm", type=float, default=PAPER_ROBOT.r_m,
                   help=f"mass ratio m_b / m_f, {_range('r_m')} (default {PAPER_ROBOT.r_m:g})")
    p.add_argument("--s", type=float, default=PAPER_ROBOT.s,
                   help=f"stroke S / x_s, {_range('s')} (default {PAPER_ROBOT.s:g})")
    p.add_argument("--umax", type=float, default=umax, help=umax_help)
    p.add_argument("--l0", type=float, default=None,
                   help="leg length at impact and impedance rest length (default s/2)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _v0_range_args(p: argparse.ArgumentParser, n: int) -> None:
    """--v0-min, --v0-max, --n: the impact velocities a sweep visits."""
    p.add_argument("--v0-min", type=float, default=-10.0, help="default -10")
    p.add_argument("--v0-max", type=float, default=0.0, help="default 0")
    p.add_argument("--n", type=int, default=n, help=f"number of velocities (default {n})")


def _plot_arg(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--plot", metavar="FILE.png", help=f"write {what}")
    _force_arg(p)


def _accept_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--accept-unverified", action="store_true",
                   help="exit 0 even when a check fails (refinement, exact replay, PMP "
                        "certificate); the output still says 'verified: no' and why")


DASK_TIMEOUT_S = 600.0
"""Default of ``--dask-timeout`` (that of :mod:`softlanding.studies.sweeps`, not imported: slow)."""
MAX_DASK_TIMEOUT_S = 86_400.0
"""Largest ``--dask-timeout`` (:data:`softlanding.studies.sweeps.MAX_DASK_TIMEOUT_S`)."""


def dask_timeout(a: argparse.Namespace) -> float:
    """``--dask-timeout``, checked: only with ``--scheduler``, in ``(0, a day]``.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments with ``scheduler`` and ``dask_timeout`` (None: not given).

    Raises
    ------
    ParameterError
        Given without ``--scheduler`` (a local run has no cluster to wait for), or out of
        range.
    """
    if a.dask_timeout is None:
        return DASK_TIMEOUT_S
    if a.scheduler is None:
        raise ParameterError("dask-timeout", "applies with --scheduler (a local run has no "
                                             "cluster to wait for)")
    if not 0 < a.dask_timeout <= MAX_DASK_TIMEOUT_S:  # False for nan too
        raise ParameterError("dask-timeout", f"must be in (0, {MAX_DASK_TIMEOUT_S:g}] seconds, "
                                             f"got {plain(a.dask_timeout)}")
    return float(a.dask_timeout)


def _dask_args(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--scheduler", metavar="tcp://host:port", type=scheduler_address, help=what)
    p.add_argument("--dask-timeout", type=float, default=None, metavar="SECONDS",
                   help="with --scheduler only: fail (exit 1, nothing written) when no result "
                        "has arrived for this long, or no worker is left for "
                        f"min(this, 30) s (default {DASK_TIMEOUT_S:g}, at most "
                        f"{MAX_DASK_TIMEOUT_S:g})")


def _force_arg(p: argparse.ArgumentParser) -> None:
    with contextlib.suppress(argparse.ArgumentError):  # a second output option: already there
        p.add_argument("--force", action="store_true",
                       help="overwrite existing output files (default: refuse)")


def _simulate(sub: Any) -> argparse.ArgumentParser:
    s = sub.add_parser("simulate", help="simulate one landing exactly (event-driven)",
                       description="Simulate one landing with a rigid or impedance-controlled "
                                   "leg. Exact: matrix exponentials and root-found events. "
                                   "Choose --rigid, or --kp and --kd.")
    s.add_argument("--v0", type=float, required=True,
                   help=f"impact velocity, {_range('v0')} (negative = downward)")
    s.add_argument("--rigid", action="store_true", help="body and foot locked together")
    s.add_argument("--kp", type=float,
                   help=f"impedance stiffness k_p = K_p / k_g, {_range('gain')}")
    s.add_argument("--kd", type=float,
                   help=f"impedance damping k_d = K_d / sqrt(m_t k_g), {_range('gain')}")
    _model_args(s, None, "actuator force limit, saturating the leg (default: no limit)")
    _plot_arg(s, "the trajectory figure (heights, force, ground mode)")
    ground_args(s)
    return s


def _scale(sub: Any) -> argparse.ArgumentParser:
    c = sub.add_parser("scale", help="convert a physical robot to dimensionless numbers and back",
                       description="SI -> dimensionless (default; --preset paper starts from "
                                   "the paper's rig and any SI flag given overrides it) or "
                                   "dimensionless -> SI (--to-si, with --mt and --kg). "
                                   "Velocities are negative when moving down.")
    c.add_argument("--preset", choices=["paper"], help="the paper's rig (m_b 2.5, m_f 0.5 kg, "
                                                        "k_g 4.4 kN/m)")
    for flag, what in (("--mb", "body mass [kg]"), ("--mf", "foot mass [kg]"),
                       ("--kg", "ground stiffness [N/m]"), ("--stroke", "actuator stroke S [m]"),
                       ("--umax-si", "actuator force limit [N]"),
                       ("--v0-si", "impact velocity [m/s] (<= 0)"),
                       ("--Kp", "leg stiffness [N/m]"), ("--Kd", "leg damping [N s/m]"),
                       ("--g", "gravity [m/s^2] (default 9.81)")):
        c.add_argument(flag, type=float, help=what)
    c.add_argument("--medium", choices=["poppy-lp", "poppy-cp"],
                   help="instead of --kg: the ground stiffness of a flat foot by resistive "
                        "force theory, k_g = alpha_z A (poppy seeds, loosely or closely "
                        "packed), printed beside the paper's measured 4.4 kN/m")
    c.add_argument("--foot-diameter", type=float,
                   help="foot diameter for --medium [m] (default 0.130, the paper's foot)")
    c.add_argument("--to-si", action="store_true", help="convert dimensionless -> SI")
    c.add_argument("--mt", type=float, default=3.0, help="total mass for --to-si [kg] (3)")
    for flag, what in (("--rm", "mass ratio"), ("--s", "stroke"), ("--v0", "impact velocity"),
                       ("--umax", "force limit"), ("--kp", "stiffness"), ("--kd", "damping")):
        c.add_argument(flag, type=float, help=f"{what} for --to-si")
    c.add_argument("--json", action="store_true", help="print one JSON object")
    return c


def _solve(sub: Any, argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    o = sub.add_parser("solve", help="minimum-depth landing by optimal control (bang-bang)",
                       description="Solve the paper's soft-landing OCP (min -x_f(T), free T, "
                                   "|u| <= umax, 0 <= stroke <= s, v_f <= 0, v_f(T) = 0, "
                                   "body-arrest condition) by multiple shooting and Ipopt, "
                                   "then refine the switching times with exact arcs and "
                                   "replay the schedule in the exact simulator; or one of "
                                   "the hybrid variants (--variant). An option the chosen "
                                   "variant does not take is refused (exit 2).")
    o.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    _model_args(o, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    o.add_argument("--no-refine", action="store_true", default=None,
                   help="report the transcribed solution only (replayed as its "
                        "piecewise-constant force)")
    o.add_argument("--pmp", action="store_true", default=None,
                   help="check Pontryagin's conditions (costates, H, switching function) "
                        "and give a bang-bang verdict, or say in one line why there is no "
                        "certificate (not with two-phase --steps 2)")
    _plot_arg(o, "the trajectory figure (paper --pmp: also FILE-pmp.png, the certificate)")
    _accept_arg(o)
    ground_args(o)
    add_variant_options(o, argv, "solve")
    return o


def _hop(sub: Any) -> argparse.ArgumentParser:
    h = sub.add_parser("hop", help="minimum-energy hop cycle on yielding ground",
                       description="One vertical hop: touchdown on fresh ground at v0 (apex "
                                   "v0^2/2, leg at s/2), stance on the crater, lift-off, "
                                   "flight back to the apex posture. Minimises the energy the "
                                   "actuator draws per cycle, int (P+ - eta P-) dt, and "
                                   "evaluates it on the exact replay.")
    h.add_argument("--v0", type=float, required=True, help="touchdown velocity (< 0)")
    h.add_argument("--eta", type=float, default=0.0,
                   help="regenerative efficiency in [0, 1) (default 0: a dissipative actuator)")
    h.add_argument("--leg", choices=["free", "impedance", "rigid", "all"], default="free",
                   help="free: the optimum; impedance: the best (k_p, k_d) with a thrust from "
                        "the body's lowest point to lift-off; rigid: a rigid landing, then "
                        "the optimal push-off; all: the three")
    h.add_argument("--grid", type=int, default=None,
                   help="--leg impedance or all: gain grid per axis (default 9, 2 to 41)")
    h.add_argument("--doublings", type=int, default=None, metavar="K",
                   help="--leg free or all: the optimum re-solved on K grids, each with twice "
                        "the nodes (default 1, 0 to 4); the finest is reported with the "
                        "continuous optimum extrapolated from the sequence and its error; its "
                        "arcs are then refined exactly and replayed (converged when the "
                        "refined energy and its replay agree to 1e-6). Where that fails the "
                        "grid's energy, a discretised value, is reported and the cycle is not "
                        "verified (exit 1 without --accept-unverified)")
    _model_args(h, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    h.add_argument("--pmp", action="store_true", default=None,
                   help="say, for every leg, why there is no Pontryagin certificate (the "
                        "hop's optimum is not bang-bang: its arc structure is named)")
    _plot_arg(h, "the hop cycle figure (the first leg), phases shaded")
    _accept_arg(h)
    return h


def _solve_sweep(sub: Any, argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    w = sub.add_parser("solve-sweep", help="bang-bang depth against impact velocity",
                       description="Solve the OCP over v0 from --v0-max down to --v0-min "
                                   "with continuation (each solve warm-starts the next); "
                                   "or any landing variant (--variant, its options as for "
                                   "solve).")
    _v0_range_args(w, 21)
    _model_args(w, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    _plot_arg(w, "depth against v0")
    _accept_arg(w)
    ground_args(w)
    add_variant_options(w, argv, "solve-sweep")
    return w


def _impedance(sub: Any) -> argparse.ArgumentParser:
    i = sub.add_parser("impedance", help="optimal impedance gains for one impact velocity",
                       description="Minimise depth (or CoT) over the gains (k_p, k_d) in "
                                   "[0, 1]^2, excluding landings that leave the stroke: the "
                                   "paper's grid, then a zooming feasible-grid refinement "
                                   "(to 1e-8) and a bisection onto the stroke limit. With "
                                   "comma lists of --stiffness or --cd (e.g. --ground drag "
                                   "--stiffness 0.5,1,2 --cd 0,0.2,1), the gains minimise "
                                   "the worst case over every ground named, feasible on all "
                                   "of them.")
    i.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    _model_args(i, None, "actuator force limit (default none, as in the paper's study)")
    i.add_argument("--objective", choices=["depth", "cot", "cot-lossless"], default="depth",
                   help="depth; CoT with actuator and ground losses; or ground losses only")
    i.add_argument("--grid", type=int, default=101,
                   help="starting grid per axis (default 101, 2 to 2001)")
    ground_args(i, several=True)
    return i


def _map(sub: Any) -> argparse.ArgumentParser:
    m = sub.add_parser("map", help="the (k_p, k_d) depth map at one impact velocity",
                       description="Simulate the (k_p, k_d) grid, save every figure of every "
                                   "landing as a labelled netCDF dataset, and plot depth "
                                   "normalised by its minimum (infeasible blank, optimum "
                                   "starred).")
    m.add_argument("--v0", type=float, required=True, help="impact velocity (<= 0)")
    m.add_argument("--n", type=int, default=101, help="points per axis (default 101, <= 2001)")
    _model_args(m, None, "actuator force limit (default none)")
    m.add_argument("--out", required=True, metavar="FILE.nc", help="netCDF dataset to write")
    _plot_arg(m, "the map figure")
    _dask_args(m, "run on a Dask cluster instead of the local cores")
    ground_args(m)
    return m


def _sweep(sub: Any) -> argparse.ArgumentParser:
    w = sub.add_parser("sweep", help="optimal gains against impact velocity (and r_m, s)",
                       description="Optimal impedance at each v0 from --v0-max to --v0-min, "
                                   "for every --rm and --s given (repeat the flags for "
                                   "families), with the paper's observations checked.")
    _v0_range_args(w, 21)
    w.add_argument("--rm", type=float, action="append", help="mass ratio (repeatable)")
    w.add_argument("--s", type=float, action="append", help="stroke (repeatable)")
    w.add_argument("--umax", type=float, help="actuator force limit (default none)")
    w.add_argument("--objective", choices=["depth", "cot", "cot-lossless"], default="depth")
    w.add_argument("--grid", type=int, default=101, help="starting grid per axis")
    w.add_argument("--out", metavar="FILE.nc", help="netCDF dataset to write")
    _plot_arg(w, "the curves figure")
    _dask_args(w, "Dask scheduler address")
    w.add_argument("--json", action="store_true", help="print one JSON object")
    ground_args(w)
    return w


def _compare(sub: Any) -> argparse.ArgumentParser:
    cp = sub.add_parser("compare", help="rigid vs optimal impedance vs bang-bang, against v0",
                        description="The paper's comparison: penetration depth against impact "
                                    "velocity for a rigid leg (analytic), the depth-optimal "
                                    "impedance (unsaturated, as in the paper), and optimal "
                                    "bang-bang force control.")
    _v0_range_args(cp, 11)
    _model_args(cp, PAPER_ROBOT.u_max,
                f"force limit of the bang-bang controller (default {PAPER_ROBOT.u_max:g})")
    cp.add_argument("--grid", type=int, default=101, help="impedance starting grid per axis")
    _plot_arg(cp, "depth against v0")
    ground_args(cp)
    return cp


DEMO_FOLDER = "softlanding-demo"
"""The demo's own output folder (replaced, all at once, by each run that writes it)."""
DEMO_FIGURE = "demo.png"
"""The demo's figure in :data:`DEMO_FOLDER`."""


def _demo(sub: Any) -> argparse.ArgumentParser:
    d = sub.add_parser("demo", help="rigid vs impedance landings at several impact velocities",
                       description="Simulate rigid and impedance landings at v0 = 0, -1, -3, "
                                   "-5, -10, print a table (with the analytic rigid depth "
                                   "as a check) and write a figure. About 5 s of CPU: "
                                   "until a command has compiled the simulator, the "
                                   "demo's hundred landings run it as Python, faster than "
                                   "compiling it (about 20 s); the numbers are the same to "
                                   "the last bit.")
    d.add_argument("--out", metavar="FILE.png",
                   help="figure path, a new file unless --force ('' for none); by default "
                        f"{DEMO_FOLDER}/{DEMO_FIGURE}, in the demo's own folder, which each "
                        "run replaces all at once")
    d.add_argument("--json", action="store_true", help="print one JSON object")
    _force_arg(d)
    return d


def _reproduce(sub: Any) -> argparse.ArgumentParser:
    r = sub.add_parser("reproduce", help="every figure of the paper, summary tables, robustness",
                       description="Regenerate every figure of the paper (PNG and PDF), "
                                   "summary.md and summary.json with the headline numbers, "
                                   "and a robustness study of the nominal bang-bang and "
                                   "impedance controllers under +-30 % model error. --quick "
                                   "(coarser grids, fewer velocities) takes about 3 minutes "
                                   "of CPU (179 s measured on a quiet machine, 2 min 20 s "
                                   "wall on 2 cores); the full run several times that.")
    r.add_argument("--out", required=True, metavar="DIR",
                   help="folder to write: new or empty, or with --force an existing one whose "
                        "files of the same names are replaced")
    _force_arg(r)
    r.add_argument("--quick", action="store_true", help="coarser grids: about 3 minutes of CPU")
    r.add_argument("--json", action="store_true", help="print summary.json's contents")
    return r


def _mpc(sub: Any) -> argparse.ArgumentParser:
    m = sub.add_parser("mpc", help="model-predictive landing on ground the robot does not know",
                       description="Land on the true ground (the ground options) under "
                                   "closed-loop control: every --period the controller "
                                   "measures the state and the foot's acceleration, updates a "
                                   "least-squares estimate of the ground (f = K d + c_d v^2), "
                                   "re-solves the landing from the measured state (compiled, "
                                   "within the rig's period, unless --controller replan) and "
                                   "applies it for one period. Compared with the clairvoyant "
                                   "optimum (knows the ground) and the nominal open-loop plan "
                                   "replayed on the true ground.")
    m.add_argument("--v0", type=float, required=True,
                   help="impact velocity (<= -1e-6: slower, the foot counts as stopped)")
    _model_args(m, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    m.add_argument("--period", type=float, default=None,
                   help="sample period in sqrt(m_t/k_g) (default 0.01: 0.26 ms on the paper's "
                        "rig, a 4 kHz controller)")
    m.add_argument("--model-ground", choices=["linear", "drag"], default="linear",
                   help="the ground the controller assumes before measuring (default: the "
                        "paper's linear ground)")
    m.add_argument("--model-stiffness", type=float, default=None, metavar="K",
                   help="its stiffness factor (default 1)")
    m.add_argument("--model-cd", type=float, default=None, metavar="C",
                   help="its drag number (--model-ground drag)")
    m.add_argument("--no-estimate", action="store_true",
                   help="keep the model ground (no on-line estimation)")
    m.add_argument("--controller", choices=["bangbang", "replan"], default="bangbang",
                   help="bangbang (default): the compiled real-time controller, microseconds "
                        "a sample (Newton on the push/pull switching times, the creep law, "
                        "and a compiled fallback where neither covers the state); replan: "
                        "re-solve the landing OCP every sample (milliseconds to seconds a "
                        "sample: the slow baseline)")
    m.add_argument("--noise-std", type=float, default=0.0, metavar="S",
                   help="Gaussian noise (standard deviation, paper units) on the measured "
                        "foot position, velocity, acceleration and force (default 0)")
    m.add_argument("--delay", type=int, default=0, metavar="N",
                   help="samples between a measurement and the actuation of its control "
                        "(default 0)")
    m.add_argument("--seed", type=int, default=0, metavar="K",
                   help="the noise's random seed (default 0)")
    m.add_argument("--margin", type=float, default=0.0, metavar="M",
                   help="bangbang: plan for the estimate less M standard deviations of K and "
                        "c_d while it is uncertain (default 0)")
    m.add_argument("--estimator", choices=["measured", "filtered"], default=None,
                   help="with --noise-std: what the ground estimate regresses. filtered "
                        "(default): the force as commanded and the foot state filtered with "
                        "its measured acceleration (assumes the actuator applies its command "
                        "exactly); measured: the measured force and foot state")
    _plot_arg(m, "the landing's depth and force against time")
    ground_args(m)
    return m


def _export_controller(sub: Any) -> argparse.ArgumentParser:
    e = sub.add_parser("export-controller",
                       help="write the compiled landing controller as C source (libm only)",
                       description="Write the landing controller that `mpc --controller "
                                   "bangbang` runs (a real-time Newton on the push/pull "
                                   "durations with a least-squares ground estimator) as C99 "
                                   "source for a robot: DIR/softlanding_controller.c and .h "
                                   "(the step function, the layout of its parameter and memory "
                                   "arrays, and the foot filter, per-sample weights and "
                                   "recovery of `mpc --estimator filtered` for noisy sensors) "
                                   "and README.txt (how to compile and call it). It "
                                   "needs nothing beyond libm. The robot's and the ground's "
                                   "numbers are runtime parameters (the array P); the options "
                                   "below give the values written as SL_ROBOT_NUMBERS. --check "
                                   "compiles it with the system's C compiler and compares it "
                                   "with the Python controller on 1,000 samples of random "
                                   "landings, and the filter and the filtered step with the "
                                   "Python ones on 600 samples of noisy landings (exit 1 "
                                   "unless every output agrees to 1e-12).")
    e.add_argument("--out", required=True, metavar="DIR",
                   help="folder to write: new or empty, or with --force an existing one whose "
                        "files of the same names are replaced (written in a temporary folder, "
                        "put in place at the end)")
    _force_arg(e)
    _model_args(e, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    e.add_argument("--period", type=float, default=None,
                   help="sample period in sqrt(m_t/k_g) (default 0.01: 0.26 ms on the paper's "
                        "rig)")
    e.add_argument("--model-ground", choices=["linear", "drag"], default="linear",
                   help="the ground the controller assumes before measuring (default linear)")
    e.add_argument("--model-stiffness", type=float, default=None, metavar="K",
                   help="its stiffness factor (default 1)")
    e.add_argument("--model-cd", type=float, default=None, metavar="C",
                   help="its drag number (--model-ground drag)")
    e.add_argument("--noise-std", type=float, default=0.0, metavar="S",
                   help="the sensors' noise (standard deviation of the measured foot "
                        "acceleration and force, paper units), which weighs the estimator "
                        "(default 0)")
    e.add_argument("--margin", type=float, default=0.0, metavar="M",
                   help="plan for the estimate less M standard deviations of K and c_d "
                        "(default 0)")
    e.add_argument("--estimator", choices=["measured", "filtered"], default="measured",
                   help="with --noise-std: the estimate the numbers are for. measured: the "
                        "measured force and foot state (default); filtered: the force as "
                        "applied and the foot state from the exported foot filter "
                        "(sl_filter_step, then sl_filtered_weight and sl_filtered_step; the "
                        "estimator's noise then the filtered one's)")
    e.add_argument("--check", action="store_true",
                   help="compile the files with the system's C compiler (cc, gcc or $CC) and "
                        "compare them (controller, foot filter, filtered step) with the Python "
                        "ones "
                        "before writing them")
    return e


def _robust(sub: Any) -> argparse.ArgumentParser:
    r = sub.add_parser("robust", help="one landing plan for a set of grounds (robust, tree)",
                       description="Plan the landing for every ground of a set (the products "
                                   "of --stiffness and --cd: f = K d + c_d v^2) at once: the "
                                   "robust open-loop schedule minimises the worst depth over "
                                   "the set with the stroke held and the body at rest on every "
                                   "ground (exact replays); --tree shares it only until "
                                   "--branch-time, then re-plans on each ground. Compared per "
                                   "ground with the nominal plan (solved for the paper's ground) "
                                   "and the clairvoyant optimum (knows the ground).")
    r.add_argument("--v0", type=float, required=True, help="impact velocity (< 0)")
    _model_args(r, PAPER_ROBOT.u_max, f"force limit (default {PAPER_ROBOT.u_max:g})")
    r.add_argument("--stiffness", type=numbers, default=[1.0], metavar="K1,K2,...",
                   help="the grounds' stiffness factors K > 0 (default 1)")
    r.add_argument("--cd", type=numbers, default=[0.0], metavar="C1,C2,...",
                   help="the grounds' drag numbers c_d >= 0 (default 0: linear grounds)")
    r.add_argument("--tree", action="store_true",
                   help="also the two-stage tree: the robust schedule until --branch-time, "
                        "then a plan for each ground")
    r.add_argument("--branch-time", type=float, default=None, metavar="T",
                   help="when the tree branches, in sqrt(m_t/k_g) (default 0.05: 1.3 ms on "
                        "the paper's rig; with --tree only)")
    r.add_argument("--extra-pieces", type=int, default=0, metavar="N",
                   help="force pieces added to the nominal plan's before the search (0 to 4, "
                        "default 0)")
    _plot_arg(r, "the depth on every ground")
    r.add_argument("--accept-unverified", action="store_true",
                   help="exit 0 even when the search did not converge (its KKT check fails); "
                        "the output still says 'converged: no' and why")
    return r


def _cache(sub: Any) -> argparse.ArgumentParser:
    c = sub.add_parser("cache", help="the compiled ground-law cache: size, --clear",
                       description="Ground laws the exact kernel does not have built in (a "
                                   "user's ground, a drag ground of stiffness K != 1) are "
                                   "compiled to C once and kept in $SOFTLANDING_CACHE/laws "
                                   "(default ~/.cache/softlanding/laws), least recently used "
                                   "evicted beyond 256 laws or 32 MiB. Shows the folder, the "
                                   "number of laws and their size.")
    c.add_argument("--clear", action="store_true", help="remove every compiled law")
    c.add_argument("--json", action="store_true", help="print one JSON object")
    return c


BUILDERS = {"simulate": _simulate, "scale": _scale, "solve": _solve, "solve-sweep": _solve_sweep,
            "impedance": _impedance, "map": _map, "sweep": _sweep, "compare": _compare,
            "demo": _demo, "reproduce": _reproduce, "hop": _hop, "mpc": _mpc,
            "robust": _robust, "export-controller": _export_controller,
            "variants": variants_parser, "cache": _cache}


def build_parser(handlers: Handlers, parser_class: type[argparse.ArgumentParser],
                 argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The whole parser; each sub-command calls its handler.

    Parameters
    ----------
    handlers : dict
        Sub-command name -> function of the parsed arguments returning the exit code
        (``variants`` has its own).
    parser_class : type
        The ArgumentParser subclass to use (one-line errors).
    argv : sequence of str, optional
        The command line to be parsed: a variant it names outside the built-in ones
        (``--variant module:attribute``) adds its options to ``solve``.
    """
    ap = parser_class(prog="softlanding", description=DESCRIPTION)
    ap.add_argument("--version", action="version", version=f"softlanding {_version()}")
    ap.add_argument("--debug", action="store_true",
                    help="show the traceback of an internal error")
    ap.add_argument("--progress", action="store_true",
                    help="draw progress bars even when stderr is not a terminal")
    sub = ap.add_subparsers(dest="command", required=True, parser_class=parser_class)
    for name, build in BUILDERS.items():
        s = build(sub, argv) if build in (_solve, _solve_sweep) else build(sub)
        if name in handlers:
            s.set_defaults(func=handlers[name])
        # also accepted after the sub-command (without overwriting the value given before it)
        s.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                       help=argparse.SUPPRESS)
        s.add_argument("--progress", action="store_true", default=argparse.SUPPRESS,
                       help=argparse.SUPPRESS)
    return ap
