"""Switching-time refinement and PMP certificate: before vs now, interleaved.

Run:  python -m benchmarks.bench_refinement [--n 12] [--baseline 4d4afb0]

For ``--n`` impact velocities of the soft landing (r_m = 5, s = 20, u_max =
8.2) the transcriptions are solved first (not timed); then, v0 by v0 and
alternating, the refinement is timed three ways: the implementation at git
commit ``--baseline`` (loaded from git into a private module), the current
one through Ipopt (``fast=False``) and the current one with the Newton fast
path (``fast=True``). The same is done for the certificate (``certify`` with
the refined solution). Times are CPU (``time.process_time``) and wall
(``time.perf_counter``); the first call of each (which builds the NLP) is
reported apart from the medians of the re-solves. The depths of old and new
must agree to 1e-12, and the certificates' verdicts must be equal.

Goal (speed issue): refinement per re-solve <= ~20 ms for the landing.

Also times the time-optimal Rayleigh problem (state-nonlinear, |u| <= 4):
refinement and certificate with default settings (the baseline needed
90-110 s and failed there; it is not re-run unless ``--rayleigh-baseline``).
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def load_baseline(commit: str):
    """The ``ocp.structure.switching`` and ``ocp.certificate.certify`` modules at ``commit``,
    as private modules."""
    mods = {}
    for name in ("switching", "pmp"):
        src = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:ocp/{name}.py"],
                             capture_output=True, text=True, check=True).stdout
        src = src.replace("from .switching import", "from ocp._switching_before import")
        spec = importlib.util.spec_from_loader(f"ocp._{name}_before", loader=None)
        mod = importlib.util.module_from_spec(spec)
        mod.__package__ = "ocp"
        sys.modules[spec.name] = mod
        exec(compile(src, f"{commit}:ocp/{name}.py", "exec"), mod.__dict__)
        mods[name] = mod
    return mods["switching"], mods["pmp"]


def timed(fn, *args, **kw):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn(*args, **kw)
    return out, time.process_time() - c0, time.perf_counter() - w0


def landing(args, old_sw, old_pmp) -> None:
    from ocp.certificate.certify import certify
    from ocp.structure.switching import detect_arcs, refine_switching
    from softlanding.optimal.landing import solve_landing

    v0s = np.linspace(-0.5, -10.0, args.n)
    sols = [solve_landing(v, replay=False, refine=False).transcribed for v in v0s]
    sts = [detect_arcs(s).without_trailing_constrained() for s in sols]
    rows = {k: [] for k in ("old", "ipopt", "newton", "cert_old", "cert_new")}
    worst, verdicts = 0.0, 0
    for sol, st in zip(sols, sts, strict=True):
        r_old, *t_old = timed(old_sw.refine_switching, sol, old_sw.detect_arcs(sol)
                              .without_trailing_constrained())
        r_ip, *t_ip = timed(refine_switching, sol, st, fast=False)
        r_nw, *t_nw = timed(refine_switching, sol, st, fast=True)
        c_old, *tc_old = timed(old_pmp.certify, sol, r_old)
        c_new, *tc_new = timed(certify, sol, r_nw)
        for k, t in (("old", t_old), ("ipopt", t_ip), ("newton", t_nw), ("cert_old", tc_old),
                     ("cert_new", tc_new)):
            rows[k].append(t)
        worst = max(worst, abs(r_old.xT[2] - r_ip.xT[2]), abs(r_old.xT[2] - r_nw.xT[2]))
        verdicts += c_old.verdict == c_new.verdict
    print(f"soft landing, {args.n} values of v0 in [-0.5, -10] (s = 20), interleaved")
    print(f"{'':28}{'first call':>22}{'re-solves, median':>24}")
    print(f"{'':28}{'CPU [ms]':>11}{'wall [ms]':>11}{'CPU [ms]':>12}{'wall [ms]':>12}")
    names = {"old": f"refine, baseline {args.baseline}", "ipopt": "refine, now (Ipopt)",
             "newton": "refine, now (fast path)", "cert_old": "certify, baseline",
             "cert_new": "certify, now"}
    for k, lab in names.items():
        first, rest = rows[k][0], rows[k][1:]
        med = [statistics.median(t[i] for t in rest) * 1e3 for i in (0, 1)]
        print(f"{lab:28}{first[0] * 1e3:11.1f}{first[1] * 1e3:11.1f}{med[0]:12.2f}{med[1]:12.2f}")
    for k in ("ipopt", "newton"):
        ratio = statistics.median(a[0] / b[0] for a, b in zip(rows["old"][1:], rows[k][1:],
                                                              strict=True))
        print(f"speed-up of re-solves, baseline / {k} (CPU, median of ratios): {ratio:.1f}x")
    ratio = statistics.median(a[0] / b[0] for a, b in zip(rows["cert_old"], rows["cert_new"],
                                                          strict=True))
    print(f"speed-up of certify, baseline / now (CPU, median of ratios): {ratio:.1f}x")
    print(f"largest depth difference old vs new: {worst:.2e}; equal verdicts: "
          f"{verdicts}/{args.n}")


def rayleigh(args, old_sw, old_pmp) -> None:
    from ocp import MultipleShooting, OptimalControlProblem
    from ocp.certificate.certify import certify
    from ocp.structure.switching import clear_cache, refine_switching

    p = OptimalControlProblem("rayleigh")
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", lower=-4, upper=4)
    p.set_dynamics([x2, -x1 + x2 * (1.4 - 0.14 * x2**2) + u])
    for s, v in ((x1, -5.0), (x2, -5.0)):
        p.initial_constraint(s, v)
    for s in (x1, x2):
        p.terminal_constraint(s, 0.0)
    p.free_final_time(0.1, 20, 4.0)
    p.minimize_terminal(p.T)
    ms = MultipleShooting(p, nodes=100)
    sol = ms.solve({}, guess=ms.initial_guess(T=3.7, x=lambda s: [-5 * (1 - s), 0.0], u=[0.0]))
    clear_cache(p)
    r, c1, w1 = timed(refine_switching, sol)
    _, c2, w2 = timed(refine_switching, sol)
    cert, c3, w3 = timed(certify, sol, r)
    cert0, c4, w4 = timed(certify, sol)
    print("\ntime-optimal Rayleigh (x2' = -x1 + x2 (1.4 - 0.14 x2^2) + u, |u| <= 4), N = 100")
    print(f"refine, first call (build) : CPU {c1:.2f} s, wall {w1:.2f} s; T = {r.T:.12f}, "
          f"switches {', '.join(f'{t:.10f}' for t in r.switch_times)}, {r.status}")
    print(f"refine, re-solve           : CPU {c2 * 1e3:.1f} ms, wall {w2 * 1e3:.1f} ms; RK8 steps "
          f"{r.nlp.substeps}, integration error {r.integration_error:.1e}")
    print(f"certify (refined)          : CPU {c3 * 1e3:.0f} ms, wall {w3 * 1e3:.0f} ms; "
          f"{cert.verdict}, max|H| {cert.H_max_abs:.1e}, own error {cert.numerical_error}")
    print(f"certify (transcription)    : CPU {c4 * 1e3:.0f} ms, wall {w4 * 1e3:.0f} ms; "
          f"{cert0.verdict}")
    if args.rayleigh_baseline:
        c0, w0 = time.process_time(), time.perf_counter()
        try:
            rb = old_sw.refine_switching(sol)
            what = f"T = {rb.T:.12f}"
        except Exception as e:  # noqa: BLE001 - report whatever the baseline does
            what = f"failed: {e}"
        print(f"baseline refine: CPU {time.process_time() - c0:.1f} s, "
              f"wall {time.perf_counter() - w0:.1f} s, {what}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--baseline", default="4d4afb0")
    ap.add_argument("--rayleigh-baseline", action="store_true")
    args = ap.parse_args()
    old_sw, old_pmp = load_baseline(args.baseline)
    landing(args, old_sw, old_pmp)
    rayleigh(args, old_sw, old_pmp)


if __name__ == "__main__":
    main()
