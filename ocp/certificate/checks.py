"""The checks of the minimum principle on one set of samples: figures, judgement, verdict.

Conventions as in :mod:`ocp.certificate.certify` (minimum principle, ``sigma_j = dL/du_j +
lambda^T g_j``). Given sample times, states, controls and costates, :func:`figures`
evaluates H and the switching functions and measures the checks (H constant or
equal to its free-T value, each control at the bound ``sign(sigma)`` selects,
switches at sign changes of sigma, no singular run; controls coupled by
control-only constraints are checked over their polytope, :mod:`ocp.structure.control_set`).
:func:`judge` sorts the violations into definite ones and ones inside the error
band (:data:`ERROR_MARGIN`), and :func:`verdict_of` turns them into a verdict.

Knows nothing of where the samples come from: a refined solution
(:mod:`ocp.certificate.from_refined`) or a transcription alone
(:mod:`ocp.certificate.from_transcription`).
"""


from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..definition.problem import OptimalControlProblem
from ..structure.arcs import control_bounds_at
from ..structure.constraint_kinds import MIXED, controls_in, coupled_groups, path_kinds
from ..structure.control_set import control_polytope, distance_to_vertices, vertex_scores
from ..transcriptions.solution import along
from .costates import pmp_functions

CERTIFIED = "bang-bang certified"
NOT_BANG_BANG = "not bang-bang"
INCONCLUSIVE = "inconclusive"
CHATTERING = "chattering suspected"
NOT_APPLICABLE = "not applicable: the solve did not converge"
UNVERIFIED = "not applicable: the solution is not verified"
OTHER_CANDIDATE = "not applicable: the refinement is another candidate's"
ERROR_MARGIN = 10.0
"""A violation within this factor of the estimated numerical error is not a refutation."""



@dataclass
class Tolerances:
    """What the checks allow.

    Attributes
    ----------
    H : float
        Allowed ``H_max_abs`` (relative to ``H_scale``).
    sigma : float
        ``|sigma_j| <= sigma * max|sigma_j|`` counts as zero.
    switch : float
        Allowed time between a switch and the sign change of its sigma.
    singular : float
        Shortest run of ``sigma ~ 0`` reported as singular.
    """

    H: float
    sigma: float
    switch: float
    singular: float


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
class Figures:
    """H, sigma and the checks on one set of samples (made by :func:`figures`).

    Attributes
    ----------
    H : ndarray (m,)
        The Hamiltonian at the samples.
    sigma : ndarray (m, nu)
        The switching functions (``dH/du`` when H is not linear in u).
    H_scale : float
        ``max_t sum_i |lambda_i xdot_i|``, the size of the terms that must cancel.
    H_max_abs, H_var : float
        :func:`H_deviation` and ``max H - min H`` over the judged samples, divided by
        ``H_scale``.
    agreement : dict of str to float
        Per control: fraction of the time (where sigma is clearly non-zero) the
        control sits at the bound (or vertex) that minimises H.
    gap : dict of str to float
        Per control: largest time between a switch and a sign change of its sigma.
    singular : list of (float, float)
        Runs where sigma vanishes (singular or interior arcs).
    zeros : dict of str to ndarray
        Per control: the interpolated sign changes of its sigma.
    linear : bool
        H is linear in u (a control-affine problem).
    T_side : int
        T at its upper (+1) or lower (-1) bound, else 0 (the judgement's wording).
    """

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
    T_side: int = 0


def H_deviation(H: np.ndarray, H_exp: float | None, T_side: int = 0) -> float:
    """How far the Hamiltonian's samples are from what the free final time demands.

    ``max |H - H_exp|``; with ``H_exp`` None (T fixed) ``max |H - mean H|``; with T at a
    bound (``T_side`` +1 upper, -1 lower) ``H`` need only be constant and on the allowed
    side of ``H_exp``: the larger of ``max |H - mean H|`` and the mean's excess
    ``max(0, T_side (mean H - H_exp))``.

    Parameters
    ----------
    H : ndarray
        The judged samples (not empty).
    H_exp : float or None
        Free-T transversality's value of H.
    T_side : int
        See :func:`ocp.certificate.costates.final_time_condition`.
    """
    if H_exp is not None and not T_side:
        return float(np.max(np.abs(H - H_exp)))
    mean = float(np.mean(H))
    excess = max(0.0, T_side * (mean - H_exp)) if H_exp is not None else 0.0
    return max(float(np.max(np.abs(H - mean))), excess)


def figures(pr: OptimalControlProblem, params: dict, t: np.ndarray, x: np.ndarray,
            u: np.ndarray, lam: np.ndarray, H_exp: float | None, skip: np.ndarray,
            switches: dict[str, list[float]], tol_sigma: float, sigma_floor: np.ndarray,
            u_tol: float, min_singular: float, interior_check: bool = False,
            bounds: tuple[np.ndarray, np.ndarray] | None = None, T_side: int = 0) -> Figures:
    """Evaluate H and sigma and the sign, switch and singularity checks.

    ``skip`` marks samples not judged (constrained, or unresolved by the grid);
    ``sigma_floor`` (nu,) is the absolute size below which sigma counts as zero
    besides ``tol_sigma`` times its scale (the numerical error band); a control
    within ``u_tol`` of a bound (relative to the range) sits at it;
    ``interior_check`` (a transcription) counts a run of small sigma as
    singular only where the control is inside its bounds; ``bounds`` (lower, upper),
    each (m, nu), are the control bounds at each sample when mixed constraints
    tighten them (see :func:`ocp.certificate.from_refined.effective_bounds`).

    Parameters
    ----------
    pr : OptimalControlProblem
    params : dict
        Parameter values by name.
    t, x, u, lam : ndarray
        Sample times (m,), states (m, nx), controls (m, nu) and costates (m, nx).
    H_exp : float or None
        The value H must equal (None: a constant, compared with its mean).
    skip : ndarray of bool (m,)
        Samples not judged.
    switches : dict of str to list of float
        Switch times per control.
    tol_sigma : float
        Relative size below which sigma counts as zero.
    sigma_floor : ndarray (nu,)
        Absolute size below which sigma counts as zero (the numerical error band).
    u_tol : float
        A control this close to a bound (relative to its range) sits at it.
    min_singular : float
        Shortest run of small sigma reported as singular.
    interior_check : bool
        Count a run as singular only where the control is inside its bounds.
    bounds : (ndarray, ndarray), optional
        Lower and upper control bounds at each sample, each (m, nu).
    T_side : int
        T at its upper (+1) or lower (-1) bound: H need only be constant and on that side
        of ``H_exp`` (:func:`H_deviation`).

    Returns
    -------
    Figures

    Raises
    ------
    ValueError
        When H is not convex in u along the samples.
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
    H_max_abs = H_deviation(H[judged], H_exp, T_side) / H_scale if judged.any() else 0.0
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
    return Figures(H, sigma, H_scale, H_max_abs, H_var, agreement, gap, singular, zeros,
                   fns.linear, T_side)


def _coupled_figures(pr: OptimalControlProblem, pv: np.ndarray, t: np.ndarray, u: np.ndarray,
                    sigma: np.ndarray, terms: np.ndarray, judged: np.ndarray,
                    switches: dict[str, list[float]], tol_sigma: float,
                    sigma_floor: np.ndarray, u_tol: float, min_singular: float,
                    interior_check: bool) -> dict[str, tuple[float, float, np.ndarray,
                                                             list[tuple[float, float]]]]:
    """Sign, switch and singularity checks of controls coupled by control-only constraints.

    For a group of controls whose admissible set is a polytope ``P``
    (:mod:`ocp.structure.control_set`) the minimum principle asks ``u = argmin sigma^T v over
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
        As in :func:`figures`.

    Returns
    -------
    dict
        Per coupled control: ``(agreement, switch gap, vertex-change times, singular runs)``.
        Groups whose polytope cannot be enumerated (unbounded, too large) are left out
        (their controls get the per-control checks), and so is a single control that a
        mixed constraint bounds too. A group of several controls that a mixed
        constraint also bounds is checked on its polytope without that constraint.
    """
    out: dict[str, tuple[float, float, np.ndarray, list[tuple[float, float]]]] = {}
    dt = np.gradient(t) if len(t) > 1 else np.ones(len(t))
    in_mixed = {n for c, k in zip(pr.structure_path, path_kinds(pr), strict=True) if k == MIXED
                for n in controls_in(pr, c)}
    for group in coupled_groups(pr, singletons=True):
        if len(group) == 1 and group[0] in in_mixed:
            # a mixed constraint moves this control's bounds with the state: the
            # per-control check with the effective bounds sees both kinds at once
            continue
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


def judge(fig: Figures, tol: Tolerances, err: dict[str, float],
          expected_H: bool) -> tuple[list[str], list[str]]:
    """Reasons for definite failures and for failures inside the error band.

    Parameters
    ----------
    fig : Figures
    tol : Tolerances
    err : dict of str to float
        The certificate's own numerical error per figure (``H``, ``switch``); a
        violation within :data:`ERROR_MARGIN` times it is uncertain, not definite.
    expected_H : bool
        H is compared with its free-T value (not a constant).

    Returns
    -------
    definite, uncertain : list of str
    """
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
    if expected_H and fig.T_side:
        what = (f"a constant on the side of its free-T value that T at its "
                f"{'upper' if fig.T_side > 0 else 'lower'} bound allows")
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


def verdict_of(definite: list[str], uncertain: list[str], active: list[tuple[float, float]],
               checked_from: float, T: float) -> tuple[str, list[str]]:
    """The verdict of the judged reasons, and the reasons to report.

    A definite failure refutes; an uncertain one, or an active state constraint
    (whose span the checks leave out), gives "inconclusive"; else "bang-bang certified".

    Parameters
    ----------
    definite, uncertain : list of str
        From :func:`judge`.
    active : list of (float, float)
        State-constrained intervals.
    checked_from : float
        Start of the checked part of the horizon.
    T : float
        Final time.

    Returns
    -------
    verdict : str
    reasons : list of str
    """
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
