"""The switching-time NLP of a :class:`ocp.MultiPhaseProblem`: every phase's arcs, linked.

The NLP half of :mod:`ocp.structure.phase_refinement` (which solves it from a
transcription and assembles the :class:`~ocp.structure.phase_refinement.RefinedPhases`):
each phase has its own arcs (one :class:`~ocp.structure.flows.Mode` per control and
interval, as in :mod:`ocp.structure.refinement`); the unknowns are the interval durations
of every phase, the state at the start of every phase and the problem's decision
variables. The phases' own end-point and duration constraints and the linkage constraints
are imposed on the end-point values as the transcription does; a time link ``t0 of b = T of
a`` is used directly, every other link is a constraint. The NLP is built once per problem,
structure and step counts and cached (:func:`phase_switching_nlp`).
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import ProblemDefinitionError
from ..definition.multiphase import MultiPhaseProblem
from ..definition.problem import OptimalControlProblem
from .flows import Mode, has_running_cost
from .refinement import (
    REFINE_IPOPT,
    ConstraintBlocks,
    SwitchingNLP,
    arc_dynamics,
    build_intervals,
    rk8_of,
)
from .variables import moves_with_variables, phase_variables_as_states

Modes = tuple[tuple[Mode, ...], ...]
PhaseModes = tuple[Modes, ...]

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def check_phase_problem(mp: MultiPhaseProblem) -> None:
    """Refuse what the refinement cannot represent (see :mod:`ocp.structure.phase_refinement`).

    Parameters
    ----------
    mp : MultiPhaseProblem

    Raises
    ------
    ProblemDefinitionError
    """
    for ph in mp.phases:
        if ca.depends_on(ca.vertcat(ph.rhs, ph.lagrange), ca.vertcat(ph.t, ph.t0, ph.T)):
            raise ProblemDefinitionError(
                f"phase {ph.name!r}: switching refinement needs dynamics and running cost "
                "free of t, t0 and T")
        if ph.integrals:
            raise ProblemDefinitionError(f"phase {ph.name!r}: integrals in boundary terms are "
                                         "not supported by the switching refinement")


def flow_problem(ph: OptimalControlProblem) -> OptimalControlProblem:
    """The problem a phase's arcs are flowed on: the phase itself, or, when its dynamics,
    running cost, path constraints or control limits involve decision variables, the
    phase with the variables as constant states
    (:func:`ocp.structure.variables.phase_variables_as_states`).

    Parameters
    ----------
    ph : OptimalControlProblem
        A phase.
    """
    return phase_variables_as_states(ph) if moves_with_variables(ph) else ph


def _start_links(mp: MultiPhaseProblem) -> dict[int, int]:
    """Phase index -> the earlier phase whose final time is its initial time."""
    out: dict[int, int] = {}
    for a, b in mp.time_links:
        if a < b:
            out[b] = a
    for i, tm in enumerate(mp.times()):
        if i not in out and tm.t0_free:
            raise ProblemDefinitionError(
                f"phase {mp.phases[i].name!r}: a free initial time must be time-linked to an "
                "earlier phase for the switching refinement")
    return out


@dataclass
class _EndSymbols:
    """End-point symbols of every phase, stacked as the boundary function takes them."""

    per_phase: list[dict[str, ca.SX]]

    @classmethod
    def of(cls, mp: MultiPhaseProblem) -> _EndSymbols:
        return cls([{"x0": ph.x0, "u0": ph.u0, "xT": ph.xT, "uT": ph.uT, "t0": ph.t0,
                     "T": ph.T} for ph in mp.phases])

    def flat(self) -> ca.SX:
        return ca.vertcat(*[ca.vertcat(*d.values()) for d in self.per_phase])


class PhaseSwitchingNLP(SwitchingNLP):
    """The switching-time NLP of a multi-phase problem and its arc structure, built once.

    Decision vector: for each phase its interval durations then its initial state;
    then the decision variables.

    Parameters
    ----------
    mp : MultiPhaseProblem
        The problem.
    modes : tuple of Modes
        Per phase, per interval, one :class:`Mode` per control.
    substeps : tuple of tuple of int
        Per phase and interval: exact sub-steps or RK8 steps.
    samples : int
        Path constraints are imposed at about this many points inside each interval.
    ipopt_options : dict, optional
        Overrides of :data:`ocp.structure.refinement.REFINE_IPOPT`.

    Attributes
    ----------
    phase_rows : list of ndarray
        Constraint rows of each phase's flows (path, entry and law rows).
    boundary_rows : ndarray
        Rows of the end-point constraints (initial, terminal, boundary, durations,
        final times, links), in the order of the boundary function ``B``.
    """

    solver_name = "refine_phases"

    def __init__(self, mp: MultiPhaseProblem, modes: PhaseModes,
                 substeps: tuple[tuple[int, ...], ...], samples: int = 16,
                 ipopt_options: dict | None = None) -> None:
        t0 = time.perf_counter()
        check_phase_problem(mp)
        self.multiphase = mp
        self.problem = mp.phases[0]
        self.phase_modes = tuple(tuple(m) for m in modes)
        self.phase_substeps = tuple(tuple(s) for s in substeps)
        self.samples = int(samples)
        # each phase's arcs flow on its flow problem (the variables as constant states
        # where the phase involves them; their values are the last entries of w)
        self.flow_problems = [flow_problem(ph) for ph in mp.phases]
        self.phase_dyns = [[arc_dynamics(q, m) for m in ms]
                           for q, ms in zip(self.flow_problems, self.phase_modes, strict=True)]
        self.phase_K = [len(ms) for ms in self.phase_modes]
        self.links = _start_links(mp)
        sizes = [k + ph.nx for k, ph in zip(self.phase_K, mp.phases, strict=True)]
        self.offsets = [int(o) for o in np.r_[0, np.cumsum(sizes)[:-1]]]
        self.n_w = int(sum(sizes)) + mp.nv
        self.exact = tuple(d.exact for ds in self.phase_dyns for d in ds)
        self.K = sum(self.phase_K)
        self._build_multi()
        self._opts = {"ipopt": {**REFINE_IPOPT, **(ipopt_options or {})},
                      "print_time": False, "error_on_fail": False}
        self._solver = None  # (built on first use: SwitchingNLP.solver)
        self.build_time = time.perf_counter() - t0
        self.n_solves = 0

    # ------------------------------------------------------------------ build
    def _build_multi(self) -> None:
        mp = self.multiphase
        p = mp.p
        w = ca.SX.sym("w", self.n_w)
        V = w[self.n_w - mp.nv:]
        G = ConstraintBlocks()
        self.entry_names: list[str] = []
        values: list[dict[str, ca.SX]] = []
        ends_all: list[ca.SX] = []
        quad = ca.SX(0)
        self.phase_rows = []
        row_phase: list[int] = []
        for i, ph in enumerate(mp.phases):
            o, K = self.offsets[i], self.phase_K[i]
            tau, x0 = w[o:o + K], w[o + K:o + K + ph.nx]
            q = self.flow_problems[i]
            xq0 = ca.vertcat(x0, V) if q is not ph else x0  # the flow problem's states
            has_quad = has_running_cost(q)
            z = ca.vertcat(xq0, 0) if has_quad else xq0
            n0, first = G.n, len(G.exprs)
            z, ends = build_intervals(G, q, self.phase_dyns[i], self.phase_substeps[i],
                                      self.samples, tau, z, q.p, self.entry_names,
                                      check_start=i > 0)
            if q is not ph:  # a derived flow problem has parameter symbols of its own
                G.substitute(first, q.p, p)
                z = ca.substitute(z, q.p, p)
                ends = [ca.substitute(e, q.p, p) for e in ends]
            self.phase_rows.append(np.arange(n0, G.n))
            row_phase += [i] * (G.n - n0)
            xT = z[:ph.nx]
            if has_quad:
                quad = quad + z[q.nx]
            t0 = values[self.links[i]]["T"] if i in self.links else ca.SX(mp.times()[i]
                                                                           .t0_bounds[0])
            d0, d1 = self.phase_dyns[i][0], self.phase_dyns[i][-1]
            own = ca.vertcat(q.x, q.p)
            values.append({"x0": x0, "u0": ca.substitute(d0.u, own, ca.vertcat(xq0, p)),
                           "xT": xT, "uT": ca.substitute(d1.u, own, ca.vertcat(z[:q.nx], p)),
                           "t0": t0, "T": t0 + ca.sum1(tau)})
            ends_all.append(ca.horzcat(*ends))
        self._values = values
        self._boundary(G, values, p, V, row_phase)
        J = self._Bfn_J(values, p, V) + quad
        g = ca.vertcat(*G.exprs)
        self._nlp = {"x": w, "p": p, "f": J, "g": g}
        self.blocks = {k: np.array(v, dtype=int) for k, v in G.index.items()}
        self.row_where = np.array(G.times, dtype=int).reshape(-1, 2)
        self.row_phase = np.array(row_phase, dtype=int)
        self.n_g = G.n
        self.bounds_fn = ca.Function("bounds", [p], [ca.vertcat(*G.lower),
                                                     ca.vertcat(*G.upper)])
        xT_all = ca.vertcat(*[v["xT"] for v in values])
        T_all = ca.vertcat(*[v["T"] for v in values])
        t0_all = ca.vertcat(*[v["t0"] for v in values])
        self.out_fn = ca.Function("out", [w, p], [xT_all, T_all, J, t0_all, *ends_all])
        self.kkt_fn = ca.Function("kkt", [w, p], [g, ca.jacobian(g, w), ca.gradient(J, w)])
        vb = [mp.phases[0].variable_bounds(n) for n in mp.var_names]  # (shared by phases)
        self.var_bounds_fn = ca.Function("vb", [p], [ca.vertcat(*[lo for lo, _ in vb]),
                                                     ca.vertcat(*[hi for _, hi in vb])])

    def _boundary(self, G: ConstraintBlocks, values: list[dict[str, ca.SX]], p: ca.SX, V: ca.SX,
                  row_phase: list[int]) -> None:
        """End-point rows, and the boundary function ``B(ends, p, v, nu)`` for the costates."""
        mp = self.multiphase
        ends = _EndSymbols.of(mp)
        exprs, lows, highs, names = [], [], [], []
        skip = {f"time: {mp.phases[a].name} -> {mp.phases[b].name}" for a, b in mp.time_links}
        for _, kind, c in mp.boundary_blocks(mp.times()):
            if kind == "link" and c.name in skip:
                continue  # t0 of the later phase is the earlier phase's T by construction
            exprs.append(c.expr)
            lows.append(c.lower)
            highs.append(c.upper)
            names.append(kind)
        for ph, tm in zip(mp.phases, mp.times(), strict=True):
            # (a duration's bounds are among the blocks, its T_bounds infinite; a linked
            # phase's final time keeps its own bounds besides its span T - t0 >= 0)
            lo, hi = tm.T_bounds if tm.T_free else (tm.T_bounds[0], tm.T_bounds[0])
            if math.isfinite(lo) or math.isfinite(hi):
                exprs.append(ph.T)
                lows.append(ca.SX(lo))
                highs.append(ca.SX(hi))
                names.append("final_time")
        sym = ends.flat()
        val = ca.vertcat(*[ca.vertcat(*v.values()) for v in values])
        self.boundary_rows = np.arange(G.n, G.n + sum(int(e.numel()) for e in exprs))
        for e, elo, ehi, kind in zip(exprs, lows, highs, names, strict=True):
            G.add(kind, ca.substitute(e, ca.vertcat(sym, mp.v), ca.vertcat(val, V)), elo, ehi,
                  (-1, -1))
            row_phase += [-1] * int(e.numel())
        gB = ca.vertcat(*exprs) if exprs else ca.SX(0, 1)
        nu = ca.SX.sym("nu", gB.numel())
        Bexpr = mp.objective() + (ca.dot(nu, gB) if gB.numel() else 0)
        self._B = ca.Function("B", [sym, p, mp.v, nu], [Bexpr, ca.gradient(Bexpr, sym)])
        self._objective_fn = ca.Function("J_end", [sym, p, mp.v], [mp.objective()])

    def _Bfn_J(self, values: list[dict[str, ca.SX]], p: ca.SX, V: ca.SX) -> ca.SX:
        val = ca.vertcat(*[ca.vertcat(*v.values()) for v in values])
        return self._objective_fn(val, p, V)

    # -------------------------------------------------------------- numerics
    def phase_slice(self, i: int) -> slice:
        """Where phase ``i``'s ``[durations, x0]`` live in ``w``.

        Parameters
        ----------
        i : int
            Phase index.
        """
        o = self.offsets[i]
        return slice(o, o + self.phase_K[i] + self.multiphase.phases[i].nx)

    def _report_fn(self) -> ca.Function | None:
        return None  # the phases report through phase_outputs and transversality

    def _bounds(self, pv: np.ndarray) -> dict[str, np.ndarray]:
        lbg, ubg = (np.array(v, dtype=float).ravel() for v in self.bounds_fn(pv))
        lbx, ubx = [], []
        for K, ph in zip(self.phase_K, self.multiphase.phases, strict=True):
            lbx += [np.zeros(K), -np.inf * np.ones(ph.nx)]
            ubx += [np.inf * np.ones(K), np.inf * np.ones(ph.nx)]
        vlo, vhi = (np.array(v, dtype=float).ravel() for v in self.var_bounds_fn(pv))
        return {"lbx": np.concatenate([*lbx, vlo]), "ubx": np.concatenate([*ubx, vhi]),
                "lbg": lbg, "ubg": ubg}

    def phase_outputs(self, w: np.ndarray, pv: np.ndarray) -> dict[str, Any]:
        """Per-phase final states, start and final times, junction states; and J.

        Parameters
        ----------
        w : ndarray
            Decision vector.
        pv : ndarray
            Parameter values.
        """
        out = self.out_fn(w, pv)
        sizes = [ph.nx for ph in self.multiphase.phases]
        xT = np.array(out[0], dtype=float).ravel()
        cuts = np.r_[0, np.cumsum(sizes)]
        return {"xT": [xT[a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True)],
                "T": np.array(out[1], dtype=float).ravel(),
                "t0": np.array(out[3], dtype=float).ravel(), "J": float(out[2]),
                "Z": [np.array(z, dtype=float).T for z in out[4:]]}

    def accuracy(self, w: np.ndarray, pv: np.ndarray, tol: float  # type: ignore[override]
                 ) -> tuple[bool, float, list[tuple[int, int]]]:
        """Integration check of every interval of every phase (see
        :meth:`SwitchingNLP.accuracy`); the failing intervals as ``(phase, interval)``.

        Parameters
        ----------
        w : ndarray
            Decision vector.
        pv : ndarray
            Parameter values.
        tol : float
            Required relative accuracy of the RK8 intervals' end states.
        """
        from .flows import THETA_MAX, numeric_rk8_flow

        Z = self.phase_outputs(w, pv)["Z"]
        bad: list[tuple[int, int]] = []
        worst = 0.0
        for i, dyns in enumerate(self.phase_dyns):
            o = self.offsets[i]
            for k, d in enumerate(dyns):
                tau, m = float(w[o + k]), self.phase_substeps[i][k]
                if d.exact:
                    if d.norm_A(pv) * tau / m > THETA_MAX:
                        bad.append((i, k))
                    continue
                step = rk8_of(d)
                a = numeric_rk8_flow(step, Z[i][k], tau, m, pv)[-1]
                b = numeric_rk8_flow(step, Z[i][k], tau, 2 * m, pv)[-1]
                err = float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b)))))
                worst = max(worst, err)
                if err > tol:
                    bad.append((i, k))
        return not bad, worst, bad

    def phase_row_times(self, i: int, w: np.ndarray) -> np.ndarray:
        """Local time (from the phase's start) of each of phase ``i``'s flow rows.

        Parameters
        ----------
        i : int
            Phase index.
        w : ndarray
            Decision vector.
        """
        o, K = self.offsets[i], self.phase_K[i]
        tau = w[o:o + K]
        edges = np.r_[0.0, np.cumsum(tau)]
        rows = self.phase_rows[i]
        out = np.empty(len(rows))
        for r, (k, j) in enumerate(self.row_where[rows]):
            if j < 0:
                out[r] = edges[k + 1]
            else:
                m = self.phase_substeps[i][k]
                stride = max(1, m // max(1, self.samples + 1))
                out[r] = edges[k] + tau[k] * j * stride / m
        return out

    def transversality(self, w: np.ndarray, lam_g: np.ndarray,
                       pv: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray],
                                                list[float | None]]:
        """Costates at the ends and starts of the phases, and the value H must have.

        From the multipliers ``nu`` of the end-point rows and ``B = J_end + nu^T g_B``
        over independent end-point symbols: ``lambda_i(T_i) = d B / d xT_i`` (through
        the control law at the end), ``lambda_i(t0_i) = -d B / d x0_i``; H of the last
        phase of a time chain is ``-dB/dT``, and across a time link ``a -> b``,
        ``H_a = H_b - dB/dt0_b - dB/dT_a`` (None where a final time is fixed). A phase
        flowed with the decision variables as constant states (:func:`flow_problem`) gets
        ``lambda_i(T_i)`` for those states too: 0 (they do not enter H, their rate being
        0); ``lambda_i(t0_i)`` is the phase's states' only.

        Parameters
        ----------
        w : ndarray
            Decision vector.
        lam_g : ndarray
            Constraint multipliers (CasADi's signs).
        pv : ndarray
            Parameter values.
        """
        mp = self.multiphase
        ev = ca.Function("ends", [self._nlp["x"], self._nlp["p"]],
                         [ca.vertcat(*[ca.vertcat(*v.values()) for v in self._values])])
        sym_vals = np.array(ev(w, pv), dtype=float).ravel()
        nu = lam_g[self.boundary_rows]
        V = w[self.n_w - mp.nv:]
        _, grad = self._B(sym_vals, pv, V, nu)
        grad = np.array(grad, dtype=float).ravel()
        lam_end, lam_start, dT, dt0 = [], [], [], []
        pos = 0
        for i, ph in enumerate(mp.phases):
            nx, nu_ = ph.nx, ph.nu
            g0, gu0 = grad[pos:pos + nx], grad[pos + nx:pos + nx + nu_]
            gT = grad[pos + nx + nu_:pos + 2 * nx + nu_]
            guT = grad[pos + 2 * nx + nu_:pos + 2 * nx + 2 * nu_]
            dt0.append(float(grad[pos + 2 * nx + 2 * nu_]))
            dT.append(float(grad[pos + 2 * nx + 2 * nu_ + 1]))
            pos += 2 * nx + 2 * nu_ + 2
            K0, K1 = self._law_jacobians(i, pv)
            # (a flow problem's variable states: their costates do not enter H, their
            # rate being 0; swept from 0 at the phase's end)
            extra = np.zeros(self.flow_problems[i].nx - nx)
            lam_end.append(np.r_[gT + K1[:, :nx].T @ guT, extra])
            lam_start.append(-(g0 + K0[:, :nx].T @ gu0))
        H: list[float | None] = [None] * len(mp.phases)
        nxt = {a: b for b, a in self.links.items()}
        for i in range(len(mp.phases) - 1, -1, -1):
            if not mp.phases[i].time_free:
                continue
            if i not in nxt:
                H[i] = -dT[i]
            else:
                Hb = H[nxt[i]]
                H[i] = None if Hb is None else Hb - dt0[nxt[i]] - dT[i]
        return lam_end, lam_start, H

    def _law_jacobians(self, i: int, pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``du/dx`` of the first and last interval's control law of phase ``i`` (affine
        laws; zero for bang arcs)."""
        out = []
        q = self.flow_problems[i]
        for d in (self.phase_dyns[i][0], self.phase_dyns[i][-1]):
            aff = d.control_law_affine(pv)
            out.append(aff[0] if aff is not None else np.zeros((q.nu, q.nx)))
        return out[0], out[1]


def phase_switching_nlp(mp: MultiPhaseProblem, modes: PhaseModes,
                        substeps: tuple[tuple[int, ...], ...], samples: int = 16,
                        ipopt_options: dict | None = None) -> PhaseSwitchingNLP:
    """A cached :class:`PhaseSwitchingNLP` with at least ``substeps`` per interval.

    Parameters
    ----------
    mp : MultiPhaseProblem
    modes : tuple of Modes
        Per phase, per interval, one mode per control.
    substeps : tuple of tuple of int
        Needed per phase and interval (:func:`ocp.structure.refinement.required_substeps`).
    samples : int
        Path-constraint samples per interval.
    ipopt_options : dict, optional
        Overrides of :data:`ocp.structure.refinement.REFINE_IPOPT`.
    """
    key = (tuple(tuple(m) for m in modes), int(samples),
           tuple(sorted((k, repr(v)) for k, v in (ipopt_options or {}).items())))
    built = _CACHE.setdefault(mp, {}).setdefault(key, [])
    flat_need = [n for s in substeps for n in s]
    for nlp in built:
        have = [n for s in nlp.phase_substeps for n in s]
        if all(a >= b for a, b in zip(have, flat_need, strict=True)) and \
                all(a <= 4 * b for a, b in zip(have, flat_need, strict=True)):
            return nlp
    nlp = PhaseSwitchingNLP(mp, modes, substeps, samples, ipopt_options)
    built.append(nlp)
    return nlp


def clear_cache(mp: MultiPhaseProblem | None = None) -> None:
    """Forget the cached phase refinement NLPs (of one problem, or all): the next refinement
    builds its NLP for its own step counts instead of reusing a neighbour's (whose results
    differ in the last bits), as in a fresh process.

    Parameters
    ----------
    mp : MultiPhaseProblem, optional
        Forget only this problem's NLPs (default: all).
    """
    if mp is None:
        _CACHE.clear()
    else:
        _CACHE.pop(mp, None)



class PhaseRows:
    """What the certificate reads of a phase's NLP rows (step counts, row times).

    Parameters
    ----------
    nlp : PhaseSwitchingNLP
    i : int
        The phase.
    """

    def __init__(self, nlp: PhaseSwitchingNLP, i: int) -> None:
        self._nlp, self._i = nlp, i
        self.substeps = nlp.phase_substeps[i]

    def row_times(self, w: np.ndarray) -> np.ndarray:
        """Local times of the phase's rows at the phase's ``[durations, x0]`` ``w``.

        Parameters
        ----------
        w : ndarray
        """
        full = np.zeros(self._nlp.n_w)
        full[self._nlp.phase_slice(self._i)] = w
        return self._nlp.phase_row_times(self._i, full)


__all__ = ["Modes", "PhaseModes", "PhaseRows", "PhaseSwitchingNLP", "check_phase_problem",
           "clear_cache", "flow_problem", "phase_switching_nlp"]
