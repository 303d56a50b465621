"""The scaled NLP that Ipopt solves, and its scaling at each solve's start.

:mod:`ocp.definition.scaling` says where the numbers come from; this module places them
in a transcription's decision vector and constraint rows. The constants are NLP
parameters (after the problem's: the objective factor ``kf = 1 / f_ref``, then ``D``,
``c`` and ``r``), so every solve can take its own scaling without a rebuild:

* at build, the references from bounds, default guesses and the problem's sizes
  (:attr:`Transcription.scaling <ocp.transcriptions.nlp.Transcription>`);
* at each cold solve, the states whose reference is automatic and whose bounds say
  nothing of a magnitude (``h >= 0``, or none) are sized again from the start actually
  given (:func:`start_scaling`): the largest of their magnitude over the start, their
  size from the problem (:mod:`ocp.definition.sizes`), their linked phase's size, and
  the change the dynamics make over the phase's duration at the start's points
  (``duration * (|f| + sum_j |df/dx_j| s_j + sum_k |df/du_k| s_k)``, other states
  ``j`` only, twice, so a position at rest gets its size from its velocity's); a
  magnitude or rate at most :data:`NOISE` of the phase's largest is roundoff, not a size
  (:func:`denoised`). A guess passed later to ``solve``/``refine`` thus informs the
  scaling, and a start at rest (velocities 0) still gets the velocities' sizes from the
  thrust that moves them. A refinement round, and a solve warm-started from a solution of
  the same problem on another grid at the same parameters, keep that solution's scaling
  (:func:`carried_scaling`);
* ``scaling="none"`` (and the fallback, :mod:`ocp.transcriptions.failure`) solves with
  ``D = 1``, ``c = 0``, ``r = 1``, ``kf = 1``: the NLP as posed, exactly.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..definition.errors import ProblemDefinitionError
from ..definition.scaling import (
    AUTO_RANGE,
    Scaling,
    ScalingBuilder,
    informative_bounds,
    loose_bounds,
    phase_quantities,
)
from ..definition.sizes import phase_state_sizes

PASSES = 2  # rounds of the dynamics rule: a velocity's size, then its position's
NOISE = math.sqrt(np.finfo(float).eps)
"""A start's magnitude or rate at most this fraction of the phase's largest is roundoff
(:func:`denoised`)."""


def build_scaling(tr: Any, ends: list[tuple[ca.SX, ca.SX]]) -> Scaling:
    """The build-time constants of a transcription (see :mod:`ocp.definition.scaling`).

    Parameters
    ----------
    tr : Transcription
        The transcription (its layouts, times and options).
    ends : list of tuple of SX
        Each phase's states' default start and end guesses.
    """
    mp, opts = tr.multiphase, tr.scaling_options
    known = {"objective", "time", *mp.var_names}
    for ph in mp.phases:
        known |= {*ph.state_names, *ph.control_names}
    unknown = sorted(set(opts["refs"]) - known)
    if unknown:
        raise ProblemDefinitionError(f"scaling: {unknown} are not states, controls or "
                                     "variables of the problem (nor 'objective', 'time')")
    sb = ScalingBuilder(opts, tr.n_w, tr.n_g)
    if tr.grid_free.sizes is None or not opts["auto"]:
        sizes = state_sizes(tr, ends)
        if opts["auto"]:
            tr.grid_free.sizes = sizes
    else:
        sizes = tr.grid_free.sizes
    state_refs = []
    for ph, lay, tm, (a, b), sz in zip(mp.phases, tr.layouts, tr.times, ends, sizes,
                                       strict=True):
        states, controls = phase_quantities(ph, a, b)
        refs = [sb.ref(name, user, lo, hi, guess, sz[k])
                for k, (name, user, lo, hi, guess) in enumerate(states)]
        state_refs.append(refs)
        set_state_refs(sb, lay, ph.nx, refs)
        for k, (name, user, lo, hi, guess) in enumerate(controls):
            sb.set_entries(np.arange(lay.iU.start, lay.iU.stop)[k::ph.nu],
                           sb.ref(name, user, lo, hi, guess))
        if lay.iT is not None:
            (lo, hi), guess = tm.T_bounds, tm.T_guess
            sb.set_entries(lay.iT, sb.ref("time", None, lo, hi, guess))
        if lay.it0 is not None:
            (lo, hi), guess = tm.t0_bounds, tm.t0_guess
            sb.set_entries(lay.it0, sb.ref("time", None, lo, hi, guess))
        if "path" in lay.blocks:
            rs = [sb.row_scale(c, j) for c in ph.path for j in range(c.expr.numel())]
            sl = lay.blocks["path"]
            sb.r[sl] = np.tile(rs, (sl.stop - sl.start) // max(len(rs), 1))
    sh = mp.shared
    for k, name in enumerate(sh.var_names):
        sb.set_entries(tr.iV.start + k, sb.ref(name, sh.var_ref.get(name),
                                               sh.var_bounds[name][0], sh.var_bounds[name][1],
                                               sh.var_guess.get(name)))
    for i, kind, cs in tr.groups:
        sl = (tr.link_blocks if i == -1 else tr.layouts[i].blocks)[kind]
        sb.r[sl] = [sb.row_scale(c, j) for c in cs for j in range(c.expr.numel())]
    if "objective" not in opts["refs"] and sh.objective_ref is not None:
        opts["refs"]["objective"] = (0.0, sh.objective_ref)
    sc = sb.build()
    sc.state_refs = state_refs
    return sc


def set_state_refs(sb: Any, lay: Any, nx: int, refs: list[tuple[float, float]]) -> None:
    """Entries and defect rows of a phase's states get their ``(ref0, ref)``.

    Parameters
    ----------
    sb : ScalingBuilder or Scaling
        Anything with ``D``, ``c`` and ``r`` arrays.
    lay : PhaseLayout
        Where the phase lives.
    nx : int
        Its number of states.
    refs : list of tuple
        One ``(ref0, ref)`` per state.
    """
    for k, (ref0, ref) in enumerate(refs):
        for sl in (lay.iX, lay.iZ):
            if sl is not None:
                idx = np.arange(sl.start, sl.stop)[k::nx]
                sb.c[idx], sb.D[idx] = ref0, ref
        for kind in ("continuity", "collocation"):  # defects: state fastest
            if kind in lay.blocks:
                rows = np.arange(lay.blocks[kind].start, lay.blocks[kind].stop)
                sb.r[rows[k::nx]] = 1.0 / ref


def state_sizes(tr: Any, ends: list[tuple[ca.SX, ca.SX]]) -> list[list[float | None]]:
    """Sizes of the states that bounds and guess leave unknown (:mod:`ocp.definition.sizes`).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    ends : list of tuple of SX
        Each phase's states' default start and end guesses.
    """
    from ..definition.guess import variable_guess

    mp = tr.multiphase
    if not tr.scaling_options["auto"]:
        return [[None] * ph.nx for ph in mp.phases]
    vg = variable_guess(mp.shared)
    out: list[list[float | None]] = []
    for i, (ph, tm, (a, b)) in enumerate(zip(mp.phases, tr.times, ends, strict=True)):
        prev = next((j for j, k in mp.time_links if k == i and j < i), None)
        linked = None
        if prev is not None:
            pp = mp.phases[prev]
            linked = {n: s for n, s in zip(pp.state_names, out[prev], strict=True)
                      if s is not None}
        out.append(phase_state_sizes(ph, a, b, (tm.t0_guess, tm.T_guess), vg, linked,
                                     loose_bounds))
    return out


MODES = ("posed", "build", "start")


def scaled_nlp(nlp: dict[str, Any], n_w: int, n_g: int, mode: str = "start",
               sc: Scaling | None = None) -> dict[str, ca.MX]:
    """The NLP Ipopt solves: ``w = D w_s + c``, rows times ``r``, objective times ``kf``
    (an NLP parameter after the problem's).

    Parameters
    ----------
    nlp : dict
        The NLP in the user's units (``x``, ``p``, ``f``, ``g``).
    n_w, n_g : int
        Its sizes.
    mode : {"posed", "build", "start"}
        ``"posed"``: the graph of the NLP as posed (an identity scaling); ``"build"``:
        ``D``, ``c``, ``r`` of ``sc`` folded in as constants (the transcription's build
        scaling: the graph of the versions before parametric scaling, so a solve whose
        scaling is the build's takes exactly their iterations); ``"start"``: ``D``,
        ``c`` and ``r`` NLP parameters too, for a scaling derived at a solve's start.
    sc : Scaling, optional
        The build scaling (``mode="build"``).
    """
    kf = ca.MX.sym("kf")
    if mode == "posed":
        return {"x": nlp["x"], "p": ca.vertcat(nlp["p"], kf), "f": kf * nlp["f"],
                "g": nlp["g"]}
    ws = ca.MX.sym("ws", n_w)
    if mode == "build":
        assert sc is not None
        D, c, r, P = ca.DM(sc.D), ca.DM(sc.c), ca.DM(sc.r), ca.vertcat(nlp["p"], kf)
    else:
        syms = (ca.MX.sym(n, k) for n, k in (("D", n_w), ("c", n_w), ("r", n_g)))
        D, c, r = syms  # type: ignore[assignment]  # (symbols of the DMs' shapes)
        P = ca.vertcat(nlp["p"], kf, D, c, r)
    f, g = ca.substitute([nlp["f"], nlp["g"]], [nlp["x"]], [D * ws + c])
    return {"x": ws, "p": P, "f": kf * f, "g": r * g}


def graph_of(sc: Scaling, build: Scaling) -> str:
    """Which graph (:func:`scaled_nlp`) solves with ``sc``: ``"posed"`` for an identity,
    ``"build"`` for the build scaling's numbers, else ``"start"``.

    Parameters
    ----------
    sc : Scaling
        The solve's scaling.
    build : Scaling
        The transcription's build scaling.
    """
    if sc.is_identity():
        return "posed"
    if sc is build or (np.array_equal(sc.D, build.D) and np.array_equal(sc.c, build.c)
                       and np.array_equal(sc.r, build.r)):
        return "build"
    return "start"


def identity(n_w: int, n_g: int) -> Scaling:
    """The scaling that leaves the NLP as posed.

    Parameters
    ----------
    n_w, n_g : int
        The NLP's sizes.
    """
    return Scaling(np.ones(n_w), np.zeros(n_w), np.ones(n_g), None, False)


def scale_args(sc: Scaling, args: dict[str, Any], fref: float,
               mode: str = "start") -> dict[str, Any]:
    """Ipopt's arguments for the scaled NLP, from ``args`` in the user's units.

    Parameters
    ----------
    sc : Scaling
        The solve's scaling.
    args : dict
        ``p``, ``x0``, bounds and optional multipliers in the user's units.
    fref : float
        The objective scale.
    mode : str
        The graph (:func:`scaled_nlp`): only ``"start"`` takes the scaling as parameters.
    """
    out = dict(args)
    tail = [sc.D, sc.c, sc.r] if mode == "start" else []
    out["p"] = np.concatenate([args["p"], [1.0 / fref], *tail])
    for k in ("x0", "lbx", "ubx"):
        out[k] = sc.x_to_scaled(args[k])
    out["lbg"], out["ubg"] = sc.r * args["lbg"], sc.r * args["ubg"]
    if "lam_g0" in args:
        out["lam_g0"], out["lam_x0"] = sc.multipliers_to_scaled(args["lam_g0"],
                                                                args["lam_x0"], fref)
    return out


def unscale(sc: Scaling, res: dict[str, Any], fref: float) -> dict[str, Any]:
    """Ipopt's result mapped back to the user's units.

    Parameters
    ----------
    sc : Scaling
        The solve's scaling.
    res : dict
        Ipopt's result.
    fref : float
        The objective scale.
    """
    lam_g, lam_x = sc.multipliers_from_scaled(res["lam_g"], res["lam_x"], fref)
    return {"x": sc.x_from_scaled(res["x"]), "f": float(res["f"][0]) * fref,
            "lam_g": lam_g, "lam_x": lam_x, "g": res["g"] / sc.r}


def with_state_refs(tr: Any, refs: list[list[tuple[float, float]]]) -> Scaling:
    """The build scaling of ``tr`` with these per-state references (a scaling carried
    from a solve on another mesh of the same problem).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    refs : list of list of tuple
        Per phase, one ``(ref0, ref)`` per state.
    """
    base = tr.scaling
    sc = Scaling(base.D.copy(), base.c.copy(), base.r.copy(), base.objective_ref,
                 base.enabled)
    for lay, ph, rs in zip(tr.layouts, tr.multiphase.phases, refs, strict=True):
        set_state_refs(sc, lay, ph.nx, rs)
    sc.state_refs = [list(r) for r in refs]
    return sc


def start_scaling(tr: Any, x0: np.ndarray, pv: np.ndarray) -> Scaling:
    """The scaling of a solve from ``x0``: the build's, with the open states sized again
    from this start (see the module).

    Parameters
    ----------
    tr : Transcription
        The transcription.
    x0 : ndarray
        The start, in the user's units.
    pv : ndarray
        The parameter values.
    """
    base, opts = tr.scaling, tr.scaling_options
    if not (opts["enabled"] and opts["auto"]) or base.state_refs is None:
        return base
    vv = x0[tr.iV]
    refs: list[list[tuple[float, float]]] = []
    sizes_by_phase: list[dict[str, float]] = []
    mp = tr.multiphase
    for i, disc in enumerate(tr.phases):
        data = disc.unpack(x0[tr.offsets[i]:tr.offsets[i] + disc.size()], pv, vv)
        prev = next((j for j, k in mp.time_links if k == i and j < i), None)
        linked = sizes_by_phase[prev] if prev is not None else {}
        rs, sizes = _phase_refs(tr, i, data, pv, linked)
        refs.append(rs)
        sizes_by_phase.append(sizes)
    if refs == base.state_refs:
        return base
    return with_state_refs(tr, refs)


def _phase_refs(tr: Any, i: int, data: Any, pv: np.ndarray, linked: dict[str, float],
                ) -> tuple[list[tuple[float, float]], dict[str, float]]:
    """One phase's state references from a start's arrays, and the sizes found."""
    ph, cp = tr.multiphase.phases[i], tr.compiled[i]
    opts, base = tr.scaling_options, tr.scaling.state_refs[i]
    bounds = [np.array(b, dtype=float).ravel() for b in cp.bounds(pv)]
    xlo, xhi, ulo, uhi = bounds[2], bounds[3], bounds[4], bounds[5]
    X, U = np.asarray(data.x, dtype=float), np.asarray(data.u_points, dtype=float)
    mags = np.max(np.abs(X), axis=0) if X.size else np.zeros(ph.nx)
    mags = denoised(mags, float(np.max(mags, initial=0.0)))
    given = [opts["refs"].get(n, ph.state_ref.get(n)) for n in ph.state_names]
    open_ = np.array([g is None and informative_bounds(xlo[k], xhi[k], mags[k]) is None
                      for k, g in enumerate(given)], dtype=bool)
    sizes: dict[str, float] = {}
    if not open_.any():
        return list(base), sizes
    build = (tr.grid_free.sizes or [[None] * ph.nx] * (i + 1))[i]
    s = np.array([base[k][1] for k in range(ph.nx)], dtype=float)
    su = np.array([_control_size(ulo[k], uhi[k], U[:, k]) for k in range(ph.nu)])
    rates = _rates(tr, i, data)
    duration = float(data.T - data.t0)
    if rates is None or not (math.isfinite(duration) and duration > 0):
        rates = None
    f_change = np.zeros(ph.nx)
    if rates is not None:  # a rate at the roundoff of the phase's others is none
        scale = max(float(np.max(rates[0], initial=0.0)),
                    float(np.max(_coupled(rates, s, su), initial=0.0)))
        f_change = duration * denoised(rates[0], scale)
    # a state the start says nothing of (0, not moving there) is sized by the others
    silent = open_ & (mags == 0.0) & (f_change == 0.0)
    for k in np.flatnonzero(open_):
        cands = [mags[k], f_change[k], build[k] or 0.0, linked.get(ph.state_names[k], 0.0)]
        s[k] = max(c for c in cands if math.isfinite(c)) or 1.0
    s[silent] = 1.0
    if rates is not None and silent.any():
        for _ in range(PASSES):
            change = duration * _coupled(rates, s, su)
            grow = silent & np.isfinite(change) & (change > s)
            s[grow] = change[grow]
    for k in np.flatnonzero(silent):  # a boundary row's or linked phase's size may be larger
        s[k] = max(s[k], build[k] or 0.0, linked.get(ph.state_names[k], 0.0))
    refs = list(base)
    for k in np.flatnonzero(open_):
        sizes[ph.state_names[k]] = float(s[k])
        ref = 10.0 ** math.ceil(math.log10(s[k]) - 1e-9)  # a power of ten above the size
        refs[k] = (0.0, ref) if not AUTO_RANGE[0] <= ref <= AUTO_RANGE[1] else (0.0, 1.0)
    return refs, sizes


def denoised(values: np.ndarray, reference: float) -> np.ndarray:
    """``values`` with those at or below :data:`NOISE` times ``reference`` set to 0.

    A start's magnitude or rate that small beside the phase's largest is the roundoff of a
    cancellation, not a size: a foot held at rest by the support force that cancels the
    others has the rate ``-1 + (1 + r_m) (1/(1 + r_m) + u - u)``, 2e-16, and a solution's
    resting foot speeds of 1e-13; sized by them, its defect rows were multiplied by 1e14,
    which amplified the integrator's roundoff beyond Ipopt's tolerance (a hop's push-off:
    ``Maximum_Iterations_Exceeded`` after 1500 iterations, 58 as posed). Left at 0, the
    state is sized as one the start says nothing of. A size that small beside the others
    is also beyond what the NLP resolves in double precision, so treating it as none
    costs at most the scaling of ``scaling="none"`` for that state.

    Parameters
    ----------
    values : ndarray
        Non-negative magnitudes, one per state.
    reference : float
        The phase's largest such magnitude.
    """
    out = np.array(values, dtype=float)
    out[out <= NOISE * reference] = 0.0
    return out


def _control_size(lo: float, hi: float, values: np.ndarray) -> float:
    """A control's size: its finite bounds' largest magnitude, else its start's, else 1."""
    mags = [abs(v) for v in (lo, hi) if math.isfinite(v)]
    if mags and max(mags) > 0:
        return max(mags)
    m = float(np.max(np.abs(values))) if values.size else 0.0
    return m if m > 0 else 1.0


def _rates(tr: Any, i: int, data: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """At the start's points: the largest ``|f|`` per state, and ``|df/dx|`` (its diagonal
    zeroed: a state's own rate says nothing of its size) and ``|df/du|``, each
    ``(row, point, column)``; None where not finite."""
    n, nx, nu = len(data.t), tr.compiled[i].nx, tr.compiled[i].nu
    if n == 0:
        return None
    try:
        with np.errstate(all="ignore"):
            f, jx, ju = (np.array(a, dtype=float) for a in _rate_function(tr, i).map(n)(
                data.t[None, :], data.x.T, data.u_points.T, np.asarray(data.s)[:, None]))
    except RuntimeError:  # a function CasADi cannot evaluate there: the start says nothing
        return None
    jx = np.abs(jx).reshape(nx, n, nx)  # map stacks the points' Jacobians side by side
    jx[np.arange(nx), :, np.arange(nx)] = 0.0
    ju = np.abs(ju).reshape(nx, n, nu)
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(jx)) and np.all(np.isfinite(ju))):
        return None
    return np.max(np.abs(f), axis=1), jx, ju


def _coupled(rates: tuple[np.ndarray, np.ndarray, np.ndarray], s: np.ndarray,
             su: np.ndarray) -> np.ndarray:
    """The largest rate the other states and the controls can give each state at their
    sizes: ``max over points and columns of |df/dx_j| s_j, |df/du_k| su_k``."""
    _, jx, ju = rates
    out = np.max(jx * s, axis=(1, 2)) if jx.size else np.zeros(s.size)
    if su.size:
        out = np.maximum(out, np.max(ju * su, axis=(1, 2)))
    return out


def _rate_function(tr: Any, i: int) -> ca.Function:
    """``(t, x, u, s) -> (f, df/dx, df/du)`` of phase ``i`` (built once per problem)."""
    key = ("rate", i)
    fns = tr.grid_free.functions
    if key not in fns:
        cp = tr.compiled[i]
        t, x, u, sv = (ca.SX.sym(n, k) for n, k in (("t", 1), ("x", cp.nx), ("u", cp.nu),
                                                    ("s", cp.ns)))
        f = cp.ode(t, x, u, sv)[0]
        fns[key] = ca.Function("rate", [t, x, u, sv],
                               [f, ca.jacobian(f, x), ca.jacobian(f, u)])
    return fns[key]


def carried_scaling(tr: Any, start: Any) -> Scaling | None:
    """The scaling of the solve that found ``start`` (a solution of the same problem on
    another mesh), mapped onto ``tr``; None if ``start`` carries none.

    Mesh refinement keeps its first round's scaling (and objective scale) in every
    round, and a solve warm-started from a solution of the same problem on another grid
    at the same parameters keeps that solution's: the same problem on another mesh is
    then the same NLP to Ipopt.

    Parameters
    ----------
    tr : Transcription
        The transcription.
    start : Solution or anything
        Where the solve starts from.
    """
    sc = getattr(start, "scaling", None) if hasattr(start, "transcription") else None
    if sc is None or not same_problem(getattr(start.transcription, "multiphase", None),
                                      tr.multiphase):
        return None
    if not sc.enabled:
        return identity(tr.n_w, tr.n_g)
    return with_state_refs(tr, sc.state_refs) if sc.state_refs is not None else None


def same_problem(a: Any, b: Any) -> bool:
    """Whether two transcriptions' problems are the same: the same multi-phase problem, or
    views of the same phases (a one-phase problem is wrapped anew by each transcription).

    Parameters
    ----------
    a, b : MultiPhaseProblem or None
        The transcriptions' ``multiphase``.
    """
    if a is None or b is None:
        return False
    return a is b or (len(a.phases) == len(b.phases) and a.shared is b.shared
                      and all(p is q for p, q in zip(a.phases, b.phases, strict=True)))
