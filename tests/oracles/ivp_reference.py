"""Independent reference simulator: scipy ``solve_ivp`` with event location.

Written from the paper's equations (not from the toolkit's mode matrices) with
the same finite-state-machine logic, so that tests and the benchmark compare
the exact simulator with a second, conventional method. Supports unsaturated
or saturated impedance control and the rigid leg.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def _u(x, kp, kd, l0, umax, regime):
    if regime == 1:
        return umax
    if regime == -1:
        return -umax
    return -kp * (x[0] - x[2] - l0) - kd * (x[1] - x[3])


def _guarded(event, t0, window=1e-9):
    """The event, held on its pre-crossing side just after a restart.

    A restarted phase often begins exactly on an event surface (the foot has
    just stopped, a saturation has just switched); scipy's root bracketing
    fails on such a start, so the first ``window`` of the phase is masked.
    """
    side = -1.0 if getattr(event, "direction", 0) >= 0 else 1.0

    def g(t, y):
        return side * 1e-300 if t <= t0 + window else event(t, y)

    g.terminal = getattr(event, "terminal", False)
    g.direction = getattr(event, "direction", 0)
    return g


def landing_depth_ivp(v0, kp, kd, r_m=5.0, s=20.0, umax=math.inf, rigid=False,
                      method="LSODA", rtol=1e-10, atol=1e-12, rest_horizon=200.0,
                      max_phases=200):
    """Depth, steps and first stop time of one landing, by ODE integration.

    Returns
    -------
    dict with ``depth``, ``steps``, ``t_first_stop``.
    """
    c = (1 + r_m) / r_m
    l0 = s / 2
    x = np.array([l0, v0, 0.0, v0])
    t = 0.0
    d = 0.0
    mode = "Y" if v0 < 0 else "S"
    steps = 1 if mode == "Y" else 0
    t_first_stop = math.nan
    if rigid:
        if v0 == 0:
            mode, steps = "Y", 1

        # one body of unit mass on the one-way spring: x'' = -1 - x
        def rhs(_, y):
            return [y[1], -1.0 - y[0]]

        def stop(_, y):
            return y[1]

        stop.terminal, stop.direction = True, 1
        sol = solve_ivp(rhs, (0, 100), [0.0, v0], method=method, rtol=rtol, atol=atol,
                        events=stop)
        return {"depth": -sol.y_events[0][0][0], "steps": 1,
                "t_first_stop": sol.t_events[0][0]}

    def regime_of(y):
        ul = -kp * (y[0] - y[2] - l0) - kd * (y[1] - y[3])
        return 1 if ul > umax else (-1 if ul < -umax else 0)

    def support(y, regime):
        return 1.0 / (1 + r_m) + _u(y, kp, kd, l0, umax, regime)

    regime = regime_of(x)
    if mode == "S":
        f = support(x, regime)
        mode = "Y" if f > d else ("F" if f < 0 else "S")
        steps += mode == "Y"
    for _ in range(max_phases):
        reg = regime

        def rhs(_, y, mode=mode, reg=reg):
            u = _u(y, kp, kd, l0, umax, reg)
            ab = -1 + c * u
            if mode == "Y":
                af = -1 - (1 + r_m) * (y[2] + u)
            elif mode == "F":
                af = -1 - (1 + r_m) * u
            else:
                return [y[1], ab, 0.0, 0.0]
            return [y[1], ab, y[3], af]

        events = []
        if mode == "Y":
            def ev(_, y):
                return y[3]
            ev.direction = 1
        elif mode == "S":
            def ev(_, y, reg=reg, d=d):
                return support(y, reg) - d

            def ev_lift(_, y, reg=reg):
                return support(y, reg)
            ev.direction, ev_lift.direction, ev_lift.terminal = 1, -1, True
            events.append(ev_lift)
        else:
            def ev(_, y, d=d):
                # 1e-10 below the crater bottom, so that integrator noise at a
                # grazing lift-off is not taken for a landing
                return y[2] + d + 1e-10
            ev.direction = -1
        ev.terminal = True
        events.insert(0, ev)
        if umax < math.inf:
            def sat(_, y, reg=reg):
                ul = -kp * (y[0] - y[2] - l0) - kd * (y[1] - y[3])
                return (ul - umax) if reg == 0 else (ul - umax if reg == 1 else ul + umax)

            def sat2(_, y):
                return -kp * (y[0] - y[2] - l0) - kd * (y[1] - y[3]) + umax
            sat.terminal = sat2.terminal = True
            if reg == 0:
                sat.direction, sat2.direction = 1, -1
                events += [sat, sat2]
            else:
                sat.direction = -1 if reg == 1 else 1
                events.append(sat)
        horizon = rest_horizon if mode == "S" else 1e3
        sol = solve_ivp(rhs, (t, t + horizon), x, method=method, rtol=rtol, atol=atol,
                        events=[_guarded(e, t) for e in events])
        hit = [(te[0], k) for k, te in enumerate(sol.t_events) if len(te)]
        if not hit:
            if mode == "S":
                return {"depth": d, "steps": steps, "t_first_stop": t_first_stop}
            raise RuntimeError("no event within the horizon")
        te, k = min(hit)
        x = sol.y_events[k][0].copy()
        t = te
        n_ground = 2 if mode == "S" else 1
        if k >= n_ground:
            # saturation switch; the ground mode carries on
            regime = (1 if events[k] is sat else -1) if reg == 0 else 0  # noqa: F821
            continue
        if mode == "Y":
            x[3] = 0.0
            d = max(d, -x[2])
            if math.isnan(t_first_stop):
                t_first_stop = t
            regime = regime_of(x)
            f = support(x, regime)
            mode = "Y" if f > d else ("F" if f < 0 else "S")
        elif mode == "S":
            mode = "Y" if k == 0 else "F"
        else:
            x[2] = -d
            mode = "Y"
            if x[3] >= 0:
                x[3] = 0.0
                f = support(x, regime_of(x))
                mode = "Y" if f > d else ("F" if f < 0 else "S")
        steps += mode == "Y"
        regime = regime_of(x)
    raise RuntimeError("too many phases")
