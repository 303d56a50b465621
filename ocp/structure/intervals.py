"""The intervals of a switching-time refinement (:mod:`ocp.structure.refinement`): each
interval's closed-loop dynamics (cached per problem and modes), its flow as a CasADi
expression of the durations (exact matrix exponential on affine arcs, fixed RK8 steps
otherwise), the constraint rows it adds (entry conditions, path samples, law bounds), the
sub-steps a guess needs and the check that constant controls lie in the control set."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..definition.symbols import INF, constant
from .constraint_kinds import control_constraints
from .control_set import violated_control_constraint
from .flows import (
    ArcDynamics,
    Mode,
    expm_taylor,
    has_running_cost,
    numeric_affine_flow,
    numeric_rk8_flow,
    rk8_step_function,
    rk8_steps_for,
)

__all__ = ["DEFAULT_TOL", "ConstraintBlocks", "Modes", "arc_dynamics", "build_intervals",
           "check_control_set", "forget_arc_dynamics", "interval_flow", "required_substeps",
           "rk8_of"]

DEFAULT_TOL = 1e-12
"""Requested relative accuracy of the non-affine arcs' end states (RK8 steps)."""

Modes = tuple[tuple[Mode, ...], ...]

_DYN_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def arc_dynamics(problem: OptimalControlProblem, modes: tuple[Mode, ...]) -> ArcDynamics:
    """The :class:`~ocp.structure.flows.ArcDynamics` of ``modes``, built once per problem
    and cached.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of Mode
        One per control.

    Returns
    -------
    ArcDynamics
    """
    per = _DYN_CACHE.setdefault(problem, {})
    if modes not in per:
        per[modes] = ArcDynamics(problem, modes)
    return per[modes]


def forget_arc_dynamics(problem: OptimalControlProblem | None = None) -> None:
    """Forget the cached :func:`arc_dynamics` (of one problem, or all).

    Parameters
    ----------
    problem : OptimalControlProblem, optional
        Forget only this problem's (default: all).
    """
    if problem is None:
        _DYN_CACHE.clear()
    else:
        _DYN_CACHE.pop(problem, None)


class _Rk8:
    """RK8 step function and its ``mapaccum`` variants of one arc mode (cached)."""

    def __init__(self, dyn: ArcDynamics) -> None:
        self.step = rk8_step_function(dyn.f_z, dyn.nz, dyn.problem.np)


def rk8_of(dyn: ArcDynamics) -> ca.Function:
    """The RK8 step function ``(z, h, p) -> z_next`` of an arc mode (cached on it).

    Parameters
    ----------
    dyn : ArcDynamics
        The arc mode.
    """
    if not hasattr(dyn, "_rk8"):
        dyn._rk8 = _Rk8(dyn)  # type: ignore[attr-defined]
    return dyn._rk8.step  # type: ignore[attr-defined]



@dataclass
class ConstraintBlocks:
    """Constraint rows of a switching-time NLP, by block name.

    Built row block by row block (entry conditions, path samples, law bounds, end
    points, linkage) by :class:`SwitchingNLP` and the multi-phase
    :class:`~ocp.structure.phase_refinement.PhaseSwitchingNLP`; the block names let the
    multipliers be read back (e.g. the path rows' for the costate jumps).

    Attributes
    ----------
    exprs, lower, upper : list of casadi.SX
        Per added block: the rows (a column) and their bounds.
    index : dict of str to list of int
        Row numbers of each block name.
    times : list of (int, int)
        Per row: (interval, sample) where it is imposed.
    n : int
        Number of rows so far.
    """

    exprs: list = field(default_factory=list)
    lower: list = field(default_factory=list)
    upper: list = field(default_factory=list)
    index: dict[str, list[int]] = field(default_factory=dict)
    times: list[tuple[int, int]] = field(default_factory=list)  # (interval, sample) per row
    n: int = 0

    def add(self, name: str, expr: ca.SX, lo: Any, hi: Any, where: tuple[int, int]) -> None:
        """Append the rows ``lo <= expr <= hi`` under block ``name``.

        Parameters
        ----------
        name : str
            Block name (rows of one name need not be contiguous).
        expr : casadi.SX
            The rows (any shape; flattened); nothing is added when empty.
        lo, hi : casadi.SX or float
            Bounds, one per row or one for all.
        where : (int, int)
            (interval, sample) of these rows.
        """
        expr = ca.vec(ca.SX(expr))
        k = expr.numel()
        if k == 0:
            return
        self.exprs.append(expr)
        for store, v in ((self.lower, ca.SX(lo)), (self.upper, ca.SX(hi))):
            store.append(ca.vec(v) if v.numel() == k else ca.repmat(v, k, 1))
        self.index.setdefault(name, []).extend(range(self.n, self.n + k))
        self.times.extend([where] * k)
        self.n += k

    def substitute(self, first: int, old: ca.SX, new: ca.SX) -> None:
        """Replace the symbols ``old`` by ``new`` in the rows and bounds of the blocks added
        from the ``first``-th on (e.g. a derived phase's parameters by the problem's).

        Parameters
        ----------
        first : int
            Index of the first block (``len(exprs)`` before adding them).
        old, new : casadi.SX
            Symbols and what replaces them.
        """
        for store in (self.exprs, self.lower, self.upper):
            store[first:] = [ca.substitute(e, old, new) for e in store[first:]]



def interval_flow(d: ArcDynamics, m: int, samples: int, z: ca.SX, tau: ca.SX,
                  p: ca.SX) -> tuple[list[ca.SX], ca.SX]:
    """Sample states (start and interior points) and the end state of one interval.

    Parameters
    ----------
    d : ArcDynamics
        The interval's closed-loop dynamics.
    m : int
        Exact sub-steps (affine arcs) or RK8 steps.
    samples : int
        About how many interior samples to return.
    z : SX
        State (and cost quadrature) at the interval's start.
    tau : SX
        Its duration.
    p : SX
        Parameters.
    """
    stride = max(1, m // max(1, samples + 1))
    out: list[ca.SX] = []
    if d.exact:
        A, b = d.A_fn(p)
        n = d.nz
        M = ca.vertcat(ca.horzcat(A, b), ca.SX.zeros(1, n + 1))
        E = expm_taylor(M * (tau / m))
        zz = ca.vertcat(z, 1)
        for j in range(m):
            if j % stride == 0:
                out.append(zz[:n])
            zz = ca.mtimes(E, zz)
        return out, zz[:n]
    h = tau / m
    for j in range(m):
        if j % stride == 0:
            out.append(z)
        z = rk8_of(d)(z, h, p)  # (the cached step inlined: one call, not 12 stages in Python)
    return out, z


def build_intervals(G: ConstraintBlocks, pr: OptimalControlProblem, dyns: list[ArcDynamics],
                    substeps: tuple[int, ...], samples: int, tau: ca.SX, z: ca.SX, p: ca.SX,
                    entry_names: list[str], check_start: bool = False
                    ) -> tuple[ca.SX, list[ca.SX]]:
    """Flow one phase's intervals, adding entry, path and law-bound rows to ``G``.

    Path constraints are imposed at the samples of every interval but the phase's start
    (unless ``check_start``) and where a boundary arc holds them by construction.
    Control-only constraints are not rows: on an interval they are constants of the
    parameters (a row at its limit with no dependence on the unknowns would leave an
    interior-point method no slack); :func:`check_control_set` checks them instead.

    Parameters
    ----------
    G : ConstraintBlocks
        Constraint rows (appended to).
    pr : OptimalControlProblem
        The phase.
    dyns : list of ArcDynamics
        One per interval.
    substeps : tuple of int
        Per interval.
    samples : int
        Path-constraint samples per interval.
    tau : SX
        Interval durations.
    z : SX
        State (and cost quadrature) at the phase's start.
    p : SX
        Parameters.
    entry_names : list of str
        Receives the names of the entry conditions.
    check_start : bool
        Also impose the path constraints at the phase's start state.

    Returns
    -------
    (SX, list of SX)
        The end state and the junction states (start first).
    """
    nx = pr.nx
    names = [c.name for c in pr.structure_path]
    control_only = {c.name for c in control_constraints(pr)}
    hfn = ca.Function("h", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in pr.structure_path])]) \
        if pr.structure_path else None
    hlo = ca.vertcat(*[c.lower for c in pr.structure_path]) if pr.structure_path else ca.SX(0, 1)
    hhi = ca.vertcat(*[c.upper for c in pr.structure_path]) if pr.structure_path else ca.SX(0, 1)
    ends = [z]
    held_prev: tuple[str, ...] = ()
    for k, d in enumerate(dyns):
        _entry_rows(G, pr, k, d, z, held_prev, entry_names)
        pts, z_end = interval_flow(d, substeps[k], samples, z, tau[k], p)
        # constant controls meet the control-only constraints once for all
        # (check_control_set); a control following a boundary law may leave them
        settled = control_only if not ca.depends_on(d.u, pr.x) else set()
        for j, zj in enumerate(pts):
            if k == 0 and j == 0 and not check_start:
                continue
            skip = set(d.held) | settled | (set(held_prev) if j == 0 else set())
            keep = [i for i, n in enumerate(names) if n not in skip]
            if hfn is not None and keep:
                hv = hfn(zj[:nx], ca.substitute(d.u, pr.x, zj[:nx]), p)
                G.add("path", hv[keep], hlo[keep], hhi[keep], (k, j))
            _law_rows(G, pr, k, d, zj, j)
        _law_rows(G, pr, k, d, z_end, -1)
        z = z_end
        ends.append(z)
        held_prev = d.held
    return z, ends


def _entry_rows(G: ConstraintBlocks, pr: OptimalControlProblem, k: int, d: ArcDynamics, z: ca.SX,
                held_prev: tuple[str, ...], entry_names: list[str]) -> None:
    for (what, e), name in zip(d.entry, _entry_owners(d), strict=True):
        if name in held_prev:
            continue  # the boundary arc continues from the previous interval
        G.add("entry", ca.substitute(e, pr.x, z[:pr.nx]), 0, 0, (k, 0))
        entry_names.append(what)


def _law_rows(G: ConstraintBlocks, pr: OptimalControlProblem, k: int, d: ArcDynamics, z: ca.SX,
              j: int) -> None:
    for _, e, lo, hi in d.law_bounds:
        at = ca.substitute(e, pr.x, z[:pr.nx])
        if not ca.depends_on(ca.vertcat(lo, hi), pr.x):
            G.add("law", at, lo, hi, (k, j))
            continue
        # limits that move with a state (a decision variable refined as a constant state,
        # ocp.structure.variables): rows of the unknowns, one per finite side
        for b, low, high in ((lo, 0.0, INF), (hi, -INF, 0.0)):
            if constant(b) not in (-INF, INF):
                G.add("law", at - ca.substitute(b, pr.x, z[:pr.nx]), low, high, (k, j))


def _entry_owners(d: ArcDynamics) -> list[str]:
    """The held constraint each entry condition belongs to (they are listed in order)."""
    owners: list[str] = []
    for m in d.modes:
        if m.constraint is not None:
            owners.extend([m.constraint] * d.orders[m.constraint])
    return owners


def check_control_set(problem: OptimalControlProblem, modes: Modes, pv: np.ndarray,
                      tol: float = 1e-9) -> None:
    """Raise if an interval's controls violate a control-only path constraint.

    On an interval whose controls are all at bounds the control-only constraints
    (``u1 + u2 <= 1``) are numbers: a mode outside the control set (both ``u1``
    and ``u2`` at their upper bound) is no vertex of it.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    pv : ndarray
        Parameter values.
    tol : float
        Allowed violation, relative to ``max(1, |value|)``.

    Raises
    ------
    ValueError
        Naming the interval, its modes and the constraint.
    """
    if not control_constraints(problem):
        return
    for k, m in enumerate(modes):
        d = arc_dynamics(problem, m)
        if ca.depends_on(d.u, problem.x):
            continue  # a boundary law: the constraints are rows of the refinement NLP
        u = np.array(d.u_fn(np.zeros(problem.nx), pv), dtype=float).ravel()
        labels = [mm.label() for mm in m]
        bad = violated_control_constraint(problem, u, pv, tol)
        if bad is not None:
            raise ValueError(f"interval {k} ({labels}) violates the control-only constraint "
                             f"{bad!r}: not a vertex of the control set")
        for j, (name, mm) in enumerate(zip(problem.control_names, m, strict=True)):
            limits = ca.vertcat(*problem.control_limits[name])
            if ca.depends_on(limits, problem.x):
                continue  # a limit that moves with a (constant) state: a row of the NLP
            fb = ca.Function("b", [problem.p], [limits])
            blo, bhi = (float(b) for b in fb(pv).full().ravel())
            if mm.kind == "vertex" and not blo - tol <= u[j] <= bhi + tol:
                raise ValueError(f"interval {k} ({labels}): the vertex value {u[j]:.6g} of "
                                 f"{name!r} is outside its bounds [{blo:g}, {bhi:g}]")


def required_substeps(problem: OptimalControlProblem, modes: Modes, pv: np.ndarray,
                      durations: np.ndarray, x0: np.ndarray, samples: int, tol: float,
                      theta: float = 0.5) -> tuple[int, ...]:
    """Sub-steps per interval for a guess.

    Parameters
    ----------
    problem : OptimalControlProblem
    modes : tuple of tuple of Mode
        Per interval, one mode per control.
    pv : ndarray
        Parameter values.
    durations : ndarray
        Guessed interval lengths.
    x0 : ndarray
        Guessed initial state (propagated through the intervals).
    samples : int
        At least ``samples + 1`` sub-steps on exact intervals.
    tol : float
        Accuracy the RK8 intervals must meet (by halving).
    theta : float
        Exact intervals get ``||A|| tau / m <= theta``.

    Returns
    -------
    tuple of int
    """
    out = []
    z = np.r_[x0, 0.0] if has_running_cost(problem) else np.asarray(x0, dtype=float)
    for k, m in enumerate(modes):
        d = arc_dynamics(problem, m)
        tau = float(max(durations[k], 0.0))
        if d.exact:
            A, b = d.affine_numeric(pv)
            n = max(samples + 1, int(np.ceil(float(np.abs(A).sum(axis=0).max()) * tau / theta)))
            z = numeric_affine_flow(A, b, z, tau, n)[-1] if tau > 0 else z
        else:
            step = rk8_of(d)
            n, _ = rk8_steps_for(step, z, tau, pv, tol, minimum=max(4, (samples + 1) // 2))
            z = numeric_rk8_flow(step, z, tau, n, pv)[-1] if tau > 0 else z
        out.append(int(n))
    return tuple(out)
