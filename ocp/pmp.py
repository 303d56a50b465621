"""Pontryagin certificate: Hamiltonian, switching functions, verdict with measured accuracy.

Conventions (stated once, used everywhere here): the *minimum* principle,
``H = L + lambda^T (f(x) + g(x) u)``, and the optimal control minimises H.
For a control-affine problem the switching function of control j is
``sigma_j = dL/du_j + lambda^T g_j(x)``: ``u_j = upper`` where ``sigma_j < 0``
and ``u_j = lower`` where ``sigma_j > 0``. The paper writes the maximum
principle; its costate is ``-lambda``.

Costates come from :mod:`ocp.costates`: the transcription's continuity
multipliers, or the adjoint integrated backward jointly with the state along
the refined arcs (exact on affine arcs; RK8 at two step counts otherwise, so
the certificate knows its own numerical error).

For an autonomous problem H is constant; with free final time it equals
``-d(phi + nu^T G_T)/dT`` (0 when the terminal cost and constraints do not
involve T; -1 for minimum time posed as ``phi = T``). ``H_max_abs`` and
``H_variation`` are normalised by ``H_scale = max_t sum_i |lambda_i xdot_i|``
(the size of the terms that must cancel).

What a verdict means. ``"bang-bang certified"``: the minimum principle's
*necessary* conditions hold along this candidate, which structure detection
sees as bang (and boundary) arcs only and which shows no chattering. It is a
local statement: the candidate is a bang-bang extremal, not necessarily the
global optimum (a problem with several extremals needs several starts).
``"not bang-bang"``: this candidate fails the conditions (beyond tolerance and
numerical error). ``"inconclusive"``: nothing refutes, but a violation lies
inside the error band, a state constraint is active, or structure detection
finds an interior (singular, free or unresolved) arc, which is never
certified. ``"chattering suspected"``: switch intervals shrink geometrically
toward a point and a finer grid resolves more of them (:mod:`ocp.chattering`);
no finite switching structure is certified. ``"not applicable: ..."``: the
solution (or its refinement) did not converge or is not verified, and nothing
is checked.

A check fails only by more than its tolerance *and* more
than ten times the certificate's own estimated numerical error; a violation
inside that error band gives "inconclusive", never a refutation. From a
transcription alone, whose costates carry the grid's error, a would-be
refutation is re-checked on a grid twice as fine and reported only if it
persists there. Where a state constraint is active (a boundary arc, or a
constraint touching its limit) the unconstrained costate does not hold
before it: the checks then cover the part after the last constrained time,
and the verdict is at best "inconclusive: state constraint active on ...".
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .arcs import (
    ArcStructure,
    SolutionLike,
    TranscribedSolution,
    active_path_constraints,
    control_bounds_at,
    detect_arcs,
    detect_structure,
    transcribed,
)
from .chattering import ChatteringResult
from .chattering import detect_chattering as chattering_of
from .constraint_kinds import MIXED, STATE, coupled_groups
from .control_set import control_polytope, distance_to_vertices, vertex_scores
from .costates import (
    adjoint_along_refined,
    adjoint_sweep,
    costates_from_multipliers,
    pmp_functions,
    terminal_costate,
)
from .gridview import is_collocation, mesh_level
from .problem import OptimalControlProblem
from .solution import Solution, along
from .switching import RefinedSwitching

CERTIFIED = "bang-bang certified"
NOT_BANG_BANG = "not bang-bang"
INCONCLUSIVE = "inconclusive"
CHATTERING = "chattering suspected"
NOT_APPLICABLE = "not applicable: the solve did not converge"
UNVERIFIED = "not applicable: the solution is not verified"
ERROR_MARGIN = 10.0
"""A violation within this factor of the estimated numerical error is not a refutation."""

__all__ = ["CERTIFIED", "CHATTERING", "ChatteringResult", "INCONCLUSIVE", "NOT_APPLICABLE",
           "NOT_BANG_BANG", "PMPCertificate", "UNVERIFIED", "adjoint_along_refined", "certify",
           "costates_from_multipliers", "detect_chattering", "plot_certificate"]


@dataclass
class PMPCertificate:
    """Figures of the PMP check and a verdict.

    Attributes
    ----------
    verdict : str
        ``"bang-bang certified"``, ``"not bang-bang"``, ``"inconclusive"``,
        ``"chattering suspected"`` or ``"not applicable: ..."`` (see :func:`certify`).
    reasons : list of str
        Why (every failed, uncertain or unverifiable check).
    H_expected : float or None
        The constant H must equal (None when T is fixed: any constant).
    H_max_abs, H_variation : float
        ``max |H - H_expected|`` (or ``max |H - mean H|`` when fixed T) and
        ``max H - min H``, both divided by ``H_scale``.
    sigma_sign_agreement : float
        Fraction of the time where some ``|sigma_j|`` is clearly non-zero on
        which ``u_j`` sits at the bound its sign selects (worst control).
    switch_sigma_gap : float
        Largest time between a switch of some control and the nearest sign
        change of its switching function.
    singular_intervals, state_constraint_active_intervals : list of (t0, t1)
    costate_estimates_gap : float
        Largest difference between the two costate estimates on the checked
        part, relative to the largest costate (NaN without a refined solution).
    source : str
        Where the costates came from.
    numerical_error : dict
        The certificate's own error estimates, on the scales of the figures
        they affect: ``H``, ``sigma``, ``switch``, ``costate``, ``state``.
    checked_from : float
        Start of the checked part of the horizon (after the last constrained time).
    per_control : dict
        Per control: ``sigma_sign_agreement`` and ``switch_sigma_gap``.
    elapsed : float
        Seconds the certificate took.
    chattering : ChatteringResult or None
        Switches accumulating at a point (:func:`detect_chattering`), if found.
    t, lam, H, sigma, u : arrays for plotting (``sigma``/``u`` 1-D for one control).
    """

    verdict: str
    reasons: list[str]
    H_expected: float | None
    H_max_abs: float
    H_variation: float
    H_scale: float
    sigma_sign_agreement: float
    switch_sigma_gap: float
    singular_intervals: list[tuple[float, float]]
    state_constraint_active_intervals: list[tuple[float, float]]
    costate_estimates_gap: float
    source: str
    t: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    lam: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    H: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    sigma: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    u: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    numerical_error: dict[str, float] = field(default_factory=dict)
    checked_from: float = 0.0
    per_control: dict[str, dict[str, float]] = field(default_factory=dict)
    elapsed: float = 0.0
    chattering: ChatteringResult | None = None

    @property
    def certified(self) -> bool:
        """True when the verdict is "bang-bang certified"."""
        return self.verdict == CERTIFIED

    @property
    def applicable(self) -> bool:
        """False when the solution was refused (not converged, or not verified)."""
        return not self.verdict.startswith("not applicable")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (non-finite numbers become None)."""
        def f(x: Any) -> float | None:
            return float(x) if x is not None and math.isfinite(x) else None

        return {"verdict": self.verdict, "reasons": self.reasons,
                "H_expected": f(self.H_expected) if self.H_expected is not None else None,
                "H_max_abs": f(self.H_max_abs), "H_variation": f(self.H_variation),
                "H_scale": f(self.H_scale), "sigma_sign_agreement": f(self.sigma_sign_agreement),
                "switch_sigma_gap": f(self.switch_sigma_gap),
                "singular_intervals": [list(map(float, i)) for i in self.singular_intervals],
                "state_constraint_active_intervals": [
                    list(map(float, i)) for i in self.state_constraint_active_intervals],
                "costate_estimates_gap": f(self.costate_estimates_gap), "source": self.source,
                "numerical_error": {k: f(v) for k, v in self.numerical_error.items()},
                "checked_from": float(self.checked_from),
                "per_control": {c: {k: f(v) for k, v in d.items()}
                                for c, d in self.per_control.items()},
                "elapsed_s": float(self.elapsed),
                "chattering": self.chattering.to_dict() if self.chattering else None}


# ------------------------------------------------------------------ helpers
def intervals_of(t: np.ndarray, mask: np.ndarray, min_len: float) -> list[tuple[float, float]]:
    """Maximal runs of ``mask`` as ``(t_first, t_last)``, at least ``min_len`` long.

    Parameters
    ----------
    t : ndarray (m,)
        Sample times.
    mask : ndarray of bool (m,)
    min_len : float

    Returns
    -------
    list of (float, float)
    """
    out: list[tuple[float, float]] = []
    k, n = 0, len(mask)
    while k < n:
        if mask[k]:
            j = k
            while j + 1 < n and mask[j + 1]:
                j += 1
            if t[j] - t[k] >= min_len:
                out.append((float(t[k]), float(t[j])))
            k = j + 1
        else:
            k += 1
    return out


def sign_changes(t: np.ndarray, s: np.ndarray, tiny: float) -> np.ndarray:
    """Times where ``s`` changes sign, by linear interpolation.

    Parameters
    ----------
    t, s : ndarray (m,)
        Sample times and values.
    tiny : float
        Samples with ``|s| <= tiny`` are skipped (a crossing may land on a sample).

    Returns
    -------
    ndarray
    """
    nz = np.flatnonzero(np.abs(s) > tiny)
    a, b = nz[:-1], nz[1:]
    ch = np.sign(s[a]) != np.sign(s[b])
    a, b = a[ch], b[ch]
    return t[a] - s[a] * (t[b] - t[a]) / (s[b] - s[a])


def switch_gap(t: np.ndarray, s: np.ndarray, zeros: np.ndarray, ts: float) -> float:
    """Time between a switch at ``ts`` and the zero of the switching function ``s``.

    When ``ts`` is a sample time (a refined junction) and ``s`` changes sign
    across it, the gap is ``|s(ts)| / |s'|`` (``s'`` from the neighbouring
    samples): exact to rounding, unlike an interpolated zero. Otherwise it is
    the distance to the nearest interpolated sign change.

    Parameters
    ----------
    t, s : ndarray (m,)
        Sample times and switching-function values.
    zeros : ndarray
        Its interpolated sign changes (:func:`sign_changes`).
    ts : float
        The switch time.

    Returns
    -------
    float
        ``inf`` when there is no sign change at all.
    """
    span = max(float(t[-1] - t[0]), 1.0) if len(t) else 1.0
    at = np.flatnonzero(np.abs(t - ts) <= 1e-12 * span)
    if len(at):
        i0, i1 = int(at[0]), int(at[-1])
        if i0 > 0 and i1 + 1 < len(t) and np.sign(s[i0 - 1]) != np.sign(s[i1 + 1]):
            slope = abs(s[i1 + 1] - s[i0 - 1]) / max(float(t[i1 + 1] - t[i0 - 1]), 1e-300)
            return float(np.max(np.abs(s[at]))) / max(slope, 1e-300)
    return float(np.min(np.abs(zeros - ts))) if len(zeros) else math.inf


def is_mixed(pr: OptimalControlProblem, name: str | None) -> bool:
    """True when path constraint ``name`` involves a control (a mixed constraint
    ``c(x, u)``): held on a boundary arc it bounds the control, the costate does not jump.

    Parameters
    ----------
    pr : OptimalControlProblem
    name : str or None
        A path constraint's name (None: False).
    """
    return any(c.name == name and ca.depends_on(c.expr, pr.u) for c in pr.path)


def effective_bounds(pr: OptimalControlProblem, x: np.ndarray,
                     pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Control bounds tightened by the mixed constraints, at each sample: (m, nu) each.

    A mixed constraint ``lo <= a(x) + b(x) u_j <= hi`` affine in one control ``u_j``
    bounds it to an interval; the minimum principle then selects the ends of the
    intersection. Constraints in several controls are not used here: linear
    control-only ones couple controls into a polytope, checked by
    ``_coupled_figures`` (the Hamiltonian minimised over it, a linear programme).

    Parameters
    ----------
    pr : OptimalControlProblem
    x : ndarray (m, nx)
        States at the samples.
    pv : ndarray
        Parameter values.
    """
    m = len(x)
    los, his = np.empty((m, pr.nu)), np.empty((m, pr.nu))
    for j, name in enumerate(pr.control_names):
        lo, hi = pr.control_bounds[name]
        los[:, j], his[:, j] = (float(v) for v in ca.Function("b", [pr.p], [lo, hi])(pv))
    for c in pr.path:
        uses = [j for j in range(pr.nu) if ca.depends_on(c.expr, pr.u[j])]
        if len(uses) != 1 or ca.depends_on(ca.jacobian(c.expr, pr.u), pr.u):
            continue
        j = uses[0]
        a = ca.substitute(c.expr, pr.u, ca.DM.zeros(pr.nu))
        fn = ca.Function("ab", [pr.x, pr.p], [a, ca.jacobian(c.expr, pr.u[j]), c.lower,
                                              c.upper])
        av, bv, lc, hc = (v.ravel() for v in along(fn, x, pv))
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = np.stack([(lc - av) / bv, (hc - av) / bv])
        ok = np.abs(bv) > 1e-300
        los[ok, j] = np.maximum(los[ok, j], np.min(ends, axis=0)[ok])
        his[ok, j] = np.minimum(his[ok, j], np.max(ends, axis=0)[ok])
    return los, his


def path_activity_along(pr: OptimalControlProblem, x: np.ndarray, u: np.ndarray,
                        pv: np.ndarray, tol: float, state_only: bool = False) -> np.ndarray:
    """Where some path constraint is within ``tol * max(1, |value|)`` of a limit.

    Parameters
    ----------
    pr : OptimalControlProblem
    x, u : ndarray (m, nx), (m, nu)
        States and controls at the samples.
    pv : ndarray
        Parameter values.
    tol : float
    state_only : bool
        Leave out the mixed constraints (those involving a control).

    Returns
    -------
    ndarray of bool (m,)
    """
    cons = [c for c in pr.path if not (state_only and ca.depends_on(c.expr, pr.u))]
    if not cons:
        return np.zeros(len(x), dtype=bool)
    fn = ca.Function("hp", [pr.x, pr.u, pr.p], [ca.vertcat(*[c.expr for c in cons]),
                                                 ca.vertcat(*[c.lower for c in cons]),
                                                 ca.vertcat(*[c.upper for c in cons])])
    v, lo, hi = along(fn, x, u, pv)
    sc = tol * np.maximum(1.0, np.abs(v))
    return np.any((np.abs(v - lo) <= sc) | (np.abs(v - hi) <= sc), axis=1)


def _singular_runs(t: np.ndarray, s: np.ndarray, unclear: np.ndarray, band: float,
                   min_len: float, interior: np.ndarray | None) -> list[tuple[float, float]]:
    """Runs where ``|s| <= band`` at least ``min_len`` long that are not a transversal
    zero crossing.

    A crossing with slope ``s'`` spends ``band / |s'|`` on each side of its zero
    inside the band, whatever the grid: a run that changes sign across it and
    is no longer than twice what the local slopes on both sides predict (plus
    two sample spacings) is a switch, not a singular arc. With ``interior``
    (samples where the control is strictly inside its bounds; a transcription),
    a run also needs the control inside its bounds on half of it: a short bang
    arc whose sigma is small but of one sign is not singular.
    """
    out: list[tuple[float, float]] = []
    idx = np.flatnonzero(unclear)
    if not len(idx):
        return out
    splits = np.flatnonzero(np.diff(idx) > 1) + 1
    for run in np.split(idx, splits):
        a, b = int(run[0]), int(run[-1])
        if t[b] - t[a] < min_len:
            continue
        if a >= 2 and b + 2 < len(t) and np.sign(s[a - 1]) != np.sign(s[b + 1]):
            sl = abs(s[a - 1] - s[a - 2]) / max(t[a - 1] - t[a - 2], 1e-300)
            sr = abs(s[b + 2] - s[b + 1]) / max(t[b + 2] - t[b + 1], 1e-300)
            spacing = max(t[a] - t[a - 1], t[b + 1] - t[b])
            if t[b] - t[a] <= 2 * (band / max(sl, 1e-300) + band / max(sr, 1e-300)) \
                    + 2 * spacing:
                continue
        if interior is not None and np.mean(interior[a:b + 1]) < 0.5:
            continue
        out.append((float(t[a]), float(t[b])))
    return out


@dataclass
class _Figures:
    """H, sigma and the checks on one set of samples."""

    H: np.ndarray
    sigma: np.ndarray
    H_scale: float
    H_max_abs: float
    H_var: float
    agreement: dict[str, float]
    gap: dict[str, float]
    singular: list[tuple[float, float]]
    zeros: dict[str, np.ndarray]
    linear: bool = True


def _figures(pr: OptimalControlProblem, params: dict, t: np.ndarray, x: np.ndarray,
             u: np.ndarray, lam: np.ndarray, H_exp: float | None, skip: np.ndarray,
             switches: dict[str, list[float]], tol_sigma: float, sigma_floor: np.ndarray,
             u_tol: float, min_singular: float, interior_check: bool = False,
             bounds: tuple[np.ndarray, np.ndarray] | None = None) -> _Figures:
    """Evaluate H and sigma and the sign, switch and singularity checks.

    ``skip`` marks samples not judged (constrained, or unresolved by the grid);
    ``sigma_floor`` (nu,) is the absolute size below which sigma counts as zero
    besides ``tol_sigma`` times its scale (the numerical error band); a control
    within ``u_tol`` of a bound (relative to the range) sits at it;
    ``interior_check`` (a transcription) counts a run of small sigma as
    singular only where the control is inside its bounds; ``bounds`` (lower, upper),
    each (m, nu), are the control bounds at each sample when mixed constraints
    tighten them (see :func:`effective_bounds`).
    """
    pv = np.array([params[k] for k in pr.param_names], dtype=float)
    fns = pmp_functions(pr)
    if not fns.linear:
        Huu = along(fns.Huu, x, pv)[0].reshape(len(x), pr.nu, pr.nu)
        if np.min(np.linalg.eigvalsh(Huu), initial=0.0) < -1e-12 * max(1.0, np.max(np.abs(Huu))):
            raise ValueError("H is not convex in u along the solution: the minimum condition "
                             "cannot be checked through dH/du")
    H = along(fns.H, x, u, lam, pv)[0].ravel()
    sigma = along(fns.sigma, x, u, lam, pv)[0]
    terms = along(fns.sigma_terms, x, u, lam, pv)[0]
    xdot = along(pr.dynamics_function(), x, u, pv)[0]
    H_scale = float(np.max(np.sum(np.abs(lam * xdot), axis=1), initial=0.0)) or 1.0
    judged = ~skip
    ref_H = H_exp if H_exp is not None else float(np.mean(H[judged])) if judged.any() else 0.0
    H_max_abs = float(np.max(np.abs(H[judged] - ref_H), initial=0.0)) / H_scale
    H_var = float(np.ptp(H[judged])) / H_scale if judged.any() else 0.0
    dt = np.gradient(t) if len(t) > 1 else np.ones(len(t))
    agreement, gap, zeros = {}, {}, {}
    singular: list[tuple[float, float]] = []
    # H linear in u: minimised at a vertex of the control polytope (else per control)
    coupled = _coupled_figures(pr, pv, t, u, sigma, terms, judged, switches, tol_sigma,
                               sigma_floor, u_tol, min_singular, interior_check) \
        if fns.linear else {}
    for name, (frac, g, zc, runs) in coupled.items():
        agreement[name], gap[name], zeros[name] = frac, g, zc
        singular += [r for r in runs if r not in singular]
    for j, name in enumerate(pr.control_names):
        if name in coupled:
            continue
        lo, hi = control_bounds_at(pr, name, params)
        s = sigma[:, j]
        s_scale = float(np.max(np.r_[np.abs(s[judged]), terms[judged, j]], initial=0.0)) or 1.0
        band = max(tol_sigma * s_scale, float(sigma_floor[j]))
        clear = (np.abs(s) > band) & judged
        inside = None
        if interior_check:  # a transcription: a singular arc has its control inside
            room = u_tol * max(1.0, hi - lo) if np.isfinite(hi - lo) else 0.0
            inside = (u[:, j] > lo + room) & (u[:, j] < hi - room)
        singular += _singular_runs(t, s, ~clear & judged, band, min_singular, inside)
        want = np.where(s < 0, hi, lo) if bounds is None else \
            np.where(s < 0, bounds[1][:, j], bounds[0][:, j])
        agree = np.isfinite(want) & (np.abs(u[:, j] - want) <= u_tol * max(1.0, hi - lo))
        agreement[name] = float(np.sum(dt[clear & agree]) / max(np.sum(dt[clear]), 1e-300)) \
            if clear.any() else 1.0
        zc = sign_changes(t, s, 1e-14 * s_scale)
        zeros[name] = zc
        gap[name] = max((switch_gap(t, s, zc, ts) for ts in switches.get(name, [])),
                        default=0.0)
    return _Figures(H, sigma, H_scale, H_max_abs, H_var, agreement, gap, singular, zeros,
                    fns.linear)


def _coupled_figures(pr: OptimalControlProblem, pv: np.ndarray, t: np.ndarray, u: np.ndarray,
                    sigma: np.ndarray, terms: np.ndarray, judged: np.ndarray,
                    switches: dict[str, list[float]], tol_sigma: float,
                    sigma_floor: np.ndarray, u_tol: float, min_singular: float,
                    interior_check: bool) -> dict[str, tuple[float, float, np.ndarray,
                                                             list[tuple[float, float]]]]:
    """Sign, switch and singularity checks of controls coupled by control-only constraints.

    For a group of controls whose admissible set is a polytope ``P``
    (:mod:`ocp.control_set`) the minimum principle asks ``u = argmin sigma^T v over
    v in P``: at every sample the vertex scores give the minimiser, unique where the
    best vertex beats the second best by more than the band (``tol_sigma`` times the
    group's sigma scale, or the group's ``sigma_floor``). Agreement is the fraction
    of those clear samples (by time) where each control equals the minimiser's
    component; a switch of a control must sit where the minimising vertex changes;
    a run where the programme stays degenerate (no unique minimiser) for at least
    ``min_singular`` is singular.

    Parameters
    ----------
    pr : OptimalControlProblem
    pv : ndarray
        Parameter values.
    t, u, sigma, terms : ndarray
        Sample times, controls (m, nu), switching functions (m, nu) and the sizes of
        their terms (m, nu).
    judged : ndarray of bool (m,)
        Samples that are judged.
    switches : dict
        Switch times per control.
    tol_sigma, sigma_floor, u_tol, min_singular, interior_check
        As in :func:`_figures`.

    Returns
    -------
    dict
        Per coupled control: ``(agreement, switch gap, vertex-change times, singular runs)``.
        Groups whose polytope cannot be enumerated (unbounded, too large) are left out
        (their controls get the per-control checks).
    """
    out: dict[str, tuple[float, float, np.ndarray, list[tuple[float, float]]]] = {}
    dt = np.gradient(t) if len(t) > 1 else np.ones(len(t))
    for group in coupled_groups(pr, singletons=True):
        poly = control_polytope(pr, group, pv)
        if poly is None:
            continue
        idx = list(poly.index)
        sc = vertex_scores(poly, sigma[:, idx])
        scale = float(np.max(np.r_[np.abs(sigma[judged][:, idx]).ravel(),
                                   terms[judged][:, idx].ravel()], initial=0.0)) or 1.0
        band = max(tol_sigma * scale, float(np.max(sigma_floor[idx], initial=0.0)))
        clear = (sc.gap > band) & judged
        inside = distance_to_vertices(poly, u[:, idx]) > u_tol if interior_check else None
        runs = _singular_runs(t, sc.signed, ~clear & judged, band, min_singular, inside)
        want = poly.vertices[sc.best]
        zc = sign_changes(t, sc.signed, 1e-14 * scale)
        for c, (name, j) in enumerate(zip(poly.controls, idx, strict=True)):
            rng = float(poly.span[c])
            agree = np.abs(u[:, j] - want[:, c]) <= u_tol * rng
            frac = float(np.sum(dt[clear & agree]) / max(np.sum(dt[clear]), 1e-300)) \
                if clear.any() else 1.0
            g = max((switch_gap(t, sc.signed, zc, ts) for ts in switches.get(name, [])),
                    default=0.0)
            out[name] = (frac, g, zc, runs)
    return out


@dataclass
class _Tolerances:
    H: float
    sigma: float
    switch: float
    singular: float


def _judge(fig: _Figures, tol: _Tolerances, err: dict[str, float],
           expected_H: bool) -> tuple[list[str], list[str]]:
    """Reasons for definite failures and for failures inside the error band."""
    definite: list[str] = []
    uncertain: list[str] = []

    def check(value: float, limit: float, error: float, text: str) -> None:
        if value <= limit:
            return
        if value <= ERROR_MARGIN * error:
            uncertain.append(f"{text}, but that is within {ERROR_MARGIN:g}x the certificate's "
                             f"own numerical error ({error:.1e}): cannot decide")
        else:
            definite.append(text)

    what = "its free-T value" if expected_H else "a constant"
    check(fig.H_max_abs, tol.H, err.get("H", 0.0),
          f"H deviates from {what} by {fig.H_max_abs:.2e} of its scale (> {tol.H:g})")
    for name, frac in fig.agreement.items():
        if frac < 0.99:
            definite.append(f"{name} sits at the bound (or vertex of its control set) "
                            f"that minimises H only {frac:.1%} of the time")
    for name, g in fig.gap.items():
        check(g, tol.switch, err.get("switch", 0.0),
              f"a switch of {name} is {g:.2e} away from the nearest sign change of its sigma")
    if fig.singular:
        spans = ", ".join(f"[{a:.4g}, {b:.4g}]" for a, b in fig.singular)
        what = ("a singular arc" if fig.linear else
                "an interior arc (u minimises H inside its bounds)")
        definite.append(f"sigma vanishes on {len(fig.singular)} interval(s) ({spans}): {what}")
    return definite, uncertain


def _verdict(definite: list[str], uncertain: list[str], active: list[tuple[float, float]],
             checked_from: float, T: float) -> tuple[str, list[str]]:
    reasons = definite + uncertain
    if definite:
        return NOT_BANG_BANG, reasons
    if uncertain:
        return INCONCLUSIVE, reasons
    if active or checked_from > 0:
        spans = ", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in active) or "isolated points"
        where = (f"checked on [{checked_from:.6g}, {T:.6g}] only" if checked_from > 0
                 else "excluded from the checks")
        return INCONCLUSIVE, reasons + [
            f"state constraint active on {spans}: the bang-bang argument does not apply there "
            f"({where})"]
    return CERTIFIED, reasons


# ------------------------------------------------------------- certificates
def certify(sol: SolutionLike, refined: Any = None, *,
            tol_H: float | None = None, tol_sigma: float | None = None,
            tol_switch: float | None = None, min_singular: float | None = None,
            n: int = 2000, verify: bool = True, structure: ArcStructure | None = None,
            chattering: bool = True, max_nodes: int = 1000) -> PMPCertificate:
    """Check Pontryagin's necessary conditions for bang-bang structure along a candidate.

    What a verdict means:

    * ``"bang-bang certified"``: along *this candidate* the minimum principle's
      necessary conditions hold to the stated tolerances (H constant, or equal
      to its free-T value; every control at the bound ``sign(sigma)`` selects;
      switches at sign changes of sigma; no singular interval), structure
      detection finds only bang (and boundary) arcs, and no chattering is
      seen. It is a local statement: the candidate is an extremal, not
      necessarily the global optimum (another extremal may be better: several
      starts find them);
    * ``"not bang-bang"``: this candidate *fails* the conditions beyond their
      tolerance and the certificate's own numerical error (from a transcription
      alone, also on a grid twice as fine): e.g. a singular arc, or a control
      off the bound sigma selects;
    * ``"inconclusive"``: nothing refutes, but something prevents the
      certificate: a violation inside the error band, a state constraint
      active, or an interior (singular, free or unresolved) arc that structure
      detection finds (``"structure detection finds an interior arc on
      [a, b] ..."``), which is never certified bang-bang;
    * ``"chattering suspected"`` (:data:`CHATTERING`): switch intervals shrink
      geometrically toward a point ``t*`` and a finer grid resolves more of
      them (:func:`detect_chattering`, reported in ``cert.chattering``): a
      control that chatters switches infinitely often, so no finite bang-bang
      structure is certified. It takes precedence over the other verdicts (the
      checks' own reasons follow it);
    * ``"not applicable: the solve did not converge"`` (:data:`NOT_APPLICABLE`):
      ``sol.success`` is False (e.g. the iterate of an
      :class:`~ocp.errors.InfeasibleError`), or ``refined`` is the iterate of a
      failed refinement; the reasons give Ipopt's status. ``"not applicable:
      the solution is not verified"`` (:data:`UNVERIFIED`): ``sol.verified`` is
      False (a path constraint violated between nodes) and there is no
      ``refined`` (which would be the candidate then). Nothing is checked
      then: a certificate of a point that is not a converged optimum would
      mean nothing.

    Parameters
    ----------
    sol : Solution
        The transcribed solution (its multipliers give the first costate
        estimate, and its nodes the state-constraint activity).
    refined : RefinedSwitching or RefinedPhases, optional
        The refined solution; when given, H and sigma are evaluated on it with
        the adjoint-integrated costate, and the two estimates compared. A
        multi-phase solution needs its :class:`~ocp.phase_refinement.RefinedPhases`
        and gets a :class:`~ocp.phase_pmp.PhasesCertificate` (phase by phase, with
        the junction conditions checked).
    tol_H : float, optional
        Allowed ``H_max_abs`` (relative to ``H_scale``): default 1e-6 on a
        refined solution, 1e-2 on the transcription alone.
    tol_sigma : float, optional
        ``|sigma_j| <= tol_sigma * max|sigma_j|`` counts as zero: default 1e-6
        refined, 1e-2 transcribed.
    tol_switch : float, optional
        Allowed switch/sign-change gap (default: 1e-6 T refined, 1.5 h otherwise).
    min_singular : float, optional
        Shortest interval of ``sigma ~ 0`` reported as singular (default 2 h).
    n : int
        About how many samples along a refined solution.
    verify : bool
        Transcription alone: re-check a would-be refutation on a grid twice as
        fine (a new transcription, solved from this one); without it such a
        result is only "inconclusive". Also allows the re-solve that confirms
        chattering.
    structure : ArcStructure, optional
        The arc structure to hold the verdict to (default: :func:`detect_structure`
        of ``sol``); with ``refined`` from a structure of your own, pass that one. An
        interior arc in it forbids "bang-bang certified".
    chattering : bool
        Look for chattering (:func:`detect_chattering`).
    max_nodes : int
        Largest grid the chattering confirmation may solve.

    Returns
    -------
    PMPCertificate
    """
    if getattr(sol, "is_multiphase", False) or type(refined).__name__ == "RefinedPhases":
        from .phase_pmp import certify_phases
        from .phase_refinement import RefinedPhases

        if not isinstance(refined, RefinedPhases):
            raise ValueError("a multi-phase solution is certified with its refinement: "
                             "certify(sol, ocp.phase_refinement.refine_phases(sol))")
        # (certify_phases refuses a failed solve or refinement itself)
        return certify_phases(sol, refined, tol_H=tol_H, tol_sigma=tol_sigma,  # type: ignore
                              tol_switch=tol_switch, min_singular=min_singular, n=n)
    refused = refusal(sol, refined)
    if refused is not None:
        return refused
    tsol = transcribed(sol)
    t0 = time.process_time()
    pr = tsol.problem
    pmp_functions(pr)  # raises early on problems that are not control-affine
    h = tsol.T / tsol.N
    tol = _Tolerances(H=tol_H if tol_H is not None else (1e-6 if refined else 1e-2),
                      sigma=tol_sigma if tol_sigma is not None else (1e-6 if refined else 1e-2),
                      switch=math.nan, singular=2 * h if min_singular is None else min_singular)
    if refined is not None:
        tol.switch = 1e-6 * refined.T if tol_switch is None else tol_switch
        cert = _certify_refined(tsol, refined, tol, n)
    else:
        tol.switch = 1.5 * h if tol_switch is None else tol_switch
        cert = _certify_transcription(tsol, tol, verify, tol_switch is None)
    _against_structure(cert, detect_structure(tsol) if structure is None else structure)
    if chattering:
        found = detect_chattering(tsol, resolve=verify, max_nodes=max_nodes)
        if found is not None:
            cert.chattering = found
            cert.reasons = [found.reason, *cert.reasons]
            cert.verdict = CHATTERING
    cert.elapsed = time.process_time() - t0
    return cert


def refusal(sol: SolutionLike | None, refined: Any = None) -> PMPCertificate | None:
    """The "not applicable" certificate of a solution that is no converged, verified optimum.

    Parameters
    ----------
    sol : Solution or None
        A transcribed solution: refused when ``success`` is False (:data:`NOT_APPLICABLE`)
        or, certified alone (no ``refined``), when ``verified`` is False (:data:`UNVERIFIED`).
    refined : RefinedSwitching or RefinedPhases, optional
        Refused when its ``success`` is False (the iterate of a failed refinement).

    Returns
    -------
    PMPCertificate or None
        None when nothing is refused.
    """
    if sol is not None and getattr(sol, "success", True) is False:
        return not_applicable(NOT_APPLICABLE, [
            f"the transcription's solve did not converge (Ipopt status "
            f"{getattr(sol, 'status', '?')}): its iterate is no optimum, nothing is checked"])
    if refined is not None and getattr(refined, "success", True) is False:
        return not_applicable(NOT_APPLICABLE, [
            f"the switching refinement did not converge (status "
            f"{getattr(refined, 'status', '?')}): its iterate is no optimum, nothing is "
            "checked"])
    if refined is None and sol is not None and getattr(sol, "verified", None) is False:
        # (with a refinement, the candidate is the refined solution: the transcription
        # only started it, and its violation between nodes is the grid's)
        viol = getattr(sol, "path_violation", math.nan)
        return not_applicable(UNVERIFIED, [
            f"the transcription violates its path constraints between nodes (by {viol:.2e}, "
            f"{sorted(getattr(sol, 'violations', {}))}): not a verified solution, nothing is "
            "checked"])
    return None


def not_applicable(verdict: str, reasons: list[str],
                   cls: type[PMPCertificate] = PMPCertificate) -> PMPCertificate:
    """A certificate with a "not applicable" verdict and no figures (all NaN).

    Parameters
    ----------
    verdict : str
        :data:`NOT_APPLICABLE` or :data:`UNVERIFIED`.
    reasons : list of str
    cls : type
        :class:`PMPCertificate` or a subclass whose extra fields have defaults.
    """
    nan = math.nan
    return cls(verdict, reasons, None, nan, nan, nan, nan, nan, [], [], nan,
               "none (refused)")


def _interior_arcs(structure: ArcStructure) -> list[tuple[str, float, float]]:
    """``(control, start, end)`` of every interior arc of the structure."""
    return [(s.control, a.start, a.end) for s in structure.per_control for a in s.arcs
            if a.kind == "interior"]


def _against_structure(cert: PMPCertificate, structure: ArcStructure) -> None:
    """Never certify what structure detection doubts: an interior arc (singular, free or
    unresolved by the grid) makes a "bang-bang certified" verdict "inconclusive"."""
    interior = _interior_arcs(structure)
    if not interior and structure.refinable:
        return
    spans = ", ".join(f"[{a:.6g}, {b:.6g}] ({c})" for c, a, b in interior) or "some control"
    reason = (f"structure detection finds an interior arc on {spans}: a singular, free or "
              "unresolved arc (refine_switching refuses it), never certified bang-bang")
    if cert.verdict == CERTIFIED:
        cert.verdict = INCONCLUSIVE
    if cert.verdict != NOT_BANG_BANG:  # a refutation stands on its own checks
        cert.reasons = [*cert.reasons, reason]


def detect_chattering(sol: SolutionLike, *, resolve: bool = True,
                      max_nodes: int = 1000) -> ChatteringResult | None:
    """Switches whose intervals shrink geometrically toward a point (chattering).

    Reads the sign changes of the switching functions of a transcription (costates
    from its multipliers) and, with ``resolve``, confirms a suspicion by a re-solve
    on a grid fine enough to resolve the next predicted switch
    (:func:`finer_transcription`): the run must gain switches. See
    :mod:`ocp.chattering`.

    Parameters
    ----------
    sol : Solution
        A converged transcribed solution.
    resolve : bool
        Allow the confirming re-solve (without it, only runs of at least
        :data:`ocp.chattering.MIN_RUN_UNCONFIRMED` shrinking intervals count).
    max_nodes : int
        Largest grid the confirmation may solve.

    Returns
    -------
    ChatteringResult or None
        ``t_star``, ``ratio``, ``switch_times``, ``counts`` (nodes -> switches in the
        run); None when no chattering is seen.
    """
    return chattering_of(sol, resolve=finer_transcription if resolve else None,
                         max_nodes=max_nodes, samples=_transcription_samples)


def _effective_switches(ref: RefinedSwitching, after: float) -> dict[str, list[float]]:
    """Switch times of every control after ``after``, ignoring zero-length intervals."""
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    tiny = 1e-10 * max(edges[-1], 1.0)
    out: dict[str, list[float]] = {}
    im = ref.interval_modes
    for j, name in enumerate(ref.controls):
        modes = [(im[k][j], edges[k + 1]) for k in range(len(ref.durations))
                 if ref.durations[k] > tiny]
        out[name] = [float(e) for (m, e), (m2, _) in zip(modes[:-1], modes[1:], strict=True)
                     if m != m2 and e > after + tiny]
    return out


def _constrained_refined(ref: RefinedSwitching, n: int) -> tuple[list[tuple[float, float]],
                                                                 float]:
    """State-constrained intervals of a refined solution, and the last time the costate
    may jump (end of a boundary arc, or a path constraint binding at a sample)."""
    edges = np.r_[0.0, np.cumsum(ref.durations)]
    T = float(edges[-1])
    tiny = 1e-10 * max(T, 1.0)
    pr = ref.problem
    # boundary arcs of state constraints; a zero-length one is a touch point (the costate
    # may jump there too)
    bnd = [(float(edges[k]), float(edges[k + 1])) for k, ms in enumerate(ref.interval_modes)
           if any(m.kind == "boundary" and not is_mixed(pr, m.constraint) for m in ms)]
    last = max((b for _, b in bnd), default=0.0)
    t, x, u, _ = ref.samples(n)
    act = path_activity_along(pr, x, u, ref.pv, 1e-7, state_only=True) & (t > tiny) & \
        (t < T - tiny)
    dense = intervals_of(t, act, 2 * T / max(len(t), 1))
    if ref.nlp is not None and "path" in ref.blocks and len(ref.lam_g):
        rows = ref.blocks["path"]
        lam = np.abs(ref.lam_g[rows])
        binding = lam > 1e-8 * max(1.0, float(np.max(np.abs(ref.lam_g))))
        if binding.any():
            last = max(last, float(np.max(ref.nlp.row_times(ref.w)[rows][binding])))
    merged: list[tuple[float, float]] = []
    for a, b in sorted(bnd + dense):
        if merged and a <= merged[-1][1] + tiny:
            merged[-1] = (merged[-1][0], max(b, merged[-1][1]))
        else:
            merged.append((a, b))
    return merged, last


def _certify_refined(sol: TranscribedSolution, ref: RefinedSwitching, tol: _Tolerances,
                     n: int) -> PMPCertificate:
    pr = ref.problem
    active, last = _constrained_refined(ref, n)
    sw = adjoint_sweep(ref, last, n)
    T = float(np.sum(ref.durations))
    tiny = 1e-10 * max(T, 1.0)
    keep = (sw.t >= last - tiny) & (ref.durations[sw.interval] > tiny)
    switches = _effective_switches(ref, last)
    floor = np.zeros(pr.nu)
    args = (switches, tol.sigma)
    mixed = any(ca.depends_on(c.expr, pr.u) for c in pr.path)
    eff = effective_bounds(pr, sw.x[keep], ref.pv) if mixed else None
    fig = _figures(pr, ref.params, sw.t[keep], sw.x[keep], sw.u[keep], sw.lam[keep],
                   sw.H_expected, np.zeros(int(keep.sum()), bool), *args, floor, 1e-9,
                   tol.singular, bounds=eff)
    base = (ref.integration_error or 0.0) + sw.error_x
    err = {"H": base, "sigma": 0.0, "switch": 0.0, "costate": sw.error_lam, "state": sw.error_x}
    if sw.coarse is not None:
        c = sw.coarse
        cf = _figures(pr, ref.params, c.t[keep], c.x[keep], c.u[keep], c.lam[keep],
                      c.H_expected, np.zeros(int(keep.sum()), bool), *args, floor, 1e-9,
                      tol.singular, bounds=effective_bounds(pr, c.x[keep], ref.pv)
                      if mixed else None)
        err["H"] += float(np.max(np.abs(fig.H - cf.H), initial=0.0)) / fig.H_scale
        dsig = np.max(np.abs(fig.sigma - cf.sigma), axis=0, initial=0.0)
        err["sigma"] = float(np.max(dsig / np.maximum(np.max(np.abs(fig.sigma), axis=0), 1e-300)))
        err["switch"] = max((abs(fig.gap[k] - cf.gap[k]) for k in fig.gap
                             if math.isfinite(fig.gap[k]) and math.isfinite(cf.gap[k])),
                            default=0.0)
        # samples inside the numerical error band of sigma are not judged
        fig = _figures(pr, ref.params, sw.t[keep], sw.x[keep], sw.u[keep], sw.lam[keep],
                       sw.H_expected, np.zeros(int(keep.sum()), bool), *args,
                       ERROR_MARGIN * dsig, 1e-9, tol.singular, bounds=eff)
    definite, uncertain = _judge(fig, tol, err, sw.H_expected is not None)
    verdict, reasons = _verdict(definite, uncertain, active, last, T)
    gap_lam = _costate_gap(sol, ref, sw.t[keep], sw.lam[keep], last)
    src = "refined (adjoint integrated with the state along the refined arcs: " + (
        "exact arcs)" if ref.exact else f"RK8, error measured {sw.error_lam:.1e})")
    return _certificate(verdict, reasons, sw.H_expected, fig, active, gap_lam, src,
                        sw.t[keep], sw.lam[keep], sw.u[keep], err, last)


def _costate_gap(sol: TranscribedSolution, ref: RefinedSwitching, t: np.ndarray, lam: np.ndarray,
                 start: float) -> float:
    """Largest difference between the multiplier and the adjoint costates, relative."""
    t_tr, lam_tr = costates_from_multipliers(sol)
    h = sol.T / sol.N
    # common horizon, without the transcription's last interval (where its final
    # time, and any constrained tail, differ from the refined ones)
    sel = (t_tr <= min(float(np.sum(ref.durations)), sol.T) - h) & (t_tr >= start + h)
    if not sel.any() or len(t) < 2:
        return math.nan
    order = np.argsort(t, kind="stable")
    lam_i = np.column_stack([np.interp(t_tr[sel], t[order], lam[order, j])
                             for j in range(lam.shape[1])])
    return float(np.max(np.abs(lam_i - lam_tr[sel])) / max(np.max(np.abs(lam)), 1e-300))


def _certificate(verdict: str, reasons: list[str], H_exp: float | None, fig: _Figures,
                 active: list[tuple[float, float]], gap_lam: float, source: str,
                 t: np.ndarray, lam: np.ndarray, u: np.ndarray, err: dict[str, float],
                 checked_from: float) -> PMPCertificate:
    single = u.ndim == 2 and u.shape[1] == 1
    per = {k: {"sigma_sign_agreement": fig.agreement[k], "switch_sigma_gap": fig.gap[k]}
           for k in fig.agreement}
    return PMPCertificate(
        verdict, reasons, H_exp, fig.H_max_abs, fig.H_var, fig.H_scale,
        min(fig.agreement.values(), default=1.0), max(fig.gap.values(), default=0.0),
        fig.singular, active, gap_lam, source, t, lam, fig.H,
        fig.sigma[:, 0] if single else fig.sigma, u[:, 0] if single else u, err,
        checked_from, per)


def _transcription_samples(sol: TranscribedSolution) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray]:
    """Times t_1..t_N, states, controls and multiplier costates: at the nodes with the
    control after each node (multiple shooting), or at every collocation point with its
    collocated control (collocation)."""
    t, lam = costates_from_multipliers(sol)
    u = np.asarray(sol.u) if is_collocation(sol) else np.vstack([sol.u[1:], sol.u[-1:]])
    return t, sol.x[1:], u, lam


def _constrained_transcription(sol: TranscribedSolution) -> list[tuple[float, float]]:
    """Intervals where a path constraint is active in a transcription: nodes at a limit
    (to 1e-6) over at least one interval, and the boundary arcs :func:`detect_arcs`
    finds (which bridge the zig-zag of a transcription along a constraint)."""
    # control-only constraints shape the control set: they are no state constraint
    act = active_path_constraints(sol, 1e-6, kinds=(STATE, MIXED))
    act_nodes = act.any(axis=1) if act.size else np.zeros(sol.N + 1, dtype=bool)
    spans = intervals_of(sol.t, np.asarray(act_nodes), _shortest_interval(sol) - 1e-12)
    for name in sol.problem.control_names:
        spans += [(a.start, a.end) for a in detect_arcs(sol, name).arcs if a.kind == "boundary"]
    merged: list[tuple[float, float]] = []
    for a, b in sorted(spans):
        if merged and a <= merged[-1][1] + 1e-12:
            merged[-1] = (merged[-1][0], max(b, merged[-1][1]))
        else:
            merged.append((float(a), float(b)))
    return merged


def _shortest_interval(sol: TranscribedSolution) -> float:
    """A run of active points shorter than this is a touch, not an arc: one shooting
    interval, or the shortest collocation mesh interval (its d + 1 points)."""
    if is_collocation(sol):
        return float(np.min(np.diff(mesh_level(sol).t)))
    return sol.T / sol.N


def _transcription_figures(sol: TranscribedSolution, tol: _Tolerances
                           ) -> tuple[_Figures, float | None, list, np.ndarray]:
    pr = sol.problem
    pv = np.array([sol.params[k] for k in pr.param_names], dtype=float)
    t, x, u, lam = _transcription_samples(sol)
    H_exp = None
    if pr.time_free:
        nu = sol.multipliers.get("terminal", np.zeros(0))
        _, H_exp = terminal_costate(pr, sol.x[-1], sol.T, pv, nu)
    active = _constrained_transcription(sol)
    constrained = np.zeros(len(t), dtype=bool)
    for a, b in active:
        constrained |= (t >= a) & (t <= b)
    switches = {}
    for name in pr.control_names:
        st = detect_arcs(sol, name)
        switches[name] = [a.end for a, b in zip(st.arcs[:-1], st.arcs[1:], strict=True)
                          if a.kind in ("max", "min") and b.kind in ("max", "min")]
    fig = _figures(pr, sol.params, t, x, u, lam, H_exp, constrained, switches, tol.sigma,
                   np.zeros(pr.nu), 1e-3, tol.singular, interior_check=True)
    if is_collocation(sol):
        _rescore_H(fig, ~constrained & ~_kinked_points(sol, switches), H_exp)
    return fig, H_exp, active, t


def _kinked_points(sol: TranscribedSolution, switches: dict[str, list[float]]) -> np.ndarray:
    """Collocation points of the mesh intervals at and next to a switch of some control
    whose control is not at one bound at all their points: there the state polynomial
    cannot follow the kink of the state, and H (which needs the state) carries an error
    of the order of the interval, however fine the mesh; (N d,) bool."""
    pr = sol.problem
    mesh = mesh_level(sol).t
    N, d = len(mesh) - 1, len(sol.t[1:]) // max(len(mesh) - 1, 1)
    out = np.zeros(len(sol.t) - 1, dtype=bool)
    for j, name in enumerate(pr.control_names):
        lo, hi = control_bounds_at(pr, name, sol.params)
        room = 1e-3 * max(1.0, hi - lo) if np.isfinite(hi - lo) else 0.0
        U = np.asarray(sol.u)[:, j].reshape(N, d)
        one_bound = np.all(np.abs(U - hi) <= room, axis=1) | np.all(np.abs(U - lo) <= room,
                                                                    axis=1)
        for ts in switches.get(name, []):
            k = int(np.clip(np.searchsorted(mesh, ts, side="right") - 1, 0, N - 1))
            for i in range(max(k - 1, 0), min(k + 2, N)):
                if not one_bound[i]:
                    out[i * d:(i + 1) * d] = True
    return out


def _rescore_H(fig: _Figures, keep: np.ndarray, H_exp: float | None) -> None:
    """``H_max_abs`` and ``H_variation`` of ``fig`` over the samples ``keep`` only."""
    if not keep.any():
        return
    H = fig.H[keep]
    ref = H_exp if H_exp is not None else float(np.mean(H))
    fig.H_max_abs = float(np.max(np.abs(H - ref))) / fig.H_scale
    fig.H_var = float(np.ptp(H)) / fig.H_scale


def finer_transcription(sol: SolutionLike, factor: int = 2) -> Solution | None:
    """Re-solve ``sol``'s problem on a grid ``factor`` times finer, started from ``sol``.

    Parameters
    ----------
    sol : Solution
        A multiple-shooting or collocation solution.
    factor : int
        How many times more nodes (shooting) or mesh intervals (collocation: each
        interval split into ``factor`` equal ones).

    Returns
    -------
    Solution or None
        None when the transcription cannot be rebuilt or the solve fails.
    """
    tsol = transcribed(sol)
    from .transcription import Collocation, MultipleShooting

    tr = getattr(tsol, "transcription", None)
    if isinstance(tr, Collocation) and len(tr.meshes) == 1:
        return _finer_collocation(tsol, tr, factor)
    if not isinstance(tr, MultipleShooting):
        return None
    try:
        N = factor * tsol.N
        fine = MultipleShooting(tsol.problem, nodes=N, integrator=tr.integrator,
                                substeps=tr.substeps, ipopt_options=tr.ipopt_options)
        s = np.linspace(0.0, 1.0, N + 1)
        X = np.column_stack([np.interp(s, tsol.t / tsol.T, tsol.x[:, i])
                             for i in range(tsol.problem.nx)])
        U = tsol.u[np.minimum((s[:-1] * tsol.N + 1e-9).astype(int), tsol.N - 1)]
        return fine.solve(tsol.params, guess=fine.initial_guess(T=tsol.T, x=X, u=U))
    except Exception:  # any failure: the refutation stays unverified
        return None


def _finer_collocation(sol: TranscribedSolution, tr: Any, factor: int) -> Solution | None:
    """``sol`` re-solved on its mesh with every interval split into ``factor``, started from
    its polynomials (None when the solve fails)."""
    m = np.asarray(tr.meshes[0], dtype=float)
    s = np.linspace(0.0, 1.0, factor + 1)[:-1]
    fine = np.r_[(m[:-1, None] + np.diff(m)[:, None] * s[None, :]).ravel(), 1.0]
    try:
        return tr.with_mesh([fine]).solve(sol.params, guess=sol)
    except Exception:  # any failure: the refutation stays unverified
        return None


def _persistent(coarse: _Figures, fine: _Figures, tol: _Tolerances,
                tol_fine: _Tolerances) -> list[str]:
    """The violations of ``coarse`` that a grid twice as fine does not shrink."""
    out = []
    if coarse.H_max_abs > tol.H and fine.H_max_abs > max(tol_fine.H, 0.75 * coarse.H_max_abs):
        out.append(f"H deviates by {coarse.H_max_abs:.2e} of its scale, and by "
                   f"{fine.H_max_abs:.2e} on a grid twice as fine")
    for k, frac in coarse.agreement.items():
        f2 = fine.agreement.get(k, 1.0)
        if frac < 0.99 and f2 < 0.99 and 1 - f2 > 0.75 * (1 - frac):
            out.append(f"{k} sits at the bound sign(sigma) selects only {frac:.1%} of the time "
                       f"({f2:.1%} on a grid twice as fine)")
    for k, g in coarse.gap.items():
        g2 = fine.gap.get(k, 0.0)
        if g > tol.switch and g2 > max(tol_fine.switch, 0.75 * g):
            out.append(f"a switch of {k} is {g:.2e} from a sign change of its sigma "
                       f"({g2:.2e} on a grid twice as fine)")
    for a, b in coarse.singular:
        overlap = sum(max(0.0, min(b, d) - max(a, c)) for c, d in fine.singular)
        if overlap >= 0.75 * (b - a):  # a grid artefact halves with the grid
            what = "a singular arc" if coarse.linear else "an interior arc"
            out.append(f"sigma vanishes on [{a:.4g}, {b:.4g}], and still on a grid twice as "
                       f"fine: {what}")
    return out


def _certify_transcription(sol: TranscribedSolution, tol: _Tolerances, verify: bool,
                           default_switch: bool) -> PMPCertificate:
    fig, H_exp, active, t = _transcription_figures(sol, tol)
    definite, uncertain = _judge(fig, tol, {}, H_exp is not None)
    src = ("transcription (costates from collocation multipliers / Radau weights)"
           if is_collocation(sol) else "transcription (costates from continuity multipliers)")
    _, _, u, lam = _transcription_samples(sol)
    if not definite:
        verdict, reasons = _verdict([], uncertain, active, 0.0, sol.T)
        return _certificate(verdict, reasons, H_exp, fig, active, math.nan, src, t, lam, u,
                            {}, 0.0)
    found = finer_transcription(sol) if verify else None
    if found is None:
        why = "not re-checked" if not verify else "the finer grid could not be solved"
        return _certificate(INCONCLUSIVE, [*definite, f"unverified on a finer grid ({why}): "
                                           "the transcription's own error may cause it"],
                            H_exp, fig, active, math.nan, src, t, lam, u, {}, 0.0)
    fine = transcribed(found)
    tol_f = _Tolerances(tol.H, tol.sigma, tol.switch / 2 if default_switch else tol.switch,
                        tol.singular / 2)
    fig2, H2, active2, t2 = _transcription_figures(fine, tol_f)
    persistent = _persistent(fig, fig2, tol, tol_f)
    src2 = f"{src}; re-checked on {fine.N} nodes"
    _, _, u2, lam2 = _transcription_samples(fine)
    if persistent:
        return _certificate(NOT_BANG_BANG, persistent, H_exp, fig, active, math.nan, src2, t,
                            lam, u, {}, 0.0)
    d2, u2_reasons = _judge(fig2, tol_f, {}, H2 is not None)
    note = [f"on {sol.N} nodes: {r}; it shrinks on {fine.N} nodes (the grid's error)"
            for r in definite]
    if d2:
        return _certificate(INCONCLUSIVE, note + d2, H2, fig2, active2, math.nan, src2, t2,
                            lam2, u2, {}, 0.0)
    verdict, reasons = _verdict([], u2_reasons, active2, 0.0, fine.T)
    return _certificate(verdict, note + reasons, H2, fig2, active2, math.nan, src2, t2, lam2,
                        u2, {}, 0.0)


def plot_certificate(cert: PMPCertificate, title: str | None = None):
    """H, sigma and u against time on three axes, state-constrained spans shaded.

    Parameters
    ----------
    cert : PMPCertificate
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(7, 6.5))
    a1.plot(cert.t, cert.H / cert.H_scale)
    a1.set_ylabel(r"$H / H_{scale}$")
    a2.plot(cert.t, cert.sigma)
    a2.axhline(0, color="0.4", lw=0.7)
    a2.set_ylabel(r"switching function $\sigma = \lambda^T g$")
    a3.step(cert.t, cert.u, where="post")
    a3.set_ylabel("control $u$")
    a3.set_xlabel(r"time $\tau$")
    for a in (a1, a2, a3):
        a.grid(alpha=0.3)
        for lo, hi in cert.state_constraint_active_intervals:
            a.axvspan(lo, hi, color="0.85", lw=0)
    a1.set_title(title or f"PMP certificate: {cert.verdict} "
                 f"(max|H| {cert.H_max_abs:.1e}, switch gap {cert.switch_sigma_gap:.1e})",
                 fontsize=9)
    fig.tight_layout()
    return fig
