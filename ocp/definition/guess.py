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

Where that default (a state with neither end fixed nor guessed, a control or a
decision variable without ``guess=``) makes the dynamics or constraints
non-finite -- ``v = 0`` in ``gamma' = -g cos(gamma) / v`` -- the solve tries
other points within the bounds, one quantity at a time (:func:`repair_default`):
its ``ref0 + ref`` and ``ref0 - ref`` when it has a scaling reference, the
quarter points of finite bounds, then +-1, +-10, +-100 clipped into the bounds;
only if none makes everything finite is the culprit named (:class:`GuessError`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

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
    sym_v = ca.vertcat(*syms) if syms else ca.SX(0, 1)
    for e, lo, hi in expr_rows:
        if not ca.is_equal(lo, hi, 10):
            continue
        # one dependency sweep for all the symbols (depends_on's, one at a time)
        deps = [i for i, d in enumerate(ca.which_depends(e, sym_v, 1, False)) if d]
        if len(deps) != 1 or deps[0] in out or ca.depends_on(e, other_v):
            continue
        s = syms[deps[0]]
        coef = ca.jacobian(e, s)
        if ca.depends_on(coef, s) or (coef.is_constant() and float(coef) == 0.0):
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


@dataclass
class DefaultChoices:
    """Quantities whose guess is a bare default, with a switch to replace it.

    Each registered quantity gets two symbols: ``use[i]`` (0 or 1) and
    ``val[i]``; its default becomes ``val[i]`` clipped into its bounds when
    ``use[i]`` is 1. The guess function takes ``use`` and ``val`` after the
    parameters, so a replacement needs no rebuild.

    Attributes
    ----------
    names : list of str
        The registered quantities.
    bounds : list
        Their bounds.
    refs : list
        Their typical sizes (or None).
    use, val : list of casadi.SX
        The switch and the replacement value of each.
    """

    names: list[str] = field(default_factory=list)
    bounds: list[tuple[ca.SX, ca.SX]] = field(default_factory=list)
    refs: list[tuple[float, float] | None] = field(default_factory=list)
    use: list[ca.SX] = field(default_factory=list)
    val: list[ca.SX] = field(default_factory=list)

    def default(self, name: str, lo: ca.SX, hi: ca.SX,
                ref: tuple[float, float] | None = None) -> ca.SX:
        """The default of a quantity (the bounds' midpoint), replaceable.

        Parameters
        ----------
        name : str
            Named in messages.
        lo, hi : SX
            Its bounds.
        ref : tuple, optional
            Its ``(ref0, ref)`` scaling reference, if the user gave one.
        """
        u, v = ca.SX.sym(f"use_{len(self.names)}"), ca.SX.sym(f"val_{len(self.names)}")
        self.names.append(name)
        self.bounds.append((lo, hi))
        self.refs.append(ref)
        self.use.append(u)
        self.val.append(v)
        return ca.if_else(u, ca.fmin(ca.fmax(v, lo), hi), midpoint(lo, hi))

    @property
    def symbols(self) -> list[ca.SX]:
        """``[use, val]`` as two column vectors."""
        return [_column(self.use), _column(self.val)]

    def bound_function(self, p: ca.SX) -> ca.Function:
        """``p -> (lower, upper)`` of every registered quantity.

        Parameters
        ----------
        p : SX
            The parameters.
        """
        lo = ca.vertcat(*[b[0] for b in self.bounds]) if self.bounds else ca.SX(0, 1)
        hi = ca.vertcat(*[b[1] for b in self.bounds]) if self.bounds else ca.SX(0, 1)
        return ca.Function("default_bounds", [p], [lo, hi])


def _column(xs: list[ca.SX]) -> ca.SX:
    return ca.SX(ca.vertcat(*xs)) if xs else ca.SX(0, 1)


def candidates(lo: float, hi: float, ref: tuple[float, float] | None) -> list[float]:
    """Replacement values to try for a default, within ``[lo, hi]``, best first.

    Parameters
    ----------
    lo, hi : float
        The bounds (possibly infinite).
    ref : tuple or None
        ``(ref0, ref)`` if the user gave a scaling reference.
    """
    out: list[float] = []
    if ref is not None:
        out += [ref[0] + ref[1], ref[0] - ref[1]]
    if math.isfinite(lo) and math.isfinite(hi):
        out += [lo + (hi - lo) / 4, lo + 3 * (hi - lo) / 4]
    out += [s * m for m in (1.0, 10.0, 100.0) for s in (1.0, -1.0)]
    seen: list[float] = []
    for v in out:
        c = min(max(v, lo), hi)
        if c not in seen:
            seen.append(c)
    return seen


def repair_default(count_nonfinite: Callable[[np.ndarray, np.ndarray], int],
                   lo: np.ndarray, hi: np.ndarray,
                   refs: list[tuple[float, float] | None]) -> tuple[np.ndarray, np.ndarray]:
    """Replace defaults, one quantity at a time, until the guess is finite.

    Greedy: for each quantity in turn, the candidate (see :func:`candidates`)
    leaving the fewest non-finite entries is kept if it improves on the current
    count; it stops as soon as nothing is non-finite.

    Parameters
    ----------
    count_nonfinite : callable
        ``(use, val) -> number of non-finite entries`` of the NLP at that guess.
    lo, hi : ndarray
        Bounds of the quantities.
    refs : list
        Their scaling references, or None.

    Returns
    -------
    use, val : ndarray
        The replacements (``use`` all 0 if none helped).
    """
    n = lo.size
    use, val = np.zeros(n), np.zeros(n)
    best = count_nonfinite(use, val)
    for i in range(n):
        if best == 0:
            break
        keep = (0.0, 0.0)
        for c in candidates(float(lo[i]), float(hi[i]), refs[i]):
            use[i], val[i] = 1.0, c
            k = count_nonfinite(use, val)
            if k < best:
                best, keep = k, (1.0, c)
        use[i], val[i] = keep
    return use, val


def fixed_ends(ph: OptimalControlProblem) -> tuple[dict[int, ca.SX], dict[int, ca.SX]]:
    """The start and end values of states that an equality fixes, by state index.

    An equality among the initial (terminal) and boundary constraints that is affine
    in one state's start (end) value and involves no other unknown fixes it
    (``x(0) = 1``, ``m(T) - m_dry = 0``); the values are SX in the parameters.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    """
    x0, xT, u0, uT = (ca.vertsplit(e) for e in (ph.x0, ph.xT, ph.u0, ph.uT))
    others_x0 = [*u0, *xT, *uT, ph.t0, ph.T, *[s for s, _ in ph.integrals], *ph.shared.vars]
    others_xT = [*u0, *x0, *uT, ph.t0, ph.T, *[s for s, _ in ph.integrals], *ph.shared.vars]
    b_rows = _rows(ph.boundary, lambda e: e)
    return (_fixed_values(_rows(ph.initial, ph.at_t0) + b_rows, x0, others_x0),
            _fixed_values(_rows(ph.terminal, ph.at_tf) + b_rows, xT, others_xT))


def state_ends(ph: OptimalControlProblem, previous: dict[str, ca.SX] | None = None,
               choices: DefaultChoices | None = None,
               fixed: tuple[dict[int, ca.SX], dict[int, ca.SX]] | None = None,
               ) -> tuple[ca.SX, ca.SX]:
    """Start and end guesses of every state (SX vectors in the parameters).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    previous : dict, optional
        End guesses of the phase this one is linked from, by state name.
    choices : DefaultChoices, optional
        Registers the states whose guess is a bare default, so that a solve
        can replace it (see :func:`repair_default`).
    fixed : tuple of dict, optional
        :func:`fixed_ends` of the phase, if already derived (a build derives the
        guesses with and without ``choices`` from one).
    """
    fix0, fixT = fixed_ends(ph) if fixed is None else fixed
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
                a = b = (midpoint(lo, hi) if choices is None else
                         choices.default(f"state {name!r} of phase {ph.name!r}", lo, hi,
                                         ph.state_ref.get(name)))
            a = b if a is None else a
            b = a if b is None else b
        starts.append(ca.fmin(ca.fmax(a, lo), hi))
        ends.append(ca.fmin(ca.fmax(b, lo), hi))
    return ca.vertcat(*starts), ca.vertcat(*ends)


def control_guess(ph: OptimalControlProblem, choices: DefaultChoices | None = None) -> ca.SX:
    """Guess of every control (SX vector in the parameters).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    choices : DefaultChoices, optional
        Registers the controls without a guess (see :func:`state_ends`).
    """
    out = []
    for name in ph.control_names:
        lo, hi = ph.control_bounds[name]
        g = ph.control_guess.get(name)
        if g is not None:
            out.append(ca.fmin(ca.fmax(g, lo), hi))
        elif choices is None:
            out.append(midpoint(lo, hi))
        else:
            out.append(choices.default(f"control {name!r} of phase {ph.name!r}", lo, hi,
                                       ph.control_ref.get(name)))
    return ca.vertcat(*out) if out else ca.SX(0, 1)


def variable_guess(shared: Shared, choices: DefaultChoices | None = None) -> ca.SX:
    """Guess of every decision variable (SX vector in the parameters).

    Parameters
    ----------
    shared : Shared
        Parameters and variables of the problem.
    choices : DefaultChoices, optional
        Registers the variables without a guess (see :func:`state_ends`).
    """
    out = []
    for name in shared.var_names:
        lo, hi = shared.var_bounds[name]
        g = shared.var_guess.get(name)
        if g is not None:
            out.append(ca.fmin(ca.fmax(g, lo), hi))
        elif choices is None:
            out.append(midpoint(lo, hi))
        else:
            out.append(choices.default(f"variable {name!r}", lo, hi, shared.var_ref.get(name)))
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
