"""Regular interior arcs in the refinement: the costate carried as extra states.

On a *regular* interior arc (H strictly convex in the control, ``H_u = 0``) the control is a
function of the state and the costate, ``u = argmin_u H(x, lambda, u)``. The switching-time
refinement flies states only, so :func:`costates_as_states` derives a problem whose states
are the problem's and, for each *run* of interior arcs (a maximal stretch of intervals on
which some control is interior), a copy ``lambda^(i)`` of the costate: it follows the
costate equation ``lambda' = -H_x(x, lambda, u)`` on its own run and stays constant
elsewhere (:func:`copy_rhs`), so its initial value is its value at the run's start, a
free unknown of the refinement NLP. Every value gives an admissible control (within its
bounds, rows of the NLP) and the optimum's costate is one of them, so minimising over
the durations and the copies' values finds the optimum, as for singular arcs
(:mod:`ocp.structure.interior_arcs`); a copy is free to jump at its run's start, as the
costate does at the junctions of a state constraint. The certificate reads the costate
on an interior run from its copy (:func:`copy_of`).

The derived problem keeps the original's names for its states, controls, path
constraints and bounds; the copies are called ``lam_<state>#<run>``.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem
from ..transcriptions.gridview import collocation_costates, is_collocation
from .derived_times import refuse_shifted_time, same_final_time

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class CopyLayout:
    """Where the costate copies sit among a derived problem's states.

    Attributes
    ----------
    origin : OptimalControlProblem
        The problem the copies were added to.
    nx : int
        Its number of states (the copies follow them, ``nx`` each).
    runs : int
        How many copies.
    """

    origin: OptimalControlProblem
    nx: int
    runs: int

    def rows(self, run: int) -> slice:
        """The state rows of copy ``run``.

        Parameters
        ----------
        run : int
        """
        return slice(self.nx * (1 + run), self.nx * (2 + run))


def copy_of(pr: OptimalControlProblem) -> CopyLayout | None:
    """The copy layout of a problem from :func:`costates_as_states` (None otherwise).

    Parameters
    ----------
    pr : OptimalControlProblem
    """
    return getattr(pr, "costate_copies", None)


def costates_as_states(pr: OptimalControlProblem, runs: int) -> OptimalControlProblem:
    """``pr`` with ``runs`` copies of the costate as states (built once per problem and count).

    Parameters
    ----------
    pr : OptimalControlProblem
        Single phase, without decision variables, end-point costs or constraints coupling
        both ends, integrals in boundary terms, or time in the dynamics.
    runs : int
        How many runs of interior arcs.

    Returns
    -------
    OptimalControlProblem
        With :func:`copy_of` its :class:`CopyLayout`.

    Raises
    ------
    ValueError
        What the derived problem cannot carry.
    """
    per = _CACHE.setdefault(pr, {})
    if runs not in per:
        per[runs] = _build(pr, runs)
    return per[runs]


def _build(pr: OptimalControlProblem, runs: int) -> OptimalControlProblem:
    refuse_shifted_time(pr)
    if pr.nv or pr.boundary or pr.integrals or not ca.SX(pr.boundary_cost).is_zero() or \
            ca.depends_on(ca.vertcat(pr.rhs, ca.SX(pr.lagrange)),
                          ca.vertcat(pr.t, pr.t0, pr.T)):
        raise ValueError("a regular interior arc is refined with the costate as states: the "
                         "problem may not have decision variables, end-point costs or "
                         "constraints on both ends, integrals, or time in its dynamics")
    q = OptimalControlProblem(f"{pr.name} (costates on {runs} interior run(s))")
    P = [q.parameter(n) for n in pr.param_names]
    X = [q.state(n) for n in pr.state_names]
    L = [[q.state(f"lam_{n}#{i}") for n in pr.state_names] for i in range(runs)]
    U = [q.control(n) for n in pr.control_names]
    old = ca.vertcat(pr.p, pr.x, pr.u, pr.t, pr.t0, pr.T)
    new = ca.vertcat(*P, *X, *U, q.t, q.t0, q.T)

    def sub(e: ca.SX) -> ca.SX:
        return ca.substitute(ca.SX(e), old, new)

    lam = ca.SX.sym("lam", pr.nx)
    Hx = ca.gradient(ca.SX(pr.lagrange) + ca.dot(lam, pr.rhs), pr.x)
    rhs = dict(zip(pr.state_names, ca.vertsplit(sub(pr.rhs)), strict=True))
    for copy in L:  # each copy follows the costate equation (copy_rhs freezes the others)
        hx = ca.vertsplit(sub(ca.substitute(-Hx, lam, ca.vertcat(*copy))))
        rhs.update(dict(zip([str(c) for c in copy], hx, strict=True)))
    q.set_dynamics(rhs)
    for n in pr.control_names:
        q.bound_control(n, *(sub(b) for b in pr.control_bounds[n]))
    for c in pr.structure_path:
        q.path_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    for c in pr.initial:
        q.initial_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    for c in pr.terminal:
        q.terminal_constraint(sub(c.expr), sub(c.lower), sub(c.upper), name=c.name)
    if pr.has_running_cost():
        q.minimize_integral(sub(pr.lagrange))
    q.minimize_terminal(sub(pr.mayer))
    same_final_time(q, pr)
    q.control_limits = {n: (sub(lo), sub(hi)) for n, (lo, hi) in pr.control_limits.items()}
    q.costate_copies = CopyLayout(pr, pr.nx, runs)  # type: ignore[attr-defined]
    return q


def costate_guess(sol: Any, starts: list[float]) -> np.ndarray:
    """The copies' initial values: the transcription's costate at each run's start.

    Parameters
    ----------
    sol : TranscribedSolution
        Its multipliers give the costate (shooting: continuity multipliers at the nodes
        after the first; collocation: :func:`ocp.transcriptions.gridview.collocation_costates`).
    starts : list of float
        The runs' start times.

    Returns
    -------
    ndarray (len(starts) * nx,)
    """
    if is_collocation(sol):
        t, lam = np.asarray(sol.t[1:], dtype=float), collocation_costates(sol)
    else:
        t, lam = np.asarray(sol.t[1:], dtype=float), np.asarray(sol.multipliers["continuity"])
    return np.concatenate([[np.interp(a, t, lam[:, j]) for j in range(lam.shape[1])]
                           for a in starts])


def copy_rhs(pr: OptimalControlProblem, runs: tuple[int | None, ...]) -> ca.SX:
    """The dynamics of ``pr`` with the costate copies not in ``runs`` held constant.

    Parameters
    ----------
    pr : OptimalControlProblem
        Any problem (returned as is without copies).
    runs : tuple of int or None
        The runs of the interval's interior modes.
    """
    lay = copy_of(pr)
    if lay is None:
        return pr.rhs
    rows = ca.vertsplit(pr.rhs)
    for i in range(lay.runs):
        if i not in runs:
            rows[lay.rows(i)] = [ca.SX(0)] * lay.nx
    return ca.vertcat(*rows)


__all__ = ["CopyLayout", "copy_of", "copy_rhs", "costate_guess", "costates_as_states"]
