"""Problems with known answers, shared by the ocp and PMP tests."""

from ocp import OptimalControlProblem


def min_time_double_integrator(mayer: bool = True) -> OptimalControlProblem:
    """x'' = u, |u| <= 1, rest to rest over a distance d in minimum time.

    Answer: one switch at sqrt(d), T = 2 sqrt(d). The time is minimised as a
    Mayer term ``phi = T`` or, with ``mayer=False``, as a running cost ``L = 1``.
    """
    p = OptimalControlProblem("min_time")
    x, v = p.state("x"), p.state("v")
    u = p.control("u", lower=-1, upper=1)
    d = p.parameter("d")
    p.set_dynamics({"x": v, "v": u})
    p.initial_constraint(x, 0.0)
    p.initial_constraint(v, 0.0)
    p.terminal_constraint(x - d, 0.0)
    p.terminal_constraint(v, 0.0)
    p.free_final_time(lower=0.01, upper=100, guess=2)
    if mayer:
        p.minimize_terminal(p.T)
    else:
        p.minimize_integral(1.0)
    return p
