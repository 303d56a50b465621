"""Independent reference for landings on non-affine ground: scipy ``solve_ivp`` with events.

Written from the equations (the paper's robot, the drag and accreted-cone laws as stated in
``softlanding.model.ground``'s docstrings), not from the toolkit's kernel: the yielding foot obeys
``(m_f + m_a(d)) v_f' = -m_f - u + d + (c_d + m_a'(d)) v_f^2``; a foot landing at speed on the
crater bottom collides inelastically with the cone; the crater holds support forces up to
``d``. Impedance control without force limit, or the rigid leg.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def cone(depth, pi_a, radius, kappa):
    """``(m_a, m_a')`` of the accreted cone at ``depth``."""
    if pi_a == 0.0:
        return 0.0, 0.0
    dd = min(depth, radius / kappa)
    w = radius - kappa * dd
    return (pi_a * (radius**2 * dd - radius * kappa * dd**2 + kappa**2 * dd**3 / 3),
            pi_a * w * w)


def landing_ivp(v0, kp, kd, c_d=0.0, pi_a=0.0, radius=1.0, kappa=1.0, r_m=5.0, s=20.0,
                rigid=False, method="DOP853", rtol=1e-12, atol=1e-12, max_phases=200):
    """Depth, steps and first stop time of one landing by ODE integration with events."""
    mf, mb = 1 / (1 + r_m), r_m / (1 + r_m)
    l0 = s / 2

    def foot_force(y):
        d, v = -y[2], y[3]
        ma, dma = cone(d, pi_a, radius, kappa)
        return d + (c_d + dma) * v * v, ma

    def control(y):
        if rigid:
            f, ma = foot_force(y)
            return mb * (f + ma) / (1 + ma)
        return -kp * (y[0] - y[2] - l0) - kd * (y[1] - y[3])

    x = np.array([l0, v0, 0.0, v0])
    t, d, mode, steps, t_stop = 0.0, 0.0, "Y", 1, math.nan
    for _ in range(max_phases):
        def rhs(_, y, mode=mode):
            u = control(y)
            ab = -1 + u / mb
            if mode == "S":
                return [y[1], ab, 0.0, 0.0]
            if mode == "F":
                return [y[1], ab, y[3], -1 - u / mf]
            f, ma = foot_force(y)
            return [y[1], ab, y[3], (-mf + f - u) / (mf + ma)]

        if mode == "Y":
            def ev(_, y):
                return y[3]
            ev.direction = 1
            events = [ev]
        elif mode == "S":
            def ev(_, y, d=d):
                return mf + control(y) - d
            ev.direction = 1

            def lift(_, y):
                return mf + control(y)
            lift.direction = -1
            lift.terminal = True
            events = [ev, lift]
        else:
            def ev(_, y, d=d):
                return y[2] + d + 1e-10
            ev.direction = -1
            events = [ev]
        events[0].terminal = True
        if rigid and mode == "S":  # the locked leg rests: its support 1 <= d
            return {"depth": d, "steps": steps, "t_first_stop": t_stop}
        guarded = [_guard(e, t) for e in events]
        sol = solve_ivp(rhs, (t, t + (200.0 if mode == "S" else 1e3)), x, method=method,
                        rtol=rtol, atol=atol, events=guarded)
        hit = [(te[0], k) for k, te in enumerate(sol.t_events) if len(te)]
        if not hit:
            if mode == "S":
                return {"depth": d, "steps": steps, "t_first_stop": t_stop}
            raise RuntimeError("no event within the horizon")
        t, k = min(hit)
        x = sol.y_events[k][0].copy()
        if mode == "Y":
            x[3] = 0.0
            d = max(d, -x[2])
            t_stop = t if math.isnan(t_stop) else t_stop
            f = mf + control(x)
            mode = "Y" if f > d else ("F" if f < 0 else "S")
        elif mode == "S":
            mode = "Y" if k == 0 else "F"
        else:
            x[2] = -d
            mode = "Y"
            ma, _ = cone(d, pi_a, radius, kappa)
            x[3] = mf * x[3] / (mf + ma)
        steps += mode == "Y"
    raise RuntimeError("too many phases")


def _guard(event, t0, window=1e-9):
    side = -1.0 if getattr(event, "direction", 0) >= 0 else 1.0

    def g(t, y):
        return side * 1e-300 if t <= t0 + window else event(t, y)

    g.terminal = getattr(event, "terminal", False)
    g.direction = getattr(event, "direction", 0)
    return g
