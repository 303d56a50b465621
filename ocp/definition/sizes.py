"""Sizes of states that their bounds and default guess leave unknown (``scaling="auto"``).

A state bounded on one side only (``h >= 0``, ``v >= 0``) whose default guess
is 0 -- an initial value ``r(0) = 0``, nothing at the end -- says nothing of its
size through its bounds or its guess. The problem usually does, elsewhere:

1. **A boundary constraint on this state alone** (the other unknowns at their
   guesses) with a finite non-zero bound ``b``, such as a muzzle energy
   ``1/2 m v(0)^2 <= 4e5``: the size is the smallest ``|value|`` within the
   state's bounds at which the constraint's expression reaches ``|b|``
   (``v = 382`` m/s at the guessed mass), found on a geometric grid
   (``1e-6 .. 1e8``, steps of 2.3 %). An affine equality ``x(T) = 400`` gives 400,
   the value the default guess takes already.
2. **A link**: a state continued from the previous phase (``MultiPhaseProblem.link``,
   by name) has that state's size there.
3. **The dynamics over the phase**: in the guessed duration ``T`` a state moves
   by about ``T`` times its rate, and the rate's size at the guess is
   ``|f_i| + sum_j |df_i/dx_j| s_j + sum_k |df_i/du_k| s_k`` -- the rate plus
   what it becomes when each state and control moves by its own size ``s``
   (``h' = v sin(gamma)`` is 0 at ``gamma = 0`` but ``v * pi`` over gamma's range).
   The rate is taken at the guess's two ends, with states of guess 0 and a size
   from 1. or 2. placed at that size (``v = 382``, where ``gamma' = -g cos(gamma)/v``
   is finite). Only sizes above 1 are kept: a rate that vanishes at the guess
   says nothing (the same reason the objective is never scaled up).

Everything is evaluated at build time from numbers; a source that depends on
the problem's parameters (or on integrals) is skipped. These sizes only feed
the automatic references (:mod:`ocp.definition.scaling`), which are applied only when far
from 1, so a problem posed in normalised units keeps its NLP.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from .guess import control_guess
from .problem import OptimalControlProblem
from .symbols import constant

GRID = 10.0 ** np.arange(-6.0, 8.0 + 1e-9, 0.01)  # magnitudes tried for a boundary row


def _num(e: Any) -> float | None:
    """The float of a constant (or numeric) scalar, else None."""
    if isinstance(e, int | float):
        return float(e)
    if isinstance(e, ca.SX):  # the fast path (constant() converts through DM)
        return float(e) if e.numel() == 1 and e.is_constant() else None
    return constant(ca.SX(e))


def known_size(lo: Any, hi: Any, guess: Any, loose: Any) -> float | None:
    """Size from finite, not loose bounds, else from the guess magnitude, else None.

    Parameters
    ----------
    lo, hi : SX or float
        Bounds.
    guess : SX, float, pair or None
        Default guess (a number or a pair of numbers).
    loose : callable
        ``(lo, hi, g) -> bool``: bounds that say nothing of a magnitude.
    """
    lv, hv = _num(lo), _num(hi)
    vals = guess if isinstance(guess, tuple | list) else (guess,)
    nums = [abs(x) for x in (_num(g) for g in vals if g is not None)
            if x is not None and math.isfinite(x)]
    g = max(nums) if nums else 0.0
    if lv is not None and hv is not None and math.isfinite(lv) and math.isfinite(hv) \
            and hv > lv and not loose(lv, hv, g):
        return hv - lv
    return g if g > 0 else None


def boundary_rows(ph: OptimalControlProblem) -> list[tuple[ca.SX, Any, Any]]:
    """Every row ``(expression, lower, upper)`` of the phase's initial and terminal
    constraints, in the end-point symbols.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    """
    rows = []
    for cs, transform in ((ph.initial, ph.at_t0), (ph.terminal, ph.at_tf)):
        for c in cs:
            e = transform(c.expr)
            rows += [(e[k], c.lower[k], c.upper[k]) for k in range(e.numel())]
    return rows


def boundary_size(ph: OptimalControlProblem, i: int, rows: list[tuple[ca.SX, Any, Any]],
                  values: dict[str, float | None], lo: float, hi: float) -> float | None:
    """Size of state ``i`` from an initial or terminal constraint on it alone (rule 1).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    i : int
        The state.
    rows : list
        As returned by :func:`boundary_rows`.
    values : dict
        Numbers (or None: unknown) for the boundary symbols, by symbol name.
    lo, hi : float
        The state's bounds.
    """
    best: float | None = None
    for target in (ph.x0[i], ph.xT[i]):
        for e, lower, upper in rows:
            s = _row_size(e, lower, upper, target, ph, values, lo, hi)
            if s is not None and (best is None or s < best):
                best = s
    return best


def _row_size(e: ca.SX, lower: Any, upper: Any, target: ca.SX, ph: OptimalControlProblem,
              values: dict[str, float | None], lo: float,
              hi: float) -> float | None:
    """Smallest ``|s|`` within ``[lo, hi]`` with ``|e(s)| >= |bound|``, others fixed."""
    mags = [abs(v) for v in (_num(lower), _num(upper))
            if v is not None and math.isfinite(v) and v != 0.0]
    if not mags or not ca.depends_on(e, target):
        return None
    others = [s for s in ph.boundary_symbols() if not ca.is_equal(s, target)]
    subs = [(s, values.get(s.name())) for s in others if ca.depends_on(e, s)]
    nums = [v for _, v in subs if v is not None]
    if len(nums) < len(subs):
        return None  # depends on a parameter, an integral or another unknown
    if subs:
        e = ca.substitute(e, ca.vertcat(*[s for s, _ in subs]), ca.DM(nums))
    fn = ca.Function("row", [target], [e])
    b = max(mags)
    sizes = []
    for sign in (1.0, -1.0):
        pts = sign * GRID
        pts = pts[(pts >= lo) & (pts <= hi)]
        if pts.size == 0:
            continue
        with np.errstate(all="ignore"):
            vals = np.abs(np.array(fn.map(pts.size)(pts[None, :]), dtype=float).ravel())
        hit = np.flatnonzero(np.isfinite(vals) & (vals >= b))
        if hit.size and hit[0] > 0:  # reached from below: a crossing, not a floor
            sizes.append(abs(float(pts[hit[0]])))
    return min(sizes) if sizes else None


def dynamics_sizes(ph: OptimalControlProblem, points: Sequence[np.ndarray], u: np.ndarray,
                   statics: dict[str, float | None], sx: np.ndarray, su: np.ndarray,
                   duration: float) -> np.ndarray:
    """``duration * (|f| + |df/dx| sx + |df/du| su)``, largest over ``points`` (rule 3).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    points : sequence of ndarray
        State vectors where the rate is taken: at ``t0`` and at ``T``.
    u : ndarray
        The controls' guess.
    statics : dict
        Numbers for ``t0``, ``T`` and the decision variables (by symbol name).
    sx, su : ndarray
        Sizes of states and controls.
    duration : float
        The guessed duration of the phase.

    Returns
    -------
    ndarray
        One size per state (NaN where not finite or not computable).
    """
    out = np.full(ph.nx, np.nan)
    rhs = ph.rhs
    fixed = [ph.t0, ph.T, *ph.shared.vars]
    if ca.depends_on(rhs, ph.p) or any(statics.get(s.name()) is None for s in fixed):
        return out
    xu = ca.vertcat(ph.x, ph.u)
    jac = ca.jacobian(rhs, xu)
    fn = ca.Function("rate", [ph.x, ph.u, ph.t, ca.vertcat(*fixed)], [rhs, jac])
    sv = np.array([statics[s.name()] for s in fixed], dtype=float)
    size = np.concatenate([sx, su])
    for x, t in zip(points, sv[:2], strict=False):  # fixed starts with t0, T
        with np.errstate(all="ignore"):
            f, J = (np.array(a, dtype=float) for a in fn(x, u, t, sv))
        rate = np.abs(f.ravel()) + np.abs(J).reshape(ph.nx, -1) @ size
        ok = np.isfinite(rate)
        out[ok] = np.fmax(out[ok], duration * rate[ok])
    return out


def phase_state_sizes(ph: OptimalControlProblem, starts: ca.SX, ends: ca.SX,
                      times: tuple[float, float], var_guess: ca.SX,
                      linked: dict[str, float] | None, loose: Any) -> list[float | None]:
    """Size of every state of a phase whose bounds and guess say nothing (else None).

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    starts, ends : SX
        The states' default guesses at both ends (without guess repair).
    times : tuple
        Guessed ``(t0, T)`` of the phase.
    var_guess : SX
        Guess of the decision variables.
    linked : dict or None
        Sizes of the states of the phase this one is linked from, by name.
    loose : callable
        ``(lo, hi, g) -> bool`` (see :mod:`ocp.definition.scaling`).
    """
    a = [_num(starts[i]) for i in range(ph.nx)]
    b = [_num(ends[i]) for i in range(ph.nx)]
    known = [known_size(*ph.state_bounds[n], (a[i], b[i]), loose)
             for i, n in enumerate(ph.state_names)]
    out: list[float | None] = [None] * ph.nx
    todo = [i for i, n in enumerate(ph.state_names)
            if known[i] is None and ph.state_ref.get(n) is None]
    if not todo:  # the common case: nothing more to evaluate
        return out
    ug = control_guess(ph)
    u = [_num(ug[k]) for k in range(ph.nu)]
    vg = [_num(var_guess[k]) for k in range(var_guess.numel())]
    statics: dict[str, float | None] = {ph.t0.name(): times[0], ph.T.name(): times[1]}
    statics |= {s.name(): v for s, v in zip(ph.shared.vars, vg, strict=True)}
    values = dict(statics)
    for syms, vals in ((ph.x0, a), (ph.xT, b), (ph.u0, u), (ph.uT, u)):
        values |= {s.name(): v for s, v in zip(ca.vertsplit(syms), vals, strict=True)}
    bounds = [_float_bounds(*ph.state_bounds[n]) for n in ph.state_names]
    rows = boundary_rows(ph)
    for i in todo:
        out[i] = boundary_size(ph, i, rows, values, *bounds[i])
        if out[i] is None and linked is not None:
            out[i] = linked.get(ph.state_names[i])
    _from_dynamics(ph, out, known, (a, b), u, statics, bounds, times[1] - times[0])
    return out


def _from_dynamics(ph: OptimalControlProblem, out: list[float | None],
                   known: list[float | None], ends: tuple[list, list], u: list,
                   statics: dict[str, float | None], bounds: list[tuple[float, float]],
                   duration: float) -> None:
    """Rule 3 for the states still without a size (in place), keeping sizes above 1."""
    todo = [i for i in range(ph.nx) if out[i] is None and known[i] is None
            and ph.state_ref.get(ph.state_names[i]) is None]
    if not todo or duration <= 0 or any(v is None for v in u) \
            or any(v is None for e in ends for v in e):
        return
    sx = np.array([k if k is not None else (o if o is not None else 1.0)
                   for k, o in zip(known, out, strict=True)])
    su = np.array([known_size(*ph.control_bounds[n], ph.control_guess.get(n), _never) or 1.0
                   for n in ph.control_names])
    points = []
    for e in ends:
        x = np.array(e, dtype=float)
        for j in range(ph.nx):  # a state at 0 with a size from rules 1-2: at that size
            sj = out[j]
            if x[j] == 0.0 and sj is not None:
                lo, hi = bounds[j]
                x[j] = min(max(sj if hi > 0 else -sj, lo), hi)
        points.append(x)
    sizes = dynamics_sizes(ph, points, np.array(u, dtype=float), statics, sx, su, duration)
    for i in todo:
        if math.isfinite(sizes[i]) and sizes[i] > 1.0:
            out[i] = float(sizes[i])


def _float_bounds(lo: Any, hi: Any) -> tuple[float, float]:
    """Numeric bounds, a symbolic one (a parameter) taken as absent."""
    lv, hv = _num(lo), _num(hi)
    return (-math.inf if lv is None else lv), (math.inf if hv is None else hv)


def _never(*_: float) -> bool:
    return False


def transfer_time(ph: OptimalControlProblem, x_start: np.ndarray, x_end: np.ndarray,
                  u: np.ndarray, times: tuple[float, float], var_values: Sequence[float],
                  loose: Any) -> float | None:
    """The time the dynamics need for the change the guess asks of the states.

    For every state whose guessed start and end differ (boundary values, a
    transfer), ``|x_end - x_start|`` divided by the size of its rate at the
    guess's ends (rule 3 of the module: ``|f| + |df/dx| s_x + |df/du| s_u``,
    each state and control at its size ``s`` from bounds or guess, else 1);
    the largest over the states. It is a time scale of the problem that its
    bounds (``free_final_time()``'s default spans six decades) do not give.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    x_start, x_end : ndarray
        The states' guess at the phase's start and end.
    u : ndarray
        The controls' guess.
    times : tuple
        Guessed ``(t0, T)``.
    var_values : sequence of float
        The decision variables' guess.
    loose : callable
        ``(lo, hi, g) -> bool`` (see :mod:`ocp.definition.scaling`).

    Returns
    -------
    float or None
        The time, or None when no state changes or a rate cannot be evaluated
        (dynamics that depend on parameters).
    """
    a, b = np.asarray(x_start, dtype=float), np.asarray(x_end, dtype=float)
    change = np.abs(b - a)
    if not np.any(change > 0):
        return None
    sx = np.array([known_size(*ph.state_bounds[n], (float(a[i]), float(b[i])), loose) or 1.0
                   for i, n in enumerate(ph.state_names)])
    su = np.array([known_size(*ph.control_bounds[n], ph.control_guess.get(n), _never) or 1.0
                   for n in ph.control_names])
    statics: dict[str, float | None] = {ph.t0.name(): times[0], ph.T.name(): times[1]}
    var_syms = ca.vertsplit(ph.v) if ph.v.numel() else []
    statics |= {s.name(): float(v) for s, v in zip(var_syms, var_values, strict=True)}
    rates = dynamics_sizes(ph, [a, b], np.asarray(u, dtype=float), statics, sx, su, 1.0)
    ok = (change > 0) & np.isfinite(rates) & (rates > 0)
    return float(np.max(change[ok] / rates[ok])) if np.any(ok) else None
