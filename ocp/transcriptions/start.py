"""Where a transcription's solve starts: the default guess (with its bare defaults repaired
where they make the NLP non-finite), guesses from a solution on another grid or from a
:class:`~ocp.Trajectory`, multipliers from another collocation mesh, and the checks of a start
(finite, the objective's variation for the scaling). A base of
:class:`~ocp.transcriptions.nlp.Transcription`, which sets the attributes declared here in its
build."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import GuessError, ProblemDefinitionError
from ..definition.guess import (
    DefaultChoices,
    diagnose_nonfinite,
    raise_if_nonfinite,
    repair_default,
)
from ..definition.multiphase import MultiPhaseProblem
from ..definition.problem import OptimalControlProblem
from ..definition.scaling import Scaling
from ..definition.trajectory import Trajectory
from .discretization import PhaseDiscretization, PhaseLayout
from .solution import Solution

__all__ = ["TranscriptionStart"]


class TranscriptionStart:
    """The start of a transcription's solves (see the module); the NLP's layout and
    functions are the transcription's (built by :class:`~ocp.transcriptions.nlp.Transcription`)."""

    problem: OptimalControlProblem | MultiPhaseProblem
    multiphase: MultiPhaseProblem
    phases: list[PhaseDiscretization]
    layouts: list[PhaseLayout]
    offsets: list[int]
    link_blocks: dict[str, slice]
    iV: slice
    n_w: int
    n_g: int
    _nlp: dict[str, Any]
    _guess: ca.Function
    _choices: DefaultChoices
    _nlp_fn: ca.Function | None
    _grad_fn: ca.Function | None
    _last_default: tuple[bytes, np.ndarray] | None
    _last_start: tuple[bytes, float] | None
    _last_variation: tuple[bytes, float] | None

    def param_vector(self, params: dict[str, float]) -> np.ndarray:
        """The parameter values in declaration order, checked (see the problem's).

        Parameters
        ----------
        params : dict
            A value for every declared parameter.
        """
        return self.multiphase.param_vector(params)

    def default_guess(self, params: dict[str, float] | None = None) -> np.ndarray:
        """The default initial guess (see :mod:`ocp.definition.guess`) for these parameter values.

        A bare default (the bounds' midpoint, or 0 clipped into them) that makes
        the dynamics or constraints non-finite is replaced by another point within
        the bounds where one helps (:func:`ocp.definition.guess.repair_default`). Without
        ``params`` the parameters are taken as 0 (non-finite entries become 0, no
        replacement).

        Parameters
        ----------
        params : dict, optional
            Parameter values.
        """
        pv = self.param_vector(params) if params is not None else np.zeros(self.multiphase.np)
        n = len(self._choices.names)
        if params is None:
            with np.errstate(all="ignore"):
                w0 = np.array(self._guess(pv, np.zeros(n), np.zeros(n)), dtype=float).ravel()
            return np.nan_to_num(w0, posinf=0.0, neginf=0.0)
        return self._repaired_default(pv)

    def _repaired_default(self, pv: np.ndarray) -> np.ndarray:
        """The default guess, with bare defaults replaced where they make the NLP
        non-finite and another point within the bounds does not (see
        :mod:`ocp.definition.guess`); the last parameter values' is kept (a copy is
        returned), so re-solves from the default guess do not derive it again."""
        key = pv.tobytes()
        if self._last_default is None or self._last_default[0] != key:
            self._last_default = (key, self._derive_default(pv))
        return self._last_default[1].copy()

    def _derive_default(self, pv: np.ndarray) -> np.ndarray:
        n = len(self._choices.names)

        def at(use: np.ndarray, val: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                return np.array(self._guess(pv, use, val), dtype=float).ravel()

        last: dict[str, np.ndarray] = {}

        def count(use: np.ndarray, val: np.ndarray) -> int:
            w = last["w"] = at(use, val)
            if not np.all(np.isfinite(w)):
                return w.size + self.n_g + 1
            with np.errstate(all="ignore"):
                f, g = (np.array(v, dtype=float) for v in self.nlp_function()(w, pv))
            bad = int(np.sum(~np.isfinite(f)) + np.sum(~np.isfinite(g)))
            if bad == 0:  # what _check_start finds at this start: kept, not evaluated again
                self._last_start = (pv.tobytes() + w.tobytes(), float(f.ravel()[0]))
            return bad

        zeros = np.zeros(n)
        if n == 0:
            return at(zeros, zeros)
        if count(zeros, zeros) == 0:
            return last["w"]
        # the bounds of the bare defaults: only built when one needs replacing
        bounds = self._choices.bound_function(self.multiphase.p)
        lo, hi = (np.array(v, dtype=float).ravel() for v in bounds(pv))
        use, val = repair_default(count, lo, hi, self._choices.refs)
        return at(use, val)

    @property
    def nlp(self) -> dict[str, Any]:
        """The NLP in the user's units: ``x`` (= w), ``p``, ``f``, ``g`` (CasADi MX)."""
        return self._nlp

    def nlp_function(self) -> ca.Function:
        """``(w, p) -> (f, g)`` in the user's units (built on first use)."""
        if self._nlp_fn is None:
            self._nlp_fn = ca.Function("nlp", [self._nlp["x"], self._nlp["p"]],
                                       [self._nlp["f"], self._nlp["g"]])
        return self._nlp_fn

    def guess_from(self, sol: Solution | Trajectory) -> np.ndarray:
        """A decision vector for this transcription from a solution of another
        transcription (another grid or method) of the same problem, or from a
        :class:`ocp.Trajectory` (states and controls by name, interpolated
        linearly; a multi-phase problem needs its ``phase`` column).

        Parameters
        ----------
        sol : Solution or Trajectory
            Where to start from.
        """
        if isinstance(sol, Trajectory):
            return self._guess_from_trajectory(sol)
        if len(sol.phases) != len(self.phases):
            raise GuessError(f"the solution has {len(sol.phases)} phases, this problem "
                             f"{len(self.phases)}")
        for i, (ps, ph) in enumerate(zip(sol.phases, self.multiphase.phases, strict=True)):
            theirs = (ps.problem.state_names, ps.problem.control_names)
            if theirs != (ph.state_names, ph.control_names):  # a solution of another problem
                raise GuessError(
                    f"phase {i}: the solution's states and controls {theirs[0] + theirs[1]} "
                    f"are not this problem's {ph.state_names + ph.control_names}; pass a "
                    "Trajectory to start from states matched by name")
        parts = [d.guess_from(ps.resample, ps.t0, ps.T) for d, ps in zip(self.phases, sol.phases,
                                                                   strict=True)]
        parts.append(np.array([sol.variables[k] for k in self.multiphase.var_names]))
        return np.concatenate(parts)

    def dual_from(self, sol: Solution) -> tuple[np.ndarray, np.ndarray] | None:
        """Multipliers ``(lam_x, lam_g)`` for this NLP from a solution of the same problem
        on another collocation mesh (each phase's ``dual_from``), or None where a phase's
        discretisation cannot map them (multiple shooting, another method).

        Parameters
        ----------
        sol : Solution
            A solution of another transcription of this problem.
        """
        other = sol.transcription
        same = other.problem is self.problem or other.multiphase is self.multiphase
        if not same or len(sol.phases) != len(self.phases) or \
                any(not d.maps_duals or type(d) is not type(o)
                    for d, o in zip(self.phases, other.phases, strict=True)):
            return None
        lam_x, lam_g = np.zeros(self.n_w), np.zeros(self.n_g)
        for i, (d, o) in enumerate(zip(self.phases, other.phases, strict=True)):
            lay, olay = self.layouts[i], other.layouts[i]
            blocks = {k: sol.lam_g[sl] for k, sl in olay.blocks.items()}
            ob = other.offsets[i]
            g, x = d.dual_from(o, blocks, sol.lam_x[ob:ob + o.size()])
            for k, sl in lay.blocks.items():
                lam_g[sl] = g[k]
            lam_x[self.offsets[i]:self.offsets[i] + d.size()] = x
        for k, sl in self.link_blocks.items():
            lam_g[sl] = sol.lam_g[other.link_blocks[k]]
        lam_x[self.iV] = sol.lam_x[other.iV]
        return lam_x, lam_g

    def _guess_from_trajectory(self, traj: Trajectory) -> np.ndarray:
        w0 = self.default_guess()
        parts = []
        for i, (disc, ph) in enumerate(zip(self.phases, self.multiphase.phases, strict=True)):
            rows = np.ones(len(traj), bool) if traj.phase is None else traj.phase == i
            if len(self.phases) > 1 and traj.phase is None:
                raise ValueError("a guess trajectory for a multi-phase problem needs a "
                                 "phase column")
            t = traj.t[rows]
            missing = [n for n in ph.state_names + ph.control_names
                       if n not in traj.state_names + traj.control_names]
            if missing:
                raise ValueError(f"the guess trajectory lacks {missing}")

            def _sample(tq: np.ndarray, t: np.ndarray = t, rows: np.ndarray = rows,
                        ph: Any = ph) -> tuple[np.ndarray, np.ndarray]:
                col = [np.interp(tq, t, traj[n][rows]) for n in ph.state_names]
                ucol = [np.interp(tq, t, traj[n][rows]) for n in ph.control_names]
                x = np.column_stack(col)
                return x, (np.column_stack(ucol) if ucol else np.zeros((tq.size, 0)))

            parts.append(disc.guess_from(_sample, float(t[0]), float(t[-1])))
        parts.append(w0[self.iV])
        return np.concatenate(parts)

    def start_vector(self, pv: np.ndarray, params: dict[str, float], guess: Any,
                     warm_start: Solution | None) -> np.ndarray:
        """The primal start of a solve, in the user's units.

        Parameters
        ----------
        pv : ndarray
            The parameter values.
        params : dict
            The same, by name.
        guess, warm_start
            As for :meth:`solve`.
        """
        return self._start(pv, params, guess, warm_start)["x0"]

    def _start(self, pv: np.ndarray, params: dict[str, float], guess: Any,
               warm_start: Solution | None) -> dict[str, Any]:
        if warm_start is not None:
            if warm_start.transcription is self:
                return {"x0": warm_start.w, "lam_x0": warm_start.lam_x,
                        "lam_g0": warm_start.lam_g}
            x0 = self.guess_from(warm_start)
            dual = self.dual_from(warm_start)
            if dual is None:
                return {"x0": x0}
            return {"x0": x0, "lam_x0": dual[0], "lam_g0": dual[1]}
        if isinstance(guess, Solution):
            return {"x0": guess.w if guess.transcription is self else self.guess_from(guess)}
        if isinstance(guess, Trajectory):
            return {"x0": self.guess_from(guess)}
        if guess is not None:
            x0 = np.asarray(guess, dtype=float).ravel()
            if x0.shape != (self.n_w,):
                raise ValueError(f"guess has {x0.size} entries, the NLP {self.n_w}")
            return {"x0": x0}
        return {"x0": self.default_guess(params)}

    def _check_start(self, x0: np.ndarray, pv: np.ndarray) -> float:
        """The objective at the start; a clear error if the start makes the NLP
        non-finite, naming the expression (the last start's objective is kept: a re-solve
        from the same start does not evaluate it again)."""
        key = pv.tobytes() + x0.tobytes()
        last = self._last_start  # (read once: another thread may replace it)
        if last is not None and last[0] == key:
            return last[1]
        with np.errstate(all="ignore"):
            f, g = (np.array(v, dtype=float) for v in self.nlp_function()(x0, pv))
        if np.all(np.isfinite(f)) and np.all(np.isfinite(g)):
            f0 = float(f.ravel()[0])
            self._last_start = (key, f0)
            return f0
        if not np.all(np.isfinite(x0)):
            raise ProblemDefinitionError("the initial guess has non-finite entries")
        sol = self._unpack_only(x0, pv)
        msgs = [diagnose_nonfinite(d.cp, ps.t, ps.x, ps.data.u_points, ps.data.s)
                for d, ps in zip(self.phases, sol.phases, strict=True)]
        raise_if_nonfinite(msgs)
        raise ProblemDefinitionError("the initial guess makes a boundary constraint or the "
                                     "objective non-finite")

    def _objective_variation(self, x0: np.ndarray, pv: np.ndarray, sc: Scaling) -> float:
        """``sum |df/dw| D`` at the start: the objective's change when every variable
        moves by its scale (:mod:`ocp.definition.scaling`; NaN when not needed)."""
        if not sc.enabled or sc.objective_ref is not None:
            return math.nan
        x0 = np.asarray(x0, dtype=float)
        key = pv.tobytes() + x0.tobytes() + sc.D.tobytes()  # a re-solve: known
        last = self._last_variation  # (read once: another thread may replace it)
        if last is not None and last[0] == key:
            return last[1]
        if self._grad_fn is None:  # built on first use: one reverse sweep per start
            self._grad_fn = ca.Function("grad_f", [self._nlp["x"], self._nlp["p"]],
                                        [ca.gradient(self._nlp["f"], self._nlp["x"])])
        with np.errstate(all="ignore"):
            g = np.array(self._grad_fn(x0, pv), dtype=float).ravel()
        variation = float(np.sum(np.abs(g * sc.D)))
        self._last_variation = (key, variation)
        return variation

    def _unpack_only(self, w: np.ndarray, pv: np.ndarray) -> Solution:
        res = {"x": w, "f": np.nan, "lam_g": np.zeros(self.n_g), "lam_x": np.zeros(self.n_w)}
        stats = {"success": False, "return_status": "Not_Solved", "iter_count": 0}
        return Solution.from_nlp(self, pv, res, stats, 0.0)
