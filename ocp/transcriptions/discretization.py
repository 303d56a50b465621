"""What every per-phase discretisation (multiple shooting, collocation) provides.

A discretisation owns one block of the NLP's decision vector: the phase's
free times, its states and controls on a grid, and whatever else the method
needs. It builds, from symbolic views of its block and of the shared
parameters ``P`` and decision variables ``V``, the phase's constraints (with
bounds as functions of ``P``), its end-point values and integrals, the bounds
and default guess of its block; after a solve it unpacks its block into arrays
and samples the trajectory anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.compiled import CompiledPhase
from ..definition.multiphase import PhaseTimes
from .buffered import BufferedCall


@dataclass
class PhaseNLP:
    """Symbolic pieces of one phase, in terms of the decision vector ``w`` and ``P``, ``V``.

    Attributes
    ----------
    t0, T, x0, u0, xT, uT : casadi.MX
        Times, and states and controls at both ends.
    q : casadi.MX
        The integrals declared with ``problem.integral()``, in order.
    lagrange : casadi.MX
        Integral of the running cost.
    constraints : list
        ``(name, expr, lower, upper)`` rows.
    lbw, ubw, w0 : casadi.SX
        Bounds and default guess of the block (functions of the parameters).
    """

    t0: ca.MX
    T: ca.MX
    x0: ca.MX
    u0: ca.MX
    xT: ca.MX
    uT: ca.MX
    q: ca.MX  # integrals declared with problem.integral(), in order
    lagrange: ca.MX  # integral of the running cost
    constraints: list[tuple[str, ca.MX, ca.SX, ca.SX]]
    lbw: ca.SX  # bounds and default guess of the block, functions of the parameters
    ubw: ca.SX
    w0: ca.SX


@dataclass
class PhaseLayout:
    """Where a phase lives in ``w`` (absolute indices) and in ``g`` (``blocks``).

    Attributes
    ----------
    iT, it0 : int or None
        Index of the free final / initial time in ``w``.
    iX, iU, iZ, iV : slice
        States, controls, collocation states, phase variables in ``w``.
    blocks : dict
        Constraint name -> rows in ``g``.
    """

    iT: int | None
    iX: slice
    iU: slice
    it0: int | None = None
    iZ: slice | None = None
    iV: slice | None = None
    blocks: dict[str, slice] = field(default_factory=dict)


@dataclass
class PhaseData:
    """One phase's solved arrays (what :class:`ocp.Solution` exposes).

    Attributes
    ----------
    t0, T : float
        Initial and final time.
    t : ndarray
        Every discretisation point.
    x : ndarray
        States there, ``(len(t), nx)``.
    u : ndarray
        Control on each ``[t_k, t_k+1]``, ``(len(t) - 1, nu)``.
    u_points : ndarray
        A control value at each point, ``(len(t), nu)``.
    mesh : ndarray
        Mesh (shooting node) times.
    s : ndarray
        Static vector ``[p; v; t0; T]``.
    raw : dict
        Transcription-specific arrays.
    """

    t0: float
    T: float
    t: np.ndarray  # all discretisation points
    x: np.ndarray  # states there, (len(t), nx)
    u: np.ndarray  # control on [t_k, t_k+1], (len(t) - 1, nu)
    u_points: np.ndarray  # a control value at each point, for evaluate(), (len(t), nu)
    mesh: np.ndarray  # mesh (shooting node) times
    s: np.ndarray  # static vector [p; v; t0; T]
    raw: dict[str, Any] = field(default_factory=dict)


def lagrange_basis(nodes: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Lagrange basis polynomials on ``nodes`` evaluated at ``theta``: shape (len(theta), n).

    Parameters
    ----------
    nodes : ndarray
        Interpolation nodes.
    theta : ndarray
        Evaluation points.
    """
    nodes = np.asarray(nodes, dtype=float)
    theta = np.asarray(theta, dtype=float)
    out = np.ones((theta.size, nodes.size))
    for j, nj in enumerate(nodes):
        for r, nr in enumerate(nodes):
            if r != j:
                out[:, j] *= (theta - nr) / (nj - nr)
    return out


class PhaseDiscretization:
    """Common handling of a phase's times; subclasses add states, controls, constraints.

    Parameters
    ----------
    cp : CompiledPhase
        The phase's functions.
    times : PhaseTimes
        How its times enter the NLP.
    """

    method = "base"

    def __init__(self, cp: CompiledPhase, times: PhaseTimes) -> None:
        self.cp = cp
        self.times = times
        self.nT = 1 if times.T_free else 0
        self.nt0 = 1 if times.t0_free else 0
        self._check_maps: dict[int, ca.Function] = {}
        self._check_calls: dict[int, BufferedCall] = {}
        self._last_bounds: tuple[bytes, tuple[np.ndarray, ...]] | None = None
        self._checked: list[int] | None = None

    def control_only_rows(self) -> list[int]:
        """Rows of the check function this method checks at its points only (here none:
        see :meth:`ocp.transcriptions.collocation.CollocationPhase.control_only_rows`)."""
        return []

    def checked_rows(self) -> list[int]:
        """Rows of the check function (:attr:`ocp.definition.compiled.CompiledPhase.check`)
        checked, and imposed with ``inner_constraints``, between the points."""
        if self._checked is None:
            only_u = set(self.control_only_rows())
            self._checked = [i for i in range(self.cp.ncheck) if i not in only_u]
        return self._checked

    def check_map(self, n: int) -> ca.Function:
        """The phase's check function mapped over ``n`` points (cached).

        Parameters
        ----------
        n : int
            Number of points.
        """
        if n not in self._check_maps:
            self._check_maps[n] = self.cp.check.map(n)
        return self._check_maps[n]

    def check_values(self, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                     s: np.ndarray) -> np.ndarray:
        """The phase's check function at ``n`` points, shape (rows, n): ``check_map(n)``
        evaluated on the arrays as they are (no conversions to CasADi matrices).

        Parameters
        ----------
        t : ndarray
            Times, shape (n,).
        x, u : ndarray
            States and controls at those times, shapes (n, nx) and (n, nu).
        s : ndarray
            The phase's static vector (parameters, variables, t0, T).
        """
        n = t.size
        if n not in self._check_calls:
            self._check_calls[n] = BufferedCall(self.check_map(n))
        out = self._check_calls[n](t[None, :], x.T, u.T, s)[0]
        return out.reshape(self.cp.ncheck, n, order="F")

    def size(self) -> int:
        """Number of entries of the phase's block of ``w``."""
        raise NotImplementedError

    def _times(self, wb: ca.MX, it0: int) -> tuple[ca.MX, ca.MX]:
        tm = self.times
        T = wb[0] if tm.T_free else ca.MX(tm.T_bounds[0])
        t0 = wb[it0] if tm.t0_free else ca.MX(tm.t0_bounds[0])
        return t0, T

    def _time_bounds(self) -> tuple[list[ca.SX], list[ca.SX], list[ca.SX],
                                    list[ca.SX], list[ca.SX], list[ca.SX]]:
        """(lbT, ubT, T guess) and (lbt0, ubt0, t0 guess) as lists (empty when fixed)."""
        tm = self.times
        T = ([ca.SX(tm.T_bounds[0])], [ca.SX(tm.T_bounds[1])], [ca.SX(tm.T_guess)]) \
            if tm.T_free else ([], [], [])
        t0 = ([ca.SX(tm.t0_bounds[0])], [ca.SX(tm.t0_bounds[1])], [ca.SX(tm.t0_guess)]) \
            if tm.t0_free else ([], [], [])
        return T + t0

    def _unpack_times(self, wb: np.ndarray, it0: int) -> tuple[float, float]:
        tm = self.times
        T = float(wb[0]) if tm.T_free else tm.T_bounds[0]
        t0 = float(wb[it0]) if tm.t0_free else tm.t0_bounds[0]
        return t0, T

    def build(self, wb: ca.MX, P: ca.MX, V: ca.MX, ends: tuple[ca.SX, ca.SX],
              ug: ca.SX) -> PhaseNLP:
        """The phase's symbolic pieces from its block ``wb`` of ``w``.

        Parameters
        ----------
        wb : MX
            The phase's block of the decision vector.
        P, V : MX
            Parameters and decision variables.
        ends : tuple of SX
            Start and end guesses of the states (functions of the parameters).
        ug : SX
            Guess of the controls.
        """
        raise NotImplementedError

    def layout(self, offset: int) -> PhaseLayout:
        """Absolute positions of the block's parts, for a block starting at ``offset``.

        Parameters
        ----------
        offset : int
            Where the block starts in ``w``.
        """
        raise NotImplementedError

    def unpack(self, wb: np.ndarray, pv: np.ndarray, vv: np.ndarray) -> PhaseData:
        """Arrays of the solved block ``wb`` (parameters ``pv``, variables ``vv``).

        Parameters
        ----------
        wb : ndarray
            The solved block.
        pv, vv : ndarray
            Parameter and decision-variable values.
        """
        raise NotImplementedError

    def interpolate(self, data: PhaseData, k: np.ndarray, theta: np.ndarray,
                    substeps: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """States and controls on mesh interval ``k`` at the fractions ``theta`` in [0, 1]:
        the method's trajectory between its points, (n, nx) and (n, nu).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        k : ndarray of int
            Interval of each sample.
        theta : ndarray
            Fraction of the interval of each sample.
        substeps : int
            RK4 steps per sample (multiple shooting).
        """
        raise NotImplementedError

    def sample(self, data: PhaseData, t: np.ndarray,
               substeps: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """States and controls at times ``t`` (within the phase): :meth:`interpolate` on
        the interval holding each time, (n, nx) and (n, nu).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        t : ndarray
            Times.
        substeps : int
            RK4 steps per sample (multiple shooting).
        """
        return self.interpolate(data, *locate(data.mesh, t), substeps)

    def resample(self, data: PhaseData, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """States and controls at times ``t`` as the method represents them, for a guess
        on another grid (here :meth:`sample`).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        t : ndarray
            Times.
        """
        return self.sample(data, t)

    def pieces(self, data: PhaseData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pieces on which the interpolant is smooth: ``(k, a, b)``, the interval of
        each and its start and end fractions (here: every interval whole).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays.
        """
        N = data.mesh.size - 1
        return np.arange(N), np.zeros(N), np.ones(N)

    def control_bounds(self, data: PhaseData) -> tuple[np.ndarray, np.ndarray]:
        """The controls' bounds at the solution's parameter values (the last values' kept).

        Parameters
        ----------
        data : PhaseData
            The phase's solved arrays (its static vector starts with the parameters).
        """
        return self.check_bounds(data.s[:len(self.cp.phase.param_names)])[:2]

    def check_bounds(self, pv: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(ulo, uhi, clo, chi)``: the controls' and the check rows' bounds at the
        parameter values ``pv`` (read-only; the last values' kept, so a re-solve at the
        same values does not evaluate them again).

        Parameters
        ----------
        pv : ndarray
            The phase's parameter values.
        """
        pv = np.asarray(pv, dtype=float)
        key = pv.tobytes()
        last = self._last_bounds
        if last is None or last[0] != key:
            b = self.cp.bounds(pv)
            arrays = tuple(np.array(b[i], dtype=float).ravel() for i in (4, 5, 6, 7))
            for arr in arrays:
                arr.setflags(write=False)
            last = self._last_bounds = (key, arrays)
        return last[1]

    maps_duals = False
    """Whether :meth:`dual_from` maps another discretisation's multipliers onto this one."""

    def dual_from(self, old: PhaseDiscretization, lam_g: dict[str, np.ndarray],
                  lam_x: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """Multipliers for this discretisation from those of the same phase on another
        (only where :attr:`maps_duals`).

        Parameters
        ----------
        old : PhaseDiscretization
            The discretisation the multipliers belong to.
        lam_g : dict
            Its constraint multipliers by block name.
        lam_x : ndarray
            Its block of the bound multipliers.
        """
        raise NotImplementedError(f"{type(self).__name__} does not map multipliers")

    def guess_from(self, sample: Any, t0: float, T: float) -> np.ndarray:
        """A block of ``w`` from ``sample(t) -> (x, u)`` over ``[t0, T]``.

        Parameters
        ----------
        sample : callable
            ``t -> (x (n, nx), u (n, nu))``.
        t0, T : float
            The phase's times.
        """
        raise NotImplementedError

    def multipliers(self, lam: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Reshape the multipliers of this phase's blocks.

        Parameters
        ----------
        lam : dict
            Multipliers by block name, flat.
        """
        return lam


def static_vector(P: ca.MX, V: ca.MX, t0: ca.MX, T: ca.MX) -> ca.MX:
    """``s = [p; v; t0; T]`` as used by the compiled phase functions.

    Parameters
    ----------
    P, V : MX
        Parameters and decision variables.
    t0, T : MX
        The phase's initial and final times.
    """
    return ca.vertcat(P, V, t0, T)


def linear_guess(a: ca.SX, b: ca.SX, tau: np.ndarray) -> ca.SX:
    """States ``a + (b - a) tau`` at normalised times ``tau``: shape (nx, len(tau)).

    Parameters
    ----------
    a, b : SX
        Start and end values (column vectors).
    tau : ndarray
        Normalised times in [0, 1].
    """
    row = ca.DM(np.asarray(tau, dtype=float)).T
    return ca.mtimes(a, 1 - row) + ca.mtimes(b, row)


def locate(mesh: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh interval holding each time and the fraction of it there.

    Parameters
    ----------
    mesh : ndarray
        Increasing mesh times.
    t : array_like
        Query times.
    """
    t = np.asarray(t, dtype=float)
    k = segment_index(mesh, t)
    h = np.diff(mesh)[k]
    return k, np.where(h > 0, (t - mesh[k]) / np.where(h > 0, h, 1.0), 0.0)


def segment_index(mesh: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Index of the mesh interval holding each time (the last interval holds the end).

    Parameters
    ----------
    mesh : ndarray
        Increasing mesh times.
    t : ndarray
        Query times.
    """
    k = np.searchsorted(mesh, t, side="right") - 1
    return np.clip(k, 0, len(mesh) - 2)
