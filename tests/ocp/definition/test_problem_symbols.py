"""What a problem keeps between reads (its stacked symbols, its expressions at t0 and T)
follows the declarations made after the first read."""

import casadi as ca
import numpy as np

import ocp


def _at(expr: ca.SX, syms: list[ca.SX], values: list[float]) -> float:
    return float(ca.Function("f", [ca.vertcat(*syms)], [expr])(values))


def test_stacked_symbols_follow_later_declarations():
    p = ocp.OptimalControlProblem()
    x = p.state("x")
    assert [v.numel() for v in (p.x, p.u, p.x0, p.xT, p.u0, p.uT)] == [1, 0, 1, 1, 0, 0]
    y = p.state("y")
    u = p.control("u")
    assert [v.numel() for v in (p.x, p.u, p.x0, p.xT, p.u0, p.uT)] == [2, 1, 2, 2, 1, 1]
    assert ca.is_equal(p.x[0], x) and ca.is_equal(p.x[1], y) and ca.is_equal(p.u[0], u)


def test_end_values_are_kept_per_expression_and_end_and_stay_right():
    p = ocp.OptimalControlProblem()
    x = p.state("x")
    e = x ** 2 + p.t
    first = p.at_t0(e)
    y = p.state("y")  # declared after the first substitution
    u = p.control("u")
    assert p.at_t0(e) is first  # kept
    assert _at(first, [p.x0[0], p.t0], [3.0, 0.5]) == 9.5
    f = x * y + u - p.t
    syms0 = [*ca.vertsplit(p.x0), *ca.vertsplit(p.u0), p.t0]
    symsT = [*ca.vertsplit(p.xT), *ca.vertsplit(p.uT), p.T]
    vals = [2.0, 5.0, 7.0, 1.5]
    assert _at(p.at_t0(f), syms0, vals) == 2.0 * 5.0 + 7.0 - 1.5
    assert _at(p.at_tf(f), symsT, vals) == 2.0 * 5.0 + 7.0 - 1.5
    assert not ca.depends_on(p.at_tf(f), ca.vertcat(*syms0))  # the two ends kept apart
    assert np.isclose(float(p.at_t0(2.0)), 2.0)
