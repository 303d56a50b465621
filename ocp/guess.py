"""Default initial guesses, and a clear error when a guess makes the problem non-finite.

For each state the guess is a straight line in time between a start and an end
value: the user's ``guess=`` if given; otherwise the values the initial and
terminal constraints fix (an equality in that one state, affine in it, such as
``x(0) = 1`` or ``m(T) - m_dry = 0``); otherwise, for a phase linked to a
previous one, that phase's end value; otherwise the midpoint of finite bounds,
or 0 clipped into the bounds. Controls and decision variables take their
``guess=``, else the midpoint of finite bounds, else 0 clipped into them. All
of these are symbolic in the parameters, so the guess follows new parameter
values without a rebuild.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import casadi as ca
import numpy as np

from .compiled import CompiledPhase
from .errors import GuessError
from .problem import OptimalControlProblem, Shared
from .symbols import Constraint, constant


def _fixed_values(expr_rows: list[tuple[ca.SX, ca.SX, ca.SX]], syms: Sequence[ca.SX],
                  others: Sequence[ca.SX]) -> dict[int, ca.SX]:
    """Values of ``syms[i]`` fixed by an equality affine in that symbol alone."""
    out: dict[int, ca.SX] = {}
    other_v = ca.vertcat(*others) if others else ca.SX(0, 1)
    for e, lo, hi in expr_rows:
        if not ca.is_equal(lo, hi, 10):
            continue
        deps = [i for i, s in enumerate(syms) if ca.depends_on(e, s)]
        if len(deps) != 1 or deps[0] in out or ca.depends_on(e, other_v):
            continue
        s = syms[deps[0]]
        coef = ca.jacobian(e, s)
        if ca.depends_on(coef, s) or (coef.is_constant() and float(ca.DM(coef)) == 0.0):
            continue
        out[deps[0]] = (lo - ca.substitute(e, s, ca.SX(0))) / coef
    return out


def _rows(cs: list[Constraint], transform) -> list[tuple[ca.SX, ca.SX, ca.SX]]:
    rows = []
    for c in cs:
        e = transform(c.expr)
        rows += [(e[i], c.lower[i], c.upper[i]) for i in range(e.numel())]
    return rows


def midpoint(lo: ca.SX, hi: ca.SX) -> ca.SX:
    """Midpoint of finite bounds, else 0 clipped into them (symbolic in the parameters).

    Parameters
    ----------
    lo, hi : SX
        The bounds.
    """
    lc, hc = constant(lo), constant(hi)
    lo_fin = lc is None or math.isfinite(lc)
    hi_fin = hc is None or math.isfinite(hc)
    if lo_fin and hi_fin:
        return (lo + hi) / 2
    return ca.fmin(ca.fmax(ca.SX(0), lo), hi)


def state_ends(ph: OptimalControlProblem,
               previous: dict[str, ca.SX] | None = None) -> tuple[ca.SX, ca.SX]:
    """Start and end guesses of every state (SX vectors in the parameters).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    previous : dict, optional
        End guesses of the phase this one is linked from, by state name.
    """
    others_x0 = [*ph._u0, *ph._xT, *ph._uT, ph.t0, ph.T, *[s for s, _ in ph.integrals],
                 *ph._shared.vars]
    others_xT = [*ph._u0, *ph._x0, *ph._uT, ph.t0, ph.T, *[s for s, _ in ph.integrals],
                 *ph._shared.vars]
    b_rows = _rows(ph.boundary, lambda e: e)
    fix0 = _fixed_values(_rows(ph.initial, ph.at_t0) + b_rows, ph._x0, others_x0)
    fixT = _fixed_values(_rows(ph.terminal, ph.at_tf) + b_rows, ph._xT, others_xT)
    starts, ends = [], []
    for i, name in enumerate(ph.state_names):
        lo, hi = ph.state_bounds[name]
        g = ph.state_guess.get(name)
        if isinstance(g, tuple):
            a, b = g
        elif g is not None:
            a = b = g
        else:
            a, b = fix0.get(i), fixT.get(i)
            if a is None and previous is not None and name in previous:
                a = previous[name]
            if a is None and b is None:
                a = b = midpoint(lo, hi)
            a = b if a is None else a
            b = a if b is None else b
        starts.append(ca.fmin(ca.fmax(a, lo), hi))
        ends.append(ca.fmin(ca.fmax(b, lo), hi))
    return ca.vertcat(*starts), ca.vertcat(*ends)


def control_guess(ph: OptimalControlProblem) -> ca.SX:
    """Guess of every control (SX vector in the parameters).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    """
    out = []
    for name in ph.control_names:
        lo, hi = ph.control_bounds[name]
        g = ph.control_guess.get(name)
        out.append(midpoint(lo, hi) if g is None else ca.fmin(ca.fmax(g, lo), hi))
    return ca.vertcat(*out) if out else ca.SX(0, 1)


def variable_guess(shared: Shared) -> ca.SX:
    """Guess of every decision variable (SX vector in the parameters).

    Parameters
    ----------
    shared : Shared
        Parameters and variables of the problem.
    """
    out = []
    for name in shared.var_names:
        lo, hi = shared.var_bounds[name]
        g = shared.var_guess.get(name)
        out.append(midpoint(lo, hi) if g is None else ca.fmin(ca.fmax(g, lo), hi))
    return ca.vertcat(*out) if out else ca.SX(0, 1)


def diagnose_nonfinite(cp: CompiledPhase, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                       s: np.ndarray) -> str | None:
    """Name the first expression of a phase that is not finite at the guess points.

    Parameters
    ----------
    cp : CompiledPhase
        The phase's functions.
    t : ndarray, shape (n,)
        Times of the guess points.
    x : ndarray, shape (n, nx)
        Guessed states there.
    u : ndarray, shape (n, nu)
        Guessed controls there.
    s : ndarray, shape (ns,)
        Static vector (parameters, variables, t0, T).

    Returns
    -------
    str or None
        A message, or None if everything is finite.
    """
    ph = cp.phase
    exprs = [(f"dynamics of state {n!r}", ph.rhs[i]) for i, n in enumerate(ph.state_names)]
    exprs += [("running cost", ph.lagrange)]
    exprs += [(f"integrand of {s_}", e) for s_, e in ph.integrals]
    exprs += [(f"path constraint {c.name!r}", c.expr) for c in ph.path]
    fn = ca.Function("diag", [ph.t, ph.x, ph.u, cp.s], [ca.vertcat(*[e for _, e in exprs])])
    vals = np.array(fn.map(len(t))(t[None, :], x.T, u.T, s), dtype=float)
    row = 0
    for name, e in exprs:
        k = e.numel()
        bad = ~np.isfinite(vals[row:row + k]).all(axis=0)
        if bad.any():
            j = int(np.argmax(bad))
            at = ", ".join(f"{n}={x[j, i]:.4g}" for i, n in enumerate(ph.state_names))
            at += "".join(f", {n}={u[j, i]:.4g}" for i, n in enumerate(ph.control_names))
            return (f"phase {ph.name!r}: the initial guess makes the {name} non-finite: "
                    f"{e} at t={t[j]:.4g} ({at}); give a guess (state(..., guess=), "
                    f"control(..., guess=)), bounds, or a guess= to solve()")
        row += k
    return None


def raise_if_nonfinite(messages: list[str | None]) -> None:
    """Raise a :class:`GuessError` with the first message, if any.

    Parameters
    ----------
    messages : list of str or None
        One per phase, as returned by ``diagnose_nonfinite``.
    """
    for m in messages:
        if m is not None:
            raise GuessError(m)
