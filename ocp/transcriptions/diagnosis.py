"""What is wrong when Ipopt fails: an analysis of the last iterate, in one line.

:func:`diagnose` looks, in order, for

* **dependent end conditions**: equality rows of the boundary (initial, terminal,
  link, ...) whose gradients, once the dynamics' defects (and the other equality rows
  along the path) are projected out, are linearly dependent at the iterate: the
  smallest singular values of that projection (:func:`dependent_ends`) relative to the
  largest, the rank, and the rows of the null combination. Where the combination
  is the gradient of a quantity the dynamics conserve -- a linear one (its gradient the
  same at both ends) or a norm of some states (its gradient proportional to them) --
  the quantity is named and checked: its time derivative ``grad C . f(x, u)`` vanishes
  at random states and controls. The end conditions then fix the conserved quantity
  twice, and the discretisation, which conserves it only approximately, makes them
  inconsistent: drop one (``solve(drop_dependent=True)`` does it and says which);
* **conditions that cannot be met together**: the rows the iterate violates most
  (Ipopt's restoration phase ends at a local minimum of the violation), with the state
  bounds active beside them;
* **badly scaled variables**: states, controls, variables or times whose scaled
  values (what Ipopt sees) at the iterate lie more than :data:`SPREAD` apart;
* **periodic unbounded states** (:func:`periodic_states`): a state with no bound that
  enters the dynamics, running cost and path constraints only through functions of
  period ``2 pi`` (``cos``, ``sin``): its branches are equivalent, so a solver may wind
  it around and mesh refinement chase the windings; bound it or wrap it.

The one line goes into the :class:`~ocp.SolveError` message, the details onto
``error.diagnosis`` (a :class:`Diagnosis`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .labels import row_labels

DEPENDENT_RTOL = 1e-5
"""A singular value of the projected end-row Jacobian below this fraction of the largest
marks a dependence (a discretisation drifts a conserved quantity by far less)."""
SPREAD = 1e4
"""Scaled variable magnitudes further apart than this are reported."""
VIOLATION_TOL = 1e-6
"""Rows violated by more than this (relative to ``max(1, |bound|)``) are reported."""
TWO_PI = 2.0 * math.pi


@dataclass
class Diagnosis:
    """What the analysis of a failed solve's last iterate found.

    Attributes
    ----------
    summary : str
        One line: the most likely cause, or that none was found.
    dependent : list of str
        The dependent equality rows (labels), empty if none.
    rank, n_equalities : int
        Rank of the end rows' Jacobian after projecting out the dynamics, and the
        number of end rows.
    dependent_rows : list of int
        Their indices in ``g``.
    conserved : str or None
        The quantity the dynamics conserve whose gradient the dependence is, if found.
    violated : list of tuple
        ``(label, violation)`` of the rows violated most at the iterate.
    badly_scaled : list of tuple
        ``(quantity, largest scaled magnitude)`` outside ``[1/SPREAD, SPREAD]`` of the
        others.
    periodic : list of str
        Unbounded states entering only through ``2 pi``-periodic functions.
    weights : dict
        The null combination of the end rows: row of ``g`` -> weight.
    unreachable : list of str
        End conditions on one variable that its bounds cannot meet.
    degenerate : bool
        The dependent rows' gradients vanish at the iterate by themselves (an expression
        at its extremum, ``cos(psi) = -1``).
    """

    summary: str = "no cause found in the last iterate"
    dependent: list[str] = field(default_factory=list)
    rank: int = 0
    n_equalities: int = 0
    dependent_rows: list[int] = field(default_factory=list)
    conserved: str | None = None
    violated: list[tuple[str, float]] = field(default_factory=list)
    badly_scaled: list[tuple[str, float]] = field(default_factory=list)
    periodic: list[str] = field(default_factory=list)
    weights: dict[int, float] = field(default_factory=dict)
    degenerate: bool = False
    unreachable: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        return self.summary


def diagnose(tr: Any, w: np.ndarray, pv: np.ndarray, scaling: Any) -> Diagnosis:
    """Analyse a transcription's iterate ``w`` (see the module).

    Parameters
    ----------
    tr : Transcription
        The transcription that failed.
    w : ndarray
        The last iterate, in the user's units.
    pv : ndarray
        The parameter values.
    scaling : Scaling
        The scaling the solve used (what Ipopt saw).
    """
    d = Diagnosis()
    labels = row_labels(tr)
    bounds = tr.bounds_at(pv)
    with np.errstate(all="ignore"):
        dep = dependent_ends(tr, w, pv, bounds, scaling)
    if dep is not None:
        d.rank, d.n_equalities, d.dependent_rows, d.weights = dep
        d.dependent = [labels[k] for k in d.dependent_rows]
        d.degenerate = bool(d.rank + len(d.dependent_rows) == d.n_equalities and
                            all(w_ == 1.0 for w_ in d.weights.values()))
        with np.errstate(all="ignore"):
            d.conserved = None if d.degenerate else conserved_quantity(tr, w, pv, d.weights)
    d.unreachable = unreachable_rows(tr, w, pv, bounds, labels)
    d.violated = violated_rows(tr, w, pv, bounds, labels)
    d.badly_scaled = badly_scaled(tr, w, scaling)
    d.periodic = [f"{ph.name}: {n}" if len(tr.multiphase.phases) > 1 else n
                  for ph in tr.multiphase.phases for n in periodic_states(ph)]
    d.summary = _summary(d)
    return d


def _summary(d: Diagnosis) -> str:
    """The one line of a diagnosis: the first cause found."""
    if d.dependent and d.degenerate:
        return (f"the gradient of {', '.join(d.dependent)} vanishes at the last iterate (an "
                "expression at its extremum): pose the condition on the variable itself")
    if d.dependent:
        why = f" ({d.conserved} is conserved by the dynamics and fixed at both ends)" \
            if d.conserved else ""
        advice = "drop one (solve(drop_dependent=True))" if d.conserved else (
            "they fix one quantity twice: drop one if their values agree "
            "(solve(drop_dependent=True)), else they contradict")
        return (f"end conditions {', '.join(d.dependent)} are dependent (rank "
                f"{d.rank} of {d.n_equalities} after the dynamics){why}; {advice}")
    if d.unreachable:
        return f"cannot be met together: {'; '.join(d.unreachable)}"
    if d.periodic:
        return (f"state {', '.join(repr(p) for p in d.periodic)} enters only through "
                "2*pi-periodic functions and is unbounded: bound it (e.g. within "
                "[-2*pi, 2*pi]) or wrap it")
    if d.violated:
        rows = ", ".join(f"{k} (by {v:.2g})" for k, v in d.violated[:3])
        return f"the last iterate violates most: {rows}"
    if d.badly_scaled:
        q = ", ".join(f"{k} ({v:.1e})" for k, v in d.badly_scaled[:3])
        return f"badly scaled: {q} in scaled units; give ref= to these quantities"
    return "no cause found in the last iterate"


# ------------------------------------------------------------------ dependence
def _jacobian(tr: Any, w: np.ndarray, pv: np.ndarray) -> Any:
    """``dg/dw`` at ``w`` in the user's units, sparse (its function built once)."""
    fn = getattr(tr, "jacobian_function", None)
    if fn is None:
        nlp = tr.nlp
        fn = ca.Function("jac_g", [nlp["x"], nlp["p"]], [ca.jacobian(nlp["g"], nlp["x"])])
        tr.jacobian_function = fn
    import scipy.sparse as sp  # here: scipy.sparse costs 0.2 s of every solving process

    J = fn(w, pv)
    rows, cols = J.sparsity().get_triplet()
    return sp.csr_matrix((np.array(J.nonzeros(), dtype=float), (rows, cols)), shape=J.shape)


def dependent_ends(tr: Any, w: np.ndarray, pv: np.ndarray, bounds: tuple,
                   scaling: Any) -> tuple[int, int, list[int], dict[int, float]] | None:
    """Dependent equality end rows at ``w``, or None.

    The Jacobian is taken in the scaled variables (``dg/dw * D``), each row of unit
    norm; the equality rows of the defects and path are the base ``A``, the other
    equality rows ``B``; ``R = (I - A^T (A A^T)^-1 A) B^T`` is what of the end rows is
    not already in the dynamics' span, and its small singular values are dependences.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    w : ndarray
        The iterate, in the user's units.
    pv : ndarray
        The parameter values.
    bounds : tuple
        ``(lbw, ubw, lbg, ubg)`` at ``pv``.
    scaling : Scaling
        The solve's scaling (the Jacobian is taken in its variables).

    Returns
    -------
    tuple or None
        ``(rank, number of end rows, dependent rows of g, null combination)``.
    """
    import scipy.sparse as sp  # only a failed solve's diagnosis needs it (see _jacobian)
    from scipy.sparse.linalg import splu

    lbw, ubw, lbg, ubg = bounds
    eq = np.flatnonzero((lbg == ubg) & np.isfinite(lbg))
    base_rows = _base_rows(tr)
    B = np.setdiff1d(eq, base_rows)
    A = np.intersect1d(eq, base_rows)
    if B.size < 2:
        return None
    free = np.flatnonzero(lbw < ubw)
    J = (_jacobian(tr, w, pv) @ sp.diags(scaling.D)).tocsc()[:, free].tocsr()
    norms = np.sqrt(np.asarray(J.multiply(J).sum(axis=1)).ravel())
    flat = [int(k) for k in B if norms[k] <= 1e-10 * max(1.0, float(norms.max()))]
    if flat:  # a row whose gradient vanishes: degenerate by itself (cos(psi) = -1)
        return len(B) - len(flat), int(B.size), flat, dict.fromkeys(flat, 1.0)
    norms[norms == 0] = 1.0
    J = sp.diags(1.0 / norms) @ J
    JA, JB = J[A], J[B].toarray()
    R = JB.T.copy()
    if A.size:
        M = (JA @ JA.T).tocsc() + 1e-14 * sp.identity(A.size, format="csc")
        X = splu(M).solve(np.asarray(JA @ JB.T))
        R -= JA.T @ X
    _, s, vt = np.linalg.svd(R, full_matrices=False)
    if not s.size or not np.isfinite(s).all() or s[0] == 0:
        return None
    small = s < DEPENDENT_RTOL * s[0]
    if not small.any():
        return None
    beta = vt[-1]
    involved = np.abs(beta) > 0.05 * np.abs(beta).max()
    return int(np.sum(~small)), int(B.size), [int(k) for k in B[involved]], \
        dict(zip(B.tolist(), beta.tolist(), strict=True))


def _base_rows(tr: Any) -> np.ndarray:
    """Rows of the defects and path constraints (the dynamics' own rows)."""
    rows = []
    for lay in tr.layouts:
        for kind, sl in lay.blocks.items():
            if kind in ("continuity", "collocation", "path", "path_inner"):
                rows.append(np.arange(sl.start, sl.stop))
    return np.concatenate(rows) if rows else np.zeros(0, dtype=int)


def conserved_quantity(tr: Any, w: np.ndarray, pv: np.ndarray,
                       weights: dict[int, float]) -> str | None:
    """The quantity conserved by a phase's dynamics whose gradient at the phase's end is
    the dependence's (the end rows' gradients weighted by it): a norm of two or three
    states (gradient proportional to them) or a linear combination (gradient constant),
    checked on the dynamics; None where neither fits.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    w : ndarray
        The iterate.
    pv : ndarray
        The parameter values.
    weights : dict
        The null combination: row of ``g`` -> weight.
    """
    rows = np.array(list(weights), dtype=int)
    beta = np.array(list(weights.values()))
    J = _jacobian(tr, w, pv)[rows]
    combined = np.asarray(J.T @ beta).ravel()
    for i, (ph, lay) in enumerate(zip(tr.multiphase.phases, tr.layouts, strict=True)):
        ends = np.arange(lay.iX.start, lay.iX.stop).reshape(-1, ph.nx)[-1]
        gT = combined[ends]
        if not np.any(np.abs(gT) > 1e-8 * max(1.0, np.abs(combined).max())):
            continue
        xT = w[ends]
        for name, grad in _candidates(ph, gT):
            fn = ca.Function("grad", [ph.x], [grad])
            at = np.array(fn(xT), dtype=float).ravel()
            cos = abs(at @ gT) / max(np.linalg.norm(at) * np.linalg.norm(gT), 1e-300)
            if cos > 0.999 and _conserved(tr, i, grad):
                return name
    return None


def _candidates(ph: Any, gT: np.ndarray) -> list[tuple[str, ca.SX]]:
    """Quantities whose gradient may be ``gT``: the sum of squares of the states it
    involves (a norm), and the linear combination ``gT . x``."""
    names = ph.state_names
    involved = [k for k in range(ph.nx) if abs(gT[k]) > 1e-6 * np.abs(gT).max()]
    out = []
    if 2 <= len(involved) <= 6:
        label = " + ".join(f"{names[k]}^2" for k in involved)
        out.append((label, ca.gradient(sum(ph.x[k] ** 2 for k in involved), ph.x)))
    a = gT / np.abs(gT).max()
    lin = " + ".join(f"{a[k]:.3g} {names[k]}" for k in involved)
    out.append((lin, ca.DM(a) + 0 * ph.x))
    return out


def _conserved(tr: Any, i: int, grad: ca.SX) -> bool:
    """``grad . f`` vanishes at random states and controls (within bounds, clipped)."""
    ph, cp = tr.multiphase.phases[i], tr.compiled[i]
    rate = ca.Function("dC", [ph.t, ph.x, ph.u, cp.s],
                       [ca.dot(grad, cp.ode(ph.t, ph.x, ph.u, cp.s)[0])])
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = rng.normal(size=ph.nx)
        u = rng.uniform(-1.0, 1.0, size=ph.nu)
        s = rng.uniform(0.5, 1.5, size=cp.ns)
        scale = float(np.linalg.norm(np.array(ca.Function("g", [ph.x], [grad])(x), dtype=float)))
        with np.errstate(all="ignore"):
            v = float(rate(0.3, x, u, s))
        if not math.isfinite(v) or abs(v) > 1e-10 * max(1.0, scale):
            return False
    return True


# ------------------------------------------------------------------ other causes
def unreachable_rows(tr: Any, w: np.ndarray, pv: np.ndarray, bounds: tuple,
                     labels: list[str]) -> list[str]:
    """End conditions on a single entry of ``w`` (a state at an end, a time, a variable)
    that no value within that entry's bounds meets (sampled on 65 points of a finite
    box), with the bounds that exclude them.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    w : ndarray
        The iterate, in the user's units.
    pv : ndarray
        The parameter values.
    bounds : tuple
        ``(lbw, ubw, lbg, ubg)`` at ``pv``.
    labels : list of str
        The rows' labels.
    """
    lbw, ubw, lbg, ubg = bounds
    eq_rows = np.setdiff1d(np.flatnonzero(np.isfinite(lbg) | np.isfinite(ubg)), _base_rows(tr))
    J = _jacobian(tr, w, pv)[eq_rows].tocsr()
    fmap, out = tr.nlp_function().map(65), []  # (built once: one evaluation per row)
    for j, k in enumerate(eq_rows):
        cols = J[j].indices
        if cols.size != 1 or not (np.isfinite(lbw[cols[0]]) and np.isfinite(ubw[cols[0]])):
            continue
        c = int(cols[0])
        pts = np.linspace(lbw[c], ubw[c], 65)
        W = np.repeat(w[:, None], pts.size, axis=1)
        W[c] = pts
        with np.errstate(all="ignore"):
            g = np.array(fmap(W, pv)[1], dtype=float)[k]
        if np.all((g < lbg[k] - 1e-9 * max(1.0, abs(lbg[k]))) |
                  (g > ubg[k] + 1e-9 * max(1.0, abs(ubg[k])))):
            out.append(f"{labels[k]} with its variable within [{lbw[c]:g}, {ubw[c]:g}]")
    return out


def violated_rows(tr: Any, w: np.ndarray, pv: np.ndarray, bounds: tuple,
                  labels: list[str]) -> list[tuple[str, float]]:
    """The rows violated most at ``w`` (relative to ``max(1, |bound|)``), largest first,
    one per label.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    w : ndarray
        The iterate, in the user's units.
    pv : ndarray
        The parameter values.
    bounds : tuple
        ``(lbw, ubw, lbg, ubg)`` at ``pv``.
    labels : list of str
        The rows' labels.
    """
    _, _, lbg, ubg = bounds
    with np.errstate(all="ignore"):
        g = np.array(tr.nlp_function()(w, pv)[1], dtype=float).ravel()
        v = np.maximum(lbg - g, g - ubg)
        v = np.where(np.isfinite(v), v, 0.0) / np.maximum(
            1.0, np.minimum(np.abs(np.where(np.isfinite(lbg), lbg, 0.0)) +
                            np.abs(np.where(np.isfinite(ubg), ubg, 0.0)), 1e300))
    out: dict[str, float] = {}
    for k in np.argsort(-v):
        if v[k] <= VIOLATION_TOL or len(out) >= 5:
            break
        out.setdefault(labels[k].split(" at ")[0], float(v[k]))
    return list(out.items())


def badly_scaled(tr: Any, w: np.ndarray, scaling: Any) -> list[tuple[str, float]]:
    """Quantities whose largest scaled magnitude lies more than :data:`SPREAD` from the
    median of the others'.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    w : ndarray
        The iterate, in the user's units.
    scaling : Scaling
        The solve's scaling (what Ipopt saw).
    """
    ws = np.abs(scaling.x_to_scaled(w))
    mags: dict[str, float] = {}
    multi = len(tr.layouts) > 1
    for ph, lay in zip(tr.multiphase.phases, tr.layouts, strict=True):
        pre = f"{ph.name}: " if multi else ""
        for sl, names in ((lay.iX, ph.state_names), (lay.iU, ph.control_names)):
            block = ws[sl].reshape(-1, max(len(names), 1))
            for k, n in enumerate(names):
                mags[pre + n] = float(np.max(block[:, k])) if block.size else 0.0
    for k, n in enumerate(tr.multiphase.var_names):
        mags[n] = float(ws[tr.iV.start + k])
    vals = np.array([v for v in mags.values() if v > 0])
    if vals.size < 2:
        return []
    mid = float(np.median(vals))
    out = [(n, v) for n, v in mags.items() if v > 0 and (v > SPREAD * mid or v < mid / SPREAD)]
    return sorted(out, key=lambda nv: -abs(math.log10(nv[1] / mid)))


def periodic_states(ph: Any) -> list[str]:
    """Unbounded states entering the running expressions (dynamics, running cost, path
    constraints) only through functions of period ``2 pi``, and entering them at all.

    Parameters
    ----------
    ph : OptimalControlProblem
        The phase.
    """
    from ..definition.problem import bound_value

    exprs = ca.vertcat(ph.rhs, ph.lagrange, ph.path_stack()[0])
    fn = ca.Function("run", [ph.t, ph.x, ph.u, ph.p, ph.v], [exprs])
    rng = np.random.default_rng(1)
    out = []
    for k, n in enumerate(ph.state_names):
        lo, hi = (bound_value(b) for b in ph.state_bounds[n])
        if (lo is not None and math.isfinite(lo)) or (hi is not None and math.isfinite(hi)):
            continue
        if not ca.depends_on(exprs, ph.x[k]):
            continue
        if all(_shift_invariant(fn, ph, k, rng) for _ in range(4)):
            out.append(n)
    return out


def _shift_invariant(fn: ca.Function, ph: Any, k: int, rng: np.random.Generator) -> bool:
    """The running expressions unchanged when state ``k`` moves by ``2 pi``, at a random
    point."""
    x = rng.uniform(-3.0, 3.0, size=ph.nx)
    args = [rng.uniform(0.1, 2.0), x, rng.uniform(-1.0, 1.0, size=ph.nu),
            rng.uniform(0.5, 1.5, size=ph.np), rng.uniform(0.5, 1.5, size=ph.nv)]
    with np.errstate(all="ignore"):
        a = np.array(fn(*args), dtype=float).ravel()
        x2 = x.copy()
        x2[k] += TWO_PI
        b = np.array(fn(args[0], x2, *args[2:]), dtype=float).ravel()
        changed = np.abs(a - b) > 1e-9 * np.maximum(1.0, np.abs(a))
    return bool(np.all(np.isfinite(a) == np.isfinite(b)) and not changed.any())
