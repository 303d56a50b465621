"""The published-problem suite with this toolkit and with rockit, in one run.

Run:  pip install -e ".[bench]" && python -m benchmarks.ocp_suite [--repeats 3] [names...]

For every problem of ``tests/ocp_suite`` this toolkit runs Radau collocation
(degree 3) with mesh refinement to the problem's tolerance; the final mesh's
number of intervals N is then given to rockit's ``DirectCollocation`` (Radau,
degree 3, uniform mesh: rockit has no mesh refinement), so both solve an NLP
of the same size. Each tool's NLP is then built and solved ``--repeats``
times, alternating tool by tool, solve by solve; the table reports medians
of wall time and of CPU time (``time.process_time``), the objective and its
error against the closed form where one exists, else against the published
value. rockit is given the same problem through a generic translation of the
``ocp`` definition (same expressions, same default initial guess, same Ipopt
options); multi-phase problems are not translated (rockit stages) and show n/a.

Columns: ``refine`` = this toolkit's whole refinement run (all meshes);
``build`` = building the NLP on the final mesh (rockit: up to its first
solve's transcription); ``solve`` = one solve from the default guess.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
import warnings
from typing import Any

import casadi as ca
import numpy as np

from ocp import Collocation, OptimalControlProblem  # noqa: E402
from ocp.definition.guess import control_guess, state_ends, variable_guess  # noqa: E402
from ocp.transcriptions.nlp import DEFAULT_IPOPT  # noqa: E402
from tests.oracles.ocp_suite import PROBLEMS, SuiteProblem  # noqa: E402


def timed(fn: Any) -> tuple[Any, float, float]:
    """``fn()`` with its wall and CPU time."""
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


# ------------------------------------------------------------------ ours
def ours_refine(sp: SuiteProblem) -> tuple[Any, float, float]:
    tr = Collocation(sp.build(), intervals=sp.intervals, degree=sp.degree)
    guess = sp.guess() if sp.guess else None
    return timed(lambda: tr.refine(tol=sp.tol, max_rounds=sp.max_rounds, guess=guess))


def ours_round(sp: SuiteProblem, meshes: list[np.ndarray]) -> dict[str, float]:
    tr, bw, bc = timed(lambda: Collocation(sp.build(), mesh=meshes, degree=sp.degree,
                                           verify="off"))
    guess = sp.guess() if sp.guess else None
    sol, sw, sc = timed(lambda: tr.solve(guess=guess))
    return {"build": bw, "build_cpu": bc, "solve": sw, "solve_cpu": sc,
            "value": sp.value(sol)}


# ------------------------------------------------------------------ rockit
def call(expr: ca.SX, syms: list[ca.SX], values: list[Any]) -> Any:
    """``expr`` with ``syms`` replaced by rockit's ``values`` (only the ones it uses, so
    that rockit sees no spurious dependence on time)."""
    used = [(s, v) for s, v in zip(syms, values, strict=True)
            if s.numel() and ca.depends_on(expr, s)]
    if not used:
        return ca.MX(ca.evalf(expr))
    return ca.Function("e", [s for s, _ in used], [expr])(*[v for _, v in used])


def rockit_problem(pr: OptimalControlProblem, N: int, degree: int,
                   guess: Any = None) -> tuple[Any, Any]:
    """``pr`` translated to a rockit ``Ocp`` (single phase, no parameters)."""
    from rockit import DirectCollocation, FreeTime, Ocp

    t0 = FreeTime(pr.t0_guess) if pr.t0_mode == "free" else pr.t0_bounds[0]
    dur0 = (pr.T_guess if pr.duration is None else pr.duration_guess or 1.0) - \
        (pr.t0_guess if pr.duration is None else 0.0)
    T = FreeTime(dur0) if pr.time_free else pr.T_bounds[0] - pr.t0_bounds[0]
    ocp = Ocp(t0=t0, T=T)
    X = ca.vertcat(*[ocp.state() for _ in range(pr.nx)])
    U = ca.vertcat(*[ocp.control() for _ in range(pr.nu)]) if pr.nu else ca.MX(0, 1)
    V = ca.vertcat(*[ocp.variable() for _ in range(pr.nv)]) if pr.nv else ca.MX(0, 1)
    run = [pr.x, pr.u, pr.t, pr.v, pr.t0, pr.T]
    rrun = [X, U, ocp.t, V, ocp.t0, ocp.tf]
    ocp.set_der(X, call(pr.rhs, run, rrun))
    _rockit_constraints(ocp, pr, run, rrun, X, U, V)
    _rockit_guess(ocp, pr, X, U, V, guess)
    ocp.method(DirectCollocation(N=N, degree=degree, scheme="radau"))
    ocp.solver("ipopt", {"ipopt": DEFAULT_IPOPT, "print_time": False, "expand": True})
    return ocp, X


def _bounded(ocp: Any, expr: Any, lo: float, hi: float, grid: str | None = None) -> None:
    kw = {} if grid is None else {"grid": grid}
    if lo == hi:
        ocp.subject_to(expr == lo, **kw)
        return
    if math.isfinite(lo):
        ocp.subject_to(expr >= lo, **kw)
    if math.isfinite(hi):
        ocp.subject_to(expr <= hi, **kw)


def _rockit_constraints(ocp: Any, pr: OptimalControlProblem, run: list, rrun: list,
                        X: Any, U: Any, V: Any) -> None:
    h, lo, hi = (ca.evalf(v) if k else v for k, v in enumerate(pr.path_stack()))
    if h.numel():
        H = call(h, run, rrun)
        for i in range(h.numel()):
            _bounded(ocp, H[i], float(lo[i]), float(hi[i]))
    for i, n in enumerate(pr.state_names):
        _bounded(ocp, X[i], *(float(ca.evalf(b)) for b in pr.state_bounds[n]))
    for i, n in enumerate(pr.control_names):
        _bounded(ocp, U[i], *(float(ca.evalf(b)) for b in pr.control_bounds[n]))
    if pr.time_free and pr.duration is None:
        _bounded(ocp, ocp.tf, *pr.T_bounds)
    ints = [ocp.integral(call(e, run, rrun)) for _, e in pr.integrals]
    bsym = [pr.x0, pr.u0, pr.xT, pr.uT, pr.t0, pr.T, pr.q, pr.v]
    rb = [ocp.at_t0(X), ocp.at_t0(U) if pr.nu else U, ocp.at_tf(X),
          ocp.at_tf(U) if pr.nu else U, ocp.t0, ocp.tf, ca.vertcat(*ints), V]
    cons = ([(pr.at_t0(c.expr), c) for c in pr.initial] + [(pr.at_tf(c.expr), c)
                                                            for c in pr.terminal]
            + [(c.expr, c) for c in pr.boundary])
    for e, c in cons:
        val = call(e, bsym, rb)
        _bounded(ocp, val, float(ca.evalf(c.lower)), float(ca.evalf(c.upper)))
    J = call(pr.at_tf(pr.mayer) + pr.boundary_cost, bsym, rb)
    if pr.has_running_cost():
        J = J + ocp.integral(call(pr.lagrange, run, rrun))
    ocp.add_objective(J)


def _rockit_guess(ocp: Any, pr: OptimalControlProblem, X: Any, U: Any, V: Any,
                  guess: Any) -> None:
    """The same default guess as this toolkit's (straight lines, bound midpoints)."""
    a, b = (np.array(ca.evalf(e), dtype=float).ravel() for e in state_ends(pr))
    ug = np.array(ca.evalf(control_guess(pr)), dtype=float).ravel()
    t0, T = pr.t0_guess, pr.T_guess if pr.duration is None else pr.duration_guess
    s = (ocp.t - t0) / (T - t0)
    for i, name in enumerate(pr.state_names):
        if guess is not None and name in guess.state_names:
            c = np.polyfit(guess.t, guess[name], 3)
            ocp.set_initial(X[i], sum(ci * ocp.t ** (3 - k) for k, ci in enumerate(c)))
        else:
            ocp.set_initial(X[i], a[i] + (b[i] - a[i]) * s)
    for i, name in enumerate(pr.control_names):
        if guess is not None and name in guess.control_names:
            c = np.polyfit(guess.t, guess[name], 3)
            ocp.set_initial(U[i], sum(ci * ocp.t ** (3 - k) for k, ci in enumerate(c)))
        else:
            ocp.set_initial(U[i], float(ug[i]))
    if pr.nv:
        ocp.set_initial(V, np.array(ca.evalf(variable_guess(pr.shared))).ravel())


def rockit_round(sp: SuiteProblem, N: int) -> dict[str, float]:
    pr = sp.build()
    guess = sp.guess() if sp.guess else None
    (ocp, X), bw, bc = timed(lambda: rockit_problem(pr, N, sp.degree, guess))
    # rockit transcribes inside its first solve: time it separately
    _, tw, tc = timed(lambda: ocp._transcribe())
    sol, sw, sc = timed(ocp.solve)
    value = float(sol.value(ocp.objective)) if hasattr(ocp, "objective") else math.nan
    value = -value if sp.value(_Fake(1.0)) < 0 else value
    return {"build": bw + tw, "build_cpu": bc + tc, "solve": sw, "solve_cpu": sc,
            "value": value}


class _Fake:
    """Tells whether ``sp.value`` negates the objective (maximisation problems)."""

    def __init__(self, objective: float) -> None:
        self.objective = objective


# ------------------------------------------------------------------ driver
def run(sp: SuiteProblem, repeats: int) -> dict[str, Any]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol, rw, rc = ours_refine(sp)
        meshes = [ph.discretization.tau for ph in sol.phases]
        N = sum(m.size - 1 for m in meshes)
        ours, rock = [], []
        single = len(sol.phases) == 1
        for _ in range(repeats):  # alternate the tools, solve by solve
            ours.append(ours_round(sp, meshes))
            if single:
                try:
                    rock.append(rockit_round(sp, N))
                except Exception as err:  # noqa: BLE001 -- report, do not stop the table
                    rock.append({"error": f"{type(err).__name__}: {err}"[:60]})
    return {"problem": sp, "refine": (rw, rc, len(sol.mesh_history), N), "ours": ours,
            "rockit": rock, "value": sp.value(sol)}


def med(rows: list[dict[str, float]], key: str) -> float:
    vals = [r[key] for r in rows if key in r]
    return statistics.median(vals) if vals else math.nan


def errors(sp: SuiteProblem, value: float) -> str:
    """Relative error against the published value and against the closed form."""
    def rel(ref: float) -> str:
        return f"{abs(value - ref) / abs(ref):8.1e}" if math.isfinite(ref) else f"{'-':>8s}"

    return rel(sp.published) + " " + rel(sp.exact() if sp.exact is not None else math.nan)


def report(res: dict[str, Any]) -> str:
    """One line of the table."""
    sp = res["problem"]
    rw, rc, rounds, N = res["refine"]
    ours = res["ours"]
    line = (f"{sp.name:21s} {res['value']:>13.9g} {errors(sp, res['value'])} | "
            f"{rw:6.2f} {rc:6.2f} {rounds:2d} {N:4d} | {med(ours, 'build'):5.2f} "
            f"{med(ours, 'solve'):6.3f} {med(ours, 'solve_cpu'):6.3f}")
    rk = res["rockit"]
    if not rk:
        return line + " | n/a (multi-phase: rockit stages not translated)"
    if "error" in rk[0]:
        return line + f" | failed: {rk[0]['error']}"
    v = med(rk, "value")
    return line + (f" | {v:>13.9g} {errors(sp, v)} | {med(rk, 'build'):5.2f} "
                   f"{med(rk, 'solve'):6.3f} {med(rk, 'solve_cpu'):6.3f}")


HEADER = (f"{'':21s} {'this toolkit':>13s} {'':17s} | refinement run      | final mesh, "
          f"median      | {'rockit':>13s} {'':17s} | same N, median\n"
          f"{'problem':21s} {'objective':>13s} {'err(pub)':>8s} {'err(exa)':>8s} | "
          f"{'wall':>6s} {'cpu':>6s} {'#m':>2s} {'N':>4s} | {'build':>5s} {'solve':>6s} "
          f"{'cpu':>6s} | {'objective':>13s} {'err(pub)':>8s} {'err(exa)':>8s} | "
          f"{'build':>5s} {'solve':>6s} {'cpu':>6s}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="problems to run (default: all)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    chosen = [p for p in PROBLEMS if not args.names or p.name in args.names]
    print(HEADER)
    for sp in chosen:
        print(report(run(sp, args.repeats)), flush=True)


if __name__ == "__main__":
    main()
