"""Scaling of the transcribed NLP: variables, constraint rows and objective.

The NLP that Ipopt sees is a change of variables and a rescaling of rows of the
one the transcription builds (in the user's units)::

    w = D * w_s + c        (per entry: D = ref, c = ref0 of its state, control, ...)
    g_s = r * g            (per row)
    f_s = f / f_ref

so everything reported -- ``sol.w``, the objective and the multipliers
``lam_g``, ``lam_x`` -- is mapped back to the user's units: with CasADi's
Lagrangian ``f + lam_g^T g + lam_x^T w``, ``lam_g = f_ref * r * lam_g_s`` and
``lam_x = f_ref * lam_x_s / D``. Costates read off the continuity multipliers,
and the PMP certificate, therefore mean the same with and without scaling.

Where the numbers come from (``scaling="auto"``, the default):

* a state, control or decision variable: its ``ref``/``ref0`` if given (as
  dymos: the NLP sees ``(x - ref0) / ref``); else, if both bounds are finite
  numbers and not *loose* (a safety box like ``(1e-3, 1e4)``: spanning more than
  100 guess magnitudes, or two non-zero bounds more than 100 apart),
  ``ref0 = lower`` and ``ref = upper - lower``; else the magnitude of its default
  guess where that is a non-zero number; else, for a state (``h >= 0`` with guess
  0 says nothing by itself), its size from elsewhere in the problem
  (:mod:`ocp.definition.sizes`): the value at which a boundary constraint on it alone reaches
  its bound (a muzzle energy ``1/2 m v(0)^2 <= 4e5`` gives v), the size of the
  state it is linked from, or the change its rate can make over the guessed
  duration; else 1. Free times likewise from their bounds or guess. These are the
  build's numbers; at each solve, the states whose bounds say nothing are sized again
  from the start actually given, and by the dynamics' change over the phase there
  (:mod:`ocp.transcriptions.scaled`);
* defect rows (``continuity``, ``collocation``) are divided by their state's
  ``ref``, so a scaled defect is the defect of the scaled state;
* other constraint rows by their ``ref=`` if given (``path_constraint(...,
  ref=)``, ``initial_constraint``, ``terminal_constraint``,
  ``boundary_constraint``, ``integral_constraint``, ``link_constraint``), else by
  the largest finite magnitude of their bounds (unless two non-zero bounds are
  loose);
* the objective by ``minimize(..., ref=)`` if given, else by the power of ten
  that brings its *variation* at the starting point of each solve,
  ``sum |df/dw| D`` (how much it changes when every variable moves by its
  scale), into [1, 10) -- up or down, unless that variation is already in
  [1, 100] and no variable is scaled (:data:`VARIATION_KEPT`: Ipopt's gradient-based
  scaling leaves gradients up to 100 alone, and a problem posed in normalised units
  keeps its NLP). The variation is proportional to the objective,
  so the same objective in metres, kilometres or millimetres gives exactly the
  same NLP (the cannonball's ``-r(T)``, ``-r(T) / 1000``, ``-1000 r(T)``: the
  same iterations). Where the objective does not vary at the start (``u^2`` at
  ``u = 0``), by its magnitude there when that exceeds 100 (never up: a small
  value at the start may be small by accident; at most
  :data:`OBJECTIVE_AUTO_MAX`: a poor start's value may exceed the optimum's by
  far).

An automatic number is used only when it is far from 1 (outside
:data:`AUTO_RANGE`; the objective's variation: outside [1, 100]): well-scaled
problems -- every problem posed in normalised units -- keep exactly the NLP
they had (identical Ipopt iterations), and only badly scaled ones (SI units:
ranges of 1e3 m, energies of 1e5 J, radii of 1e-2 m; an objective whose
variation is below 1, as a cost in km of a problem posed in m) are touched.
User-given references are always used.

Why not leave it to Ipopt: its ``nlp_scaling_method=gradient-based`` only scales
*down* a function whose gradient at the start exceeds
``nlp_scaling_max_gradient`` (100), and never the variables. An objective like
``-r(T)`` (a range of 3e3 m) has gradient 1, so it is left alone, yet its value
sets the size of every multiplier, and Ipopt's absolute tolerances (1e-10 here)
become unreachable relative to it; a variable in centimetres beside one in
kilometres leaves the Hessian badly conditioned whatever the rows do.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ProblemDefinitionError
from .problem import OptimalControlProblem, scale_ref
from .symbols import Constraint, constant

AUTO_RANGE = (1e-2, 1e2)  # automatic references inside this range are not applied
SCALING_MODES = ("auto", "none")
OBJECTIVE_AUTO_MAX = 1e4
"""The largest automatic objective scale from its value (a user's ``ref`` may be larger)."""
VARIATION_KEPT = (1.0, 1e2)
"""An objective whose variation at the start lies here is not scaled automatically."""
VARIATION_RANGE = (1e-8, 1e8)
"""The automatic objective scale from its variation is clipped into this range."""


@dataclass
class Scaling:
    """The constants of the change of variables and row scaling (see the module).

    Attributes
    ----------
    D, c : ndarray
        ``w = D * w_s + c``.
    r : ndarray
        Row scaling ``g_s = r * g``.
    objective_ref : float or None
        The objective's scale (None: automatic at each solve).
    enabled : bool
        Whether the NLP is scaled.
    state_refs : list of list of tuple, optional
        Per phase, each state's ``(ref0, ref)`` (what a solve on another mesh of the
        same problem carries over).
    """

    D: np.ndarray  # w = D * w_s + c
    c: np.ndarray
    r: np.ndarray  # g_s = r * g
    objective_ref: float | None  # None: automatic, at each solve
    enabled: bool
    state_refs: list[list[tuple[float, float]]] | None = None  # per phase, per state

    def variables_unscaled(self) -> bool:
        """True if no variable is scaled (``D = 1``, ``c = 0``): the NLP's variables as
        posed, whose objective is then left as posed where its variation is moderate."""
        return bool(np.all(self.D == 1.0) and np.all(self.c == 0.0))

    def is_identity(self) -> bool:
        """True if no variable or row is scaled."""
        return bool(np.all(self.D == 1.0) and np.all(self.c == 0.0) and np.all(self.r == 1.0))

    def objective_scale(self, f0: float, variation: float = math.nan) -> float:
        """``f_ref`` for a solve whose starting objective is ``f0``.

        Parameters
        ----------
        f0 : float
            The objective at the starting point.
        variation : float, optional
            ``sum |df/dw| D`` there: how much the objective changes when every
            variable moves by its scale (``D``). Proportional to the objective
            (a cost in km rather than m has 1e-3 of it), so dividing by it makes
            the NLP Ipopt sees the same whatever the objective's unit.
        """
        if not self.enabled:
            return 1.0
        if self.objective_ref is not None:
            return self.objective_ref
        v = abs(variation)
        if math.isfinite(v) and v > 0:
            # divided by the power of ten that brings the variation into [1, 10): an
            # objective in km and the same in m then give exactly the same NLP (1e-3 f
            # over 10^(k-3) is f over 10^k); up as well as down, which a value cannot
            # do (a small value at the start may be small by accident, a variation that
            # is non-zero is a rate). A variation in [1, 100] is left as posed: Ipopt
            # leaves gradients up to 100 alone, and well-posed problems keep their NLP
            if VARIATION_KEPT[0] <= v <= VARIATION_KEPT[1] and self.variables_unscaled():
                return 1.0
            v = min(max(v, VARIATION_RANGE[0]), VARIATION_RANGE[1])
            return float(10.0 ** math.floor(math.log10(v) + 1e-9))
        a = abs(f0)
        # no variation at the start (a cost at its minimum there, u = 0 in u^2): its value,
        # only down: a small objective at the start may be small by accident (a guess
        # at rest, a cost that vanishes there), and scaling it up would blow it up; and
        # at most OBJECTIVE_AUTO_MAX down: a poor start's value can exceed the optimum's
        # by far, and Ipopt's absolute dual tolerance loosens by the factor applied
        return min(a, OBJECTIVE_AUTO_MAX) if math.isfinite(a) and a > AUTO_RANGE[1] else 1.0

    # ---------------------------------------------------------------- maps
    def x_to_scaled(self, w: np.ndarray) -> np.ndarray:
        """``w_s`` of ``w`` (bounds too: infinities stay infinite).

        Parameters
        ----------
        w : ndarray
            Values in the user's units.
        """
        with np.errstate(invalid="ignore"):
            return (np.asarray(w, dtype=float) - self.c) / self.D

    def x_from_scaled(self, ws: np.ndarray) -> np.ndarray:
        """``w`` of ``w_s``.

        Parameters
        ----------
        ws : ndarray
            Scaled values.
        """
        return self.D * np.asarray(ws, dtype=float) + self.c

    def multipliers_to_scaled(self, lam_g: np.ndarray, lam_x: np.ndarray,
                              fref: float) -> tuple[np.ndarray, np.ndarray]:
        """Scaled ``(lam_g_s, lam_x_s)`` of multipliers in the user's units.

        Parameters
        ----------
        lam_g, lam_x : ndarray
            Multipliers in the user's units.
        fref : float
            The objective scale of the solve.
        """
        return (np.asarray(lam_g, dtype=float) / (fref * self.r),
                np.asarray(lam_x, dtype=float) * self.D / fref)

    def multipliers_from_scaled(self, lam_gs: np.ndarray, lam_xs: np.ndarray,
                                fref: float) -> tuple[np.ndarray, np.ndarray]:
        """``(lam_g, lam_x)`` in the user's units.

        Parameters
        ----------
        lam_gs, lam_xs : ndarray
            Ipopt's multipliers of the scaled NLP.
        fref : float
            The objective scale of the solve.
        """
        return (fref * self.r * np.asarray(lam_gs, dtype=float),
                fref * np.asarray(lam_xs, dtype=float) / self.D)


def _far(ref: float) -> bool:
    return not AUTO_RANGE[0] <= ref <= AUTO_RANGE[1]


def check_scaling(scaling: Any) -> dict[str, Any]:
    """The ``scaling=`` argument of a transcription, checked, as a dict.

    Parameters
    ----------
    scaling : {"auto", "none"} or dict
        ``"auto"`` (default), ``"none"`` (the NLP exactly as posed), or a dict:
        ``"objective"``: the objective's ``ref``; ``"time"``: ``ref`` of every
        free time; a state, control or variable name: its ``ref`` or
        ``(ref0, ref)`` (overrides the problem's, in every phase);
        ``"auto"``: False to scale only what is named (default True);
        ``"fallback"``: False not to retry a failed scaled solve as posed (default True,
        :mod:`ocp.transcriptions.failure`).
    """
    if isinstance(scaling, str):
        if scaling not in SCALING_MODES:
            raise ProblemDefinitionError(f"scaling must be one of {SCALING_MODES} or a dict, "
                                         f"got {scaling!r}")
        return {"enabled": scaling == "auto", "auto": scaling == "auto", "refs": {},
                "fallback": True}
    if not isinstance(scaling, Mapping):
        raise ProblemDefinitionError(f"scaling must be 'auto', 'none' or a dict, got "
                                     f"{type(scaling).__name__}")
    refs: dict[str, tuple[float, float]] = {}
    flags = {"auto": True, "fallback": True}
    for key, val in scaling.items():
        if key in flags:
            if not isinstance(val, bool):
                raise ProblemDefinitionError(f"scaling[{key!r}] must be True or False, got "
                                             f"{val!r}")
            flags[key] = val
            continue
        pair = val if isinstance(val, tuple | list) else (None, val)
        if len(pair) != 2:
            raise ProblemDefinitionError(f"scaling[{key!r}]: give ref or (ref0, ref)")
        checked = scale_ref(pair[1], pair[0], f"scaling[{key!r}]")
        assert checked is not None
        refs[str(key)] = checked
    return {"enabled": True, "auto": flags["auto"], "refs": refs,
            "fallback": flags["fallback"]}


class ScalingBuilder:
    """Collects the per-entry and per-row constants of one transcription.

    Parameters
    ----------
    options : dict
        As returned by :func:`check_scaling`.
    n_w, n_g : int
        Sizes of the NLP.
    """

    def __init__(self, options: dict[str, Any], n_w: int, n_g: int) -> None:
        self.opt = options
        self.D, self.c = np.ones(n_w), np.zeros(n_w)
        self.r = np.ones(n_g)

    def ref(self, name: str, user: tuple[float, float] | None, lo: Any, hi: Any,
            guess: Any, size: float | None = None) -> tuple[float, float]:
        """``(ref0, ref)`` of one quantity (see the module for the rules).

        Parameters
        ----------
        name : str
            Its name (looked up in the ``scaling=`` dict).
        user : tuple or None
            The problem's ``(ref0, ref)``.
        lo, hi : SX or float
            Its bounds.
        guess : SX, float or None
            Its default guess (a number or a pair of numbers, or None).
        size : float, optional
            Its size from elsewhere in the problem (:mod:`ocp.definition.sizes`), used when
            bounds and guess give none.
        """
        if not self.opt["enabled"]:
            return 0.0, 1.0
        given = self.opt["refs"].get(name, user)
        if given is not None:
            return given
        if not self.opt["auto"]:
            return 0.0, 1.0
        auto = _auto_ref(lo, hi, guess, size)
        return auto if _far(auto[1]) else (0.0, 1.0)

    def set_entries(self, index: Any, ref: tuple[float, float]) -> None:
        """Entries ``index`` of ``w`` get ``(ref0, ref)``.

        Parameters
        ----------
        index : slice, int or array
            Entries of ``w``.
        ref : tuple
            ``(ref0, ref)``.
        """
        self.c[index], self.D[index] = ref

    def row_scale(self, c: Constraint, row: int) -> float:
        """``r`` of row ``row`` of constraint ``c``: ``1 / c.ref`` if given, else from bounds.

        Parameters
        ----------
        c : Constraint
            The constraint.
        row : int
            Which of its rows.
        """
        if not self.opt["enabled"]:
            return 1.0
        if c.ref is not None:
            return 1.0 / c.ref
        return self.row_scale_from_bounds(c.lower[row], c.upper[row])

    def row_scale_from_bounds(self, lo: Any, hi: Any) -> float:
        """``r`` of a row from its bounds: 1 / their largest finite magnitude, if far from 1.

        Parameters
        ----------
        lo, hi : SX or float
            The row's bounds.
        """
        if not (self.opt["enabled"] and self.opt["auto"]):
            return 1.0
        mags = [abs(v) for v in (_number(lo), _number(hi))
                if v is not None and math.isfinite(v) and v != 0.0]
        if not mags or (len(mags) == 2 and _loose(*mags)):
            return 1.0
        m = max(mags)
        return 1.0 / m if _far(m) else 1.0

    def build(self) -> Scaling:
        """The collected constants."""
        oref = self.opt["refs"].get("objective")
        return Scaling(self.D, self.c, self.r, None if oref is None else oref[1],
                       self.opt["enabled"])


def _number(v: Any) -> float | None:
    if v is None:
        return None
    if isinstance(v, int | float):
        return float(v)
    return constant(v)


LOOSE = 1e2  # bounds wider than this many guess magnitudes, or this ratio apart, are loose


def _auto_ref(lo: Any, hi: Any, guess: Any, size: float | None = None) -> tuple[float, float]:
    """From finite bounds ``(lo, hi - lo)`` unless they are loose, else from the guess
    magnitude, else from ``size``, else (0, 1).

    Bounds are *loose* -- a safety box such as ``(1e-3, 1e4)``, not a magnitude --
    when they span more than :data:`LOOSE` times the guess magnitude, or when both
    are non-zero and more than :data:`LOOSE` apart in magnitude.
    """
    vals = guess if isinstance(guess, tuple | list) else (guess,)
    nums = [abs(x) for x in (_number(g) for g in vals) if x is not None and math.isfinite(x)]
    g = max(nums) if nums else 0.0
    from_bounds = informative_bounds(lo, hi, g)
    if from_bounds is not None:
        return from_bounds
    if g > 0:
        return 0.0, g
    return (0.0, size) if size is not None and size > 0 else (0.0, 1.0)


def informative_bounds(lo: Any, hi: Any, g: float) -> tuple[float, float] | None:
    """``(lo, hi - lo)`` where the bounds give a magnitude (both finite numbers, not
    loose for a guess of magnitude ``g``), else None.

    Parameters
    ----------
    lo, hi : SX or float
        Bounds.
    g : float
        The guess' magnitude.
    """
    lv, hv = _number(lo), _number(hi)
    if lv is not None and hv is not None and math.isfinite(lv) and math.isfinite(hv) \
            and hv > lv and not loose_bounds(lv, hv, g):
        return lv, hv - lv
    return None


def loose_bounds(lv: float, hv: float, g: float) -> bool:
    """Finite bounds that say nothing of a magnitude: both non-zero and more than
    :data:`LOOSE` apart, or spanning more than :data:`LOOSE` guess magnitudes ``g``.

    Parameters
    ----------
    lv : float
        Lower bound.
    hv : float
        Upper bound.
    g : float
        The guess' magnitude.
    """
    return _loose(lv, hv) or (g > 0 and hv - lv > LOOSE * g)


def _loose(a: float, b: float) -> bool:
    """Both non-zero and more than :data:`LOOSE` apart in magnitude."""
    small, big = sorted((abs(a), abs(b)))
    return small > 0 and big > LOOSE * small


def phase_quantities(ph: OptimalControlProblem, starts: Any, ends: Any,
                     ) -> tuple[list[tuple[str, Any, Any, Any, Any]],
                                list[tuple[str, Any, Any, Any, Any]]]:
    """``(name, user ref, lo, hi, guess)`` of every state and control of a phase.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    starts, ends : SX
        The states' default start and end guesses (from :mod:`ocp.definition.guess`).
    """
    states = [(n, ph.state_ref.get(n), *ph.state_bounds[n], (starts[i], ends[i]))
              for i, n in enumerate(ph.state_names)]
    controls = [(n, ph.control_ref.get(n), *ph.control_bounds[n], ph.control_guess.get(n))
                for n in ph.control_names]
    return states, controls
