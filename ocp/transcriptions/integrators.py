"""Integrators of one shooting interval (RK4 and CVODES), as CasADi Functions.

The canonical form used by the transcriptions is
``F(x, u, t, h, s) -> (xf, qf, xs)``: from state ``x`` at time ``t``, hold the
control ``u`` for a duration ``h``, with the static vector ``s`` (parameters,
decision variables, ``t0``, ``T``); ``qf`` integrates the quadratures (running
cost and integral-constraint integrands) and ``xs`` holds the states at the
inner integration steps (``t + j h / M``, ``j = 1..M-1``), where path
constraints can be imposed between nodes.

:func:`rk4_function` and :func:`cvodes_function` keep the older autonomous
signature ``F(x, u, h, p) -> (xf, qf)``.
"""

from __future__ import annotations

import casadi as ca


def rk4_function(f: ca.Function, L: ca.Function, nx: int, nu: int, np_: int,
                 substeps: int) -> ca.Function:
    """One shooting interval of length ``h`` by ``substeps`` RK4 steps; also integrates L.

    Parameters
    ----------
    f : casadi.Function
        ``f(x, u, p) -> x'``.
    L : casadi.Function
        ``L(x, u, p)``, the running cost.
    nx, nu, np_ : int
        Numbers of states, controls and parameters.
    substeps : int
        RK4 steps per interval.

    Returns
    -------
    casadi.Function
        ``F(x, u, h, p) -> (xf, qf)``.
    """
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", nu)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", np_)
    dt = h / substeps
    xk, q = x, ca.SX(0)
    for _ in range(substeps):
        k1, l1 = f(xk, u, p), L(xk, u, p)
        k2, l2 = f(xk + dt / 2 * k1, u, p), L(xk + dt / 2 * k1, u, p)
        k3, l3 = f(xk + dt / 2 * k2, u, p), L(xk + dt / 2 * k2, u, p)
        k4, l4 = f(xk + dt * k3, u, p), L(xk + dt * k3, u, p)
        xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q = q + dt / 6 * (l1 + 2 * l2 + 2 * l3 + l4)
    return ca.Function("F", [x, u, h, p], [xk, q], ["x", "u", "h", "p"], ["xf", "qf"])


def cvodes_function(f: ca.Function, L: ca.Function, nx: int, nu: int, np_: int,
                    tol: float = 1e-10) -> ca.Function:
    """One shooting interval by CVODES (BDF, for stiff variants), time scaled to [0, 1].

    Parameters
    ----------
    f, L : casadi.Function
        Dynamics ``f(x, u, p)`` and running cost ``L(x, u, p)``.
    nx, nu, np_ : int
        Numbers of states, controls and parameters.
    tol : float
        Absolute and relative tolerance.

    Returns
    -------
    casadi.Function
        ``F(x, u, h, p) -> (xf, qf)``.
    """
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", nu)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", np_)
    dae = {"x": x, "p": ca.vertcat(u, h, p), "ode": h * f(x, u, p), "quad": h * L(x, u, p)}
    integ = ca.integrator("I", "cvodes", dae, 0.0, 1.0, {"abstol": tol, "reltol": tol})
    xm, um, hm, pm = (ca.MX.sym(n, k) for n, k in (("x", nx), ("u", nu), ("h", 1), ("p", np_)))
    r = integ(x0=xm, p=ca.vertcat(um, hm, pm))
    return ca.Function("F", [xm, um, hm, pm], [r["xf"], r["qf"]],
                       ["x", "u", "h", "p"], ["xf", "qf"])


def rk4_interval(ode: ca.Function, substeps: int) -> ca.Function:
    """One interval by ``substeps`` RK4 steps, non-autonomous, with inner states.

    Parameters
    ----------
    ode : casadi.Function
        ``ode(t, x, u, s) -> (xdot, qdot)``.
    substeps : int
        RK4 steps per interval (M).

    Returns
    -------
    casadi.Function
        ``F(x, u, t, h, s) -> (xf, qf, xs)`` with ``xs`` of shape (nx, M - 1).
    """
    nx, nu, ns = ode.size1_in(1), ode.size1_in(2), ode.size1_in(3)
    nq = ode.size1_out(1)
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    t, h, s = ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("s", ns)
    dt = h / substeps
    xk, q, inner = x, ca.SX.zeros(nq), []
    for j in range(substeps):
        tj = t + j * dt
        k1, l1 = ode(tj, xk, u, s)
        k2, l2 = ode(tj + dt / 2, xk + dt / 2 * k1, u, s)
        k3, l3 = ode(tj + dt / 2, xk + dt / 2 * k2, u, s)
        k4, l4 = ode(tj + dt, xk + dt * k3, u, s)
        xk = xk + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q = q + dt / 6 * (l1 + 2 * l2 + 2 * l3 + l4)
        if j < substeps - 1:
            inner.append(xk)
    xs = ca.horzcat(*inner) if inner else ca.SX(nx, 0)
    return ca.Function("F", [x, u, t, h, s], [xk, q, xs], ["x", "u", "t", "h", "s"],
                       ["xf", "qf", "xs"])


def cvodes_interval(ode: ca.Function, substeps: int, tol: float = 1e-10) -> ca.Function:
    """One interval by CVODES, non-autonomous; outputs as :func:`rk4_interval`.

    Parameters
    ----------
    ode : casadi.Function
        ``ode(t, x, u, s) -> (xdot, qdot)``.
    substeps : int
        Number of equal sub-steps whose inner end states are reported (``xs``).
    tol : float
        Absolute and relative tolerance.

    Returns
    -------
    casadi.Function
        ``F(x, u, t, h, s) -> (xf, qf, xs)``.
    """
    nx, nu, ns = ode.size1_in(1), ode.size1_in(2), ode.size1_in(3)
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    t, h, s = ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("s", ns)
    tau = ca.SX.sym("tau")
    xdot, qdot = ode(t + h * tau, x, u, s)
    dae = {"t": tau, "x": x, "p": ca.vertcat(u, t, h, s), "ode": h * xdot, "quad": h * qdot}
    grid = [j / substeps for j in range(1, substeps + 1)]
    integ = ca.integrator("I", "cvodes", dae, 0.0, grid, {"abstol": tol, "reltol": tol})
    xm, um = ca.MX.sym("x", nx), ca.MX.sym("u", nu)
    tm, hm, sm = ca.MX.sym("t"), ca.MX.sym("h"), ca.MX.sym("s", ns)
    r = integ(x0=xm, p=ca.vertcat(um, tm, hm, sm))
    xf, qf = r["xf"], r["qf"]
    return ca.Function("F", [xm, um, tm, hm, sm], [xf[:, -1], qf[:, -1], xf[:, :-1]],
                       ["x", "u", "t", "h", "s"], ["xf", "qf", "xs"])
