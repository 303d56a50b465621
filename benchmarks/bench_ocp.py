"""The soft-landing OCP with this toolkit and with rockit, in one interleaved run.

Run:  pip install -e ".[bench]" && python -m benchmarks.bench_ocp [--n 20]

Same problem (the paper's, with the body-arrest conditions multiplied by the
final stroke as in softlanding.optimal.landing), same N = 100 multiple-shooting
intervals with 4 RK4 steps each, same Ipopt options, for ``--n`` values of v0
in [-10, -0.5] (r_m = 5, s = 20, u_max = 8.2), solved in order (continuation).
Two interleavings (the machine is shared: interleaving keeps load drift out of
the ratios), each timed in CPU and wall time:

1. solve by solve: at every v0 the contenders run one after the other, in an
   order that alternates from one v0 to the next. Each contender then starts
   with caches the other three have filled (rockit's and the transcription's
   large NLPs evict the re-solve's small functions: it runs about 2x slower
   than in a sweep of its own);
2. whole sweeps: each contender runs the whole sweep alone, from the same
   start, in rounds whose order alternates (ABCD, DCBA, ...), as a user's
   sweep runs.

The contenders:

* rockit ``Ocp.to_function`` (its documented fast path), warm from the previous v0;
* this toolkit's transcription, warm (primal-dual) from the previous v0;
* this toolkit's structure re-solve: the previous refined arc structure re-solved
  for the new v0 (Newton fast path, no transcription), exact arcs;
* this toolkit end to end: ``solve_landing`` in a warm sweep (structure re-solve or
  transcription + refinement, then the exact-simulator replay).

Depth errors are against the refined depth checked by the exact simulator replay.
Goals (speed issue): end-to-end <= 10 ms per v0; exact re-solve >= 50x faster than
rockit's warm ``to_function`` (which only reaches its grid error).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import casadi as ca
import numpy as np

IPOPT = {"tol": 1e-10, "max_iter": 3000, "print_level": 0, "sb": "yes",
         "mu_strategy": "adaptive"}


def rockit_problem(N: int):
    from rockit import FreeTime, MultipleShooting, Ocp

    from softlanding.model.dynamics import stance_dynamics

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
    from softlanding.optimal.landing import landing_transcription, rigid_guess

    tr = landing_transcription(N)
    w = rigid_guess(tr, PAPER_ROBOT, Impact(v0))
    T = w[0]
    X = w[tr.layout.iX].reshape(N + 1, 4)
    U = w[tr.layout.iU]
    return T, X, U, w


def timed(fn):
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c, time.perf_counter() - w


def rockit_function(N: int, v0: float, guess):
    ocp, X, u, P = rockit_problem(N)
    for p_, val in zip(P, (5.0, 20.0, v0, 8.2), strict=True):
        ocp.set_value(p_, val)
    primal = ([ocp.value(ocp.T)] + [ocp.sample(x, grid="control")[1] for x in X]
              + [ocp.sample(u, grid="control-")[1]])
    fn = ocp.to_function("landing", [ocp.value(p_) for p_ in P] + primal, primal)
    T0, Xg, Ug, _ = guess
    return fn, fn(5.0, 20.0, v0, 8.2, T0, *[Xg[:, k] for k in range(4)], Ug)


NAMES = ("rockit to_function", "toolkit transcribed", "toolkit structure re-solve",
         "toolkit solve_landing (sweep)")


def contenders(N: int, v0s, guesses):
    """The four sweeps, each as ``(start, step)``: ``step(state, v0) -> state`` re-solves
    warm from its own previous result; ``depth(name, state)`` reads the depth."""
    from ocp import MultipleShooting
    from ocp.structure.switching import refine_structure
    from softlanding import PAPER_ROBOT, Impact
    from softlanding.optimal.landing import PARAMETERS, build_landing_problem, solve_landing

    par = dict(zip(PARAMETERS, (PAPER_ROBOT.r_m, PAPER_ROBOT.s, 0.0, PAPER_ROBOT.u_max,
                                PAPER_ROBOT.rest_length), strict=True))
    # first solves (build included), one each
    (tr, first), c_ours, w_ours = timed(lambda: (lambda t: (t, t.solve(
        {**par, "v0": v0s[0]}, guess=guesses[v0s[0]][3])))(MultipleShooting(
            build_landing_problem(), nodes=N, substeps=4, ipopt_options=IPOPT, expand=True)))
    (fn, out), c_rk, w_rk = timed(lambda: rockit_function(N, v0s[0], guesses[v0s[0]]))
    land = solve_landing(v0s[0], PAPER_ROBOT)  # the sweep's first point, and the exact depth
    # the structure re-solve's NLP belongs to tr.problem: solve it once by Ipopt, untimed
    refine_structure(tr.problem, land.refined.modes, land.refined.durations,
                     Impact(v0s[0]).initial_state(PAPER_ROBOT), {**par, "v0": v0s[0]})
    steps = {
        NAMES[0]: (out, lambda o, v: fn(5.0, 20.0, v, 8.2, *o)),
        NAMES[1]: (first, lambda s, v: tr.solve({**par, "v0": v}, warm_start=s)),
        NAMES[2]: (land.refined, lambda r, v: refine_structure(
            tr.problem, r.modes, r.durations, Impact(v).initial_state(PAPER_ROBOT),
            {**par, "v0": v})),
        NAMES[3]: (land, lambda g, v: solve_landing(v, PAPER_ROBOT, warm_start=g)),
    }
    return steps, tr, (c_ours, w_ours), (c_rk, w_rk)


def depth_of(name: str, state) -> float:
    if name == NAMES[0]:
        return -float(np.array(state[3]).ravel()[-1])
    if name == NAMES[1]:
        return -state.x[-1, 2]
    if name == NAMES[2]:
        return -state.xT[2]
    return state.depth


def main() -> None:
    ap = argparse.ArgumentParser(description="soft-landing OCP: this toolkit vs rockit")
    ap.add_argument("--n", type=int, default=20, help="number of v0 values (default 20)")
    ap.add_argument("--nodes", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=4,
                    help="rounds of whole sweeps in alternating order (default 4)")
    a = ap.parse_args()
    N, v0s = a.nodes, np.linspace(-0.5, -10.0, a.n)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    guesses = {v: guess_arrays(v, N) for v in v0s}  # same first guess for both, untimed
    steps, tr, first_ours, first_rk = contenders(N, v0s, guesses)
    # (1) solve by solve: at every v0 the four run one after the other, order alternating
    times = {k: ([], []) for k in NAMES}
    depth = {k: [] for k in NAMES}
    exact = []
    state = {k: steps[k][0] for k in NAMES}
    for i, v in enumerate(v0s[1:]):
        for k in (NAMES if i % 2 == 0 else NAMES[::-1]):
            state[k], c, w = timed(lambda k=k, v=v: steps[k][1](state[k], v))
            times[k][0].append(c)
            times[k][1].append(w)
            depth[k].append(depth_of(k, state[k]))
        assert state[NAMES[3]].replay is not None
        exact.append(state[NAMES[3]].replay.depth)
    report(a, "solve by solve (each contender runs after the other three: cold caches)",
           times, depth, np.array(exact), first_ours, first_rk, tr)
    # (2) whole sweeps: each contender runs the sweep alone (warm caches, as in use),
    # the contenders' order reversed from one round to the next
    blocks = {k: ([], []) for k in NAMES}
    for rnd in range(a.rounds):
        for k in (NAMES if rnd % 2 == 0 else NAMES[::-1]):
            st = steps[k][0]
            for v in v0s[1:]:
                st, c, w = timed(lambda st=st, k=k, v=v: steps[k][1](st, v))
                blocks[k][0].append(c)
                blocks[k][1].append(w)
    report(a, f"whole sweeps, {a.rounds} rounds in alternating order (warm caches)",
           blocks, depth, np.array(exact), None, None, tr)


def report(a, title, times, depth, exact, first_ours, first_rk, tr) -> None:
    med = statistics.median
    print(f"soft-landing OCP, N={a.nodes}, RK4 x4, {a.n} values of v0 in [-10, -0.5], r_m=5, "
          f"s=20, u_max=8.2, same Ipopt options; {title}")
    if first_ours is not None:
        print(f"first solve (build included): toolkit cpu {first_ours[0]:.3f} s, wall "
              f"{first_ours[1]:.3f} s; rockit to_function cpu {first_rk[0]:.3f} s, wall "
              f"{first_rk[1]:.3f} s; ratio cpu {first_rk[0] / first_ours[0]:.1f}x")
    print(f"{'':32}{'cpu [ms]':>10}{'wall [ms]':>11}{'depth error':>13}  (medians per v0)")
    for k in NAMES:
        c, w = med(times[k][0]) * 1e3, med(times[k][1]) * 1e3
        err = float(np.max(np.abs(np.array(depth[k]) - exact)))
        print(f"{k:32}{c:>10.2f}{w:>11.2f}{err:>13.2e}")
    rk = med(times[NAMES[0]][0])
    for k in NAMES[1:]:
        print(f"speed-up vs rockit to_function (cpu): {k:30} {rk / med(times[k][0]):7.1f}x")
    print(f"NLP builds: {tr.n_builds} (re-solves never rebuild)")
    print("exact depth: the sweep's refined depth replayed in the exact simulator; rockit and "
          "the transcription carry their RK4 grid error")


if __name__ == "__main__":
    main()
