"""The soft-landing OCP with this toolkit and with rockit, in one run.

Run:  pip install -e ".[bench]" && python benchmarks/bench_ocp.py [--n 20]

Same problem (the paper's, with the body-arrest conditions multiplied by the
final stroke as in softlanding.landing), same N = 100 multiple-shooting
intervals with 4 RK4 steps each, same Ipopt options, same initial guess (the
rigid-leg landing) at every v0, for ``--n`` values of v0 in [-10, -0.5]
(r_m = 5, s = 20, u_max = 8.2). Prints for each tool: first solve (build
included), median re-solve at a new v0, and the depth error against the
refined, exact depth (checked against the exact simulator replay). rockit is
timed two ways, its plain ``Ocp.solve()`` with ``set_value`` and its
documented fast path ``Ocp.to_function``; the ratios use rockit's faster one.
Goals (issue 3): median re-solve >= 5x faster than rockit; first solve >= 3x;
refined depth error <= 1e-9.
"""

from __future__ import annotations

import argparse
import statistics
import time

import casadi as ca
import numpy as np

IPOPT = {"tol": 1e-10, "max_iter": 3000, "print_level": 0, "sb": "yes",
         "mu_strategy": "adaptive"}


def rockit_problem(N: int):
    from rockit import FreeTime, MultipleShooting, Ocp

    from softlanding.dynamics import stance_dynamics

    ocp = Ocp(T=FreeTime(0.5))
    xb, vb, xf, vf = (ocp.state() for _ in range(4))
    u = ocp.control()
    r_m, s, v0, umax = (ocp.parameter() for _ in range(4))
    rhs = stance_dynamics(ca.vertcat(xb, vb, xf, vf), u, r_m)
    for k, x in enumerate((xb, vb, xf, vf)):
        ocp.set_der(x, rhs[k])
    ocp.subject_to(-umax <= (u <= umax))
    ocp.subject_to(0 <= (xb - xf <= s))
    ocp.subject_to(vf <= 0)
    ocp.subject_to(ocp.at_t0(xb) == s / 2)
    ocp.subject_to(ocp.at_t0(vb) == v0)
    ocp.subject_to(ocp.at_t0(xf) == 0)
    ocp.subject_to(ocp.at_t0(vf) == v0)
    ocp.subject_to(ocp.at_tf(vf) == 0)
    st = ocp.at_tf(xb) - ocp.at_tf(xf)
    mb = r_m / (1 + r_m)
    ocp.subject_to(st * (-ocp.at_tf(xf) - 1 / (1 + r_m)) - mb * (st + ocp.at_tf(vb) ** 2 / 2) >= 0)
    ocp.subject_to(st * umax - mb * (st + ocp.at_tf(vb) ** 2 / 2) >= 0)
    ocp.subject_to(ocp.T >= 1e-3)
    ocp.subject_to(ocp.T <= 30)
    ocp.add_objective(-ocp.at_tf(xf))
    ocp.solver("ipopt", {"ipopt": IPOPT, "print_time": False, "expand": True})
    ocp.method(MultipleShooting(N=N, M=4, intg="rk"))
    return ocp, (xb, vb, xf, vf), u, (r_m, s, v0, umax)


def guess_arrays(v0: float, N: int):
    from softlanding import PAPER_ROBOT, Impact
    from softlanding.landing import landing_transcription, rigid_guess

    tr = landing_transcription(N)
    w = rigid_guess(tr, PAPER_ROBOT, Impact(v0))
    T = w[0]
    X = w[tr.layout.iX].reshape(N + 1, 4)
    U = w[tr.layout.iU]
    return T, X, U, w


def main() -> None:
    ap = argparse.ArgumentParser(description="soft-landing OCP: this toolkit vs rockit")
    ap.add_argument("--n", type=int, default=20, help="number of v0 values (default 20)")
    ap.add_argument("--nodes", type=int, default=100)
    a = ap.parse_args()
    N = a.nodes
    v0s = np.linspace(-0.5, -10.0, a.n)
    guesses = {v: guess_arrays(v, N) for v in v0s}  # same guess for both tools, untimed

    # ---------------------------------------------------------------- toolkit
    from ocp import MultipleShooting
    from softlanding import PAPER_ROBOT
    from softlanding.landing import build_landing_problem, solve_landing

    par = {"r_m": PAPER_ROBOT.r_m, "s": PAPER_ROBOT.s, "u_max": PAPER_ROBOT.u_max,
           "l0": PAPER_ROBOT.rest_length}
    t = time.perf_counter()
    tr = MultipleShooting(build_landing_problem(), nodes=N, substeps=4, ipopt_options=IPOPT,
                          expand=True)
    ours = [tr.solve({**par, "v0": v0s[0]}, guess=guesses[v0s[0]][3])]
    first_ours = time.perf_counter() - t
    cold_ours, warm_ours, warm_sols = [], [], [ours[0]]
    for v in v0s[1:]:
        t = time.perf_counter()
        ours.append(tr.solve({**par, "v0": v}, guess=guesses[v][3]))
        cold_ours.append(time.perf_counter() - t)
        t = time.perf_counter()
        warm_sols.append(tr.solve({**par, "v0": v}, warm_start=warm_sols[-1]))
        warm_ours.append(time.perf_counter() - t)
    assert tr.n_builds == 1

    # exact reference: refined switching times, checked by the simulator replay
    exact, replay_gap = [], []
    for v in v0s:
        r = solve_landing(v)
        exact.append(r.depth)
        replay_gap.append(r.replay_difference)
    exact = np.array(exact)
    depth_ours = np.array([-s.x[-1, 2] for s in ours])
    depth_warm = np.array([-s.x[-1, 2] for s in warm_sols])

    # ----------------------------------------------------------------- rockit
    t = time.perf_counter()
    ocp, X, u, P = rockit_problem(N)
    depth_rk, times_rk = [], []
    for i, v in enumerate(v0s[:5]):  # the plain path is slow; five solves give its median
        T0, Xg, Ug, _ = guesses[v]
        t1 = time.perf_counter()
        for p_, val in zip(P, (5.0, 20.0, v, 8.2), strict=True):
            ocp.set_value(p_, val)
        ocp.set_initial(ocp.T, T0)
        for k, x in enumerate(X):
            ocp.set_initial(x, Xg[:, k])
        ocp.set_initial(u, Ug)
        sol = ocp.solve()
        depth_rk.append(-float(sol.value(ocp.at_tf(X[2]))))
        if i == 0:
            first_rk = time.perf_counter() - t
        else:
            times_rk.append(time.perf_counter() - t1)
    t = time.perf_counter()
    ocp2, X2, u2, P2 = rockit_problem(N)
    for p_, val in zip(P2, (5.0, 20.0, v0s[0], 8.2), strict=True):
        ocp2.set_value(p_, val)
    primal = ([ocp2.value(ocp2.T)] + [ocp2.sample(x, grid="control")[1] for x in X2]
              + [ocp2.sample(u2, grid="control-")[1]])
    fn = ocp2.to_function("landing", [ocp2.value(p_) for p_ in P2] + primal, primal)
    depth_fn, cold_fn, warm_fn = [], [], []
    prev = None
    for i, v in enumerate(v0s):
        T0, Xg, Ug, _ = guesses[v]
        t1 = time.perf_counter()
        out = fn(5.0, 20.0, v, 8.2, T0, *[Xg[:, k] for k in range(4)], Ug)
        dt = time.perf_counter() - t1
        depth_fn.append(-float(np.array(out[3]).ravel()[-1]))
        if i == 0:
            first_fn = time.perf_counter() - t
        else:
            cold_fn.append(dt)
            t1 = time.perf_counter()
            fn(5.0, 20.0, v, 8.2, *prev)
            warm_fn.append(time.perf_counter() - t1)
        prev = out
    depth_fn = np.array(depth_fn)

    med = statistics.median
    err = lambda d: float(np.max(np.abs(np.asarray(d) - exact[:len(d)])))  # noqa: E731
    print(f"soft-landing OCP, N={N}, RK4 x4, {a.n} values of v0 in [-10, -0.5], r_m=5, s=20, "
          "u_max=8.2, same Ipopt options")
    print(f"{'':30}{'first solve':>12}{'re-solve, cold':>16}{'re-solve, warm':>16}"
          f"{'depth error':>13}")
    print(f"{'':30}{'[s]':>12}{'median [s]':>16}{'median [s]':>16}{'(max)':>13}")
    print(f"{'this toolkit (transcribed)':30}{first_ours:>12.3f}{med(cold_ours):>16.4f}"
          f"{med(warm_ours):>16.4f}{max(err(depth_ours), err(depth_warm)):>13.2e}")
    print(f"{'this toolkit (refined)':30}{'':>12}{'':>16}{'':>16}{max(replay_gap):>13.2e}"
          "  vs exact simulator replay")
    print(f"{'rockit Ocp.solve+set_value':30}{first_rk:>12.3f}{med(times_rk):>16.4f}{'-':>16}"
          f"{err(depth_rk):>13.2e}  ({len(depth_rk)} solves)")
    print(f"{'rockit Ocp.to_function':30}{first_fn:>12.3f}{med(cold_fn):>16.4f}"
          f"{med(warm_fn):>16.4f}{err(depth_fn):>13.2e}")
    print("warm: from the previous v0's solution (this toolkit: primal and dual, Ipopt warm "
          "start; rockit: primal, its documented pattern)")
    best_first = min(first_rk, first_fn)
    print(f"speed-up, first solve (vs rockit's faster path): {best_first / first_ours:6.1f}x")
    print(f"speed-up, median cold re-solve (vs to_function): {med(cold_fn) / med(cold_ours):6.1f}x")
    print(f"speed-up, median warm re-solve (vs to_function): {med(warm_fn) / med(warm_ours):6.1f}x")
    print(f"speed-up, median re-solve vs rockit Ocp.solve : {med(times_rk) / med(warm_ours):6.1f}x")
    print("depth error of a transcription is its RK4/grid error (max over v0 against the "
          "refined depth); the refined depth is exact to rounding")


if __name__ == "__main__":
    main()
