"""Problems with known answers, shared by the ocp and PMP tests."""

from ocp import OptimalControlProblem


def min_time_double_integrator(mayer: bool = True, umax: float = 1.0,
                               T_guess: float | None = 2.0, refs: dict | None = None,
                               name: str = "min_time") -> OptimalControlProblem:
    """x'' = u, |u| <= umax, rest to rest over a distance d in minimum time (the README's).

    Answer: one switch at sqrt(d / umax), T = 2 sqrt(d / umax). The time is minimised
    as a Mayer term ``phi = T`` or, with ``mayer=False``, as a running cost ``L = 1``.
    ``T_guess`` None keeps the default guess of T; ``refs`` gives keyword arguments
    (``ref``/``ref0``) per name ``x``, ``v``, ``u``, ``objective``.
    """
    refs = refs or {}
    p = OptimalControlProblem(name)
    x, v = p.state("x", **refs.get("x", {})), p.state("v", **refs.get("v", {}))
    u = p.control("u", lower=-umax, upper=umax, **refs.get("u", {}))
    d = p.parameter("d")
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - d, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(lower=0.01, upper=100, **({} if T_guess is None else {"guess": T_guess}))
    if mayer:
        p.minimize_terminal(p.T, **refs.get("objective", {}))
    else:
        p.minimize_integral(1.0, **refs.get("objective", {}))
    return p
