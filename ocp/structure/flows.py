"""Arc dynamics for switching-time refinement and the PMP certificate.

An *arc mode* says, for every control, what it does on an interval of time:
sit at its upper bound (``"max"``), its lower bound (``"min"``), keep a path
constraint at one of its limits (``"boundary"``), or sit at a vertex of the
control set cut by a control-only constraint held at a limit (``"vertex"``:
``u1 = 1 - u2`` on ``u1 + u2 <= 1`` with ``u2`` at its lower bound, a value
inside ``u1``'s own bounds). :class:`ArcDynamics` turns a
tuple of modes into closed-loop dynamics ``x' = F(x, p) = f(x, u(x, p), p)``
(and the running cost ``L(x, u(x, p), p)``), with

* the **boundary control law**: for a constraint ``c(x, p)`` of relative
  degree ``r`` in the boundary control (``r`` = how often ``c`` must be
  differentiated along the dynamics before the control appears), the control
  solves ``d^r c / dt^r = 0`` (``c = limit`` when ``r = 0``); for a
  control-affine problem the solution is explicit, ``u = -L_f^r c / L_g L_f^{r-1} c``.
  Entering the arc needs ``c = limit, c' = 0, ..., c^(r-1) = 0``: the
  *entry conditions*;
* the **flow** over a duration ``tau`` in ``m`` equal sub-steps: exact (a
  Taylor polynomial of the matrix exponential of the augmented matrix
  ``[[A, b], [0, 0]]``, accurate to rounding while ``||A|| tau / m <= 1``) when
  the closed loop and the running cost are affine in the state, else a
  fixed-step explicit Runge-Kutta method of order 8 (the Dormand-Prince 8
  tableau, as in scipy's DOP853), whose step count is chosen from the
  requested accuracy and verified by halving.

Every symbolic object here is a CasADi ``SX`` expression of the state and the
problem parameters, so one build serves every parameter value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..definition.problem import Constraint, OptimalControlProblem
from .costate_copies import copy_rhs
from .free_laws import free_arc_laws

TAYLOR_ORDER = 18
"""Degree of the Taylor polynomial of ``expm``: error ``theta^19/19!`` <= 8e-18 at theta = 1."""

THETA_MAX = 1.0
"""Largest ``||A||_1 tau / m`` an exact sub-step may have (accuracy to rounding)."""

RK_ORDER = 8


@lru_cache(maxsize=1)
def rk8_tableau() -> tuple[np.ndarray, np.ndarray]:
    """``A`` (12, 12) and ``b`` (12,) of the explicit 8th-order Dormand-Prince method
    (read from scipy's DOP853; imported on first use, scipy.integrate is slow to import)."""
    from scipy.integrate._ivp import dop853_coefficients as dop

    n = dop.N_STAGES
    return np.asarray(dop.A[:n, :n], dtype=float), np.asarray(dop.B, dtype=float)


@dataclass(frozen=True)
class Mode:
    """What one control does on an arc.

    Parameters
    ----------
    kind : {"max", "min", "boundary", "vertex", "singular", "interior"}
        At a bound; keeping (state or mixed) path constraint ``constraint`` at its
        ``side`` limit; at the vertex of the control set where control-only
        constraint ``constraint`` is at its ``side`` limit (the other controls'
        modes fixing the rest); on a singular arc (the singular control as a state
        feedback); on a regular interior arc, ``H_u = 0`` with the costate copy of run
        ``run`` (both: :mod:`ocp.structure.free_laws`).
    constraint : str, optional
        Name of the path constraint kept at its limit (boundary and vertex arcs).
    side : {"lower", "upper"}, optional
        Which limit of ``constraint``.
    run : int, optional
        An interior mode's run (which costate copy, :mod:`ocp.structure.costate_copies`).
    """

    kind: str
    constraint: str | None = None
    side: str | None = None
    run: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("max", "min", "boundary", "vertex", "singular", "interior"):
            raise ValueError(f"mode kind {self.kind!r} is not one of 'max', 'min', "
                             "'boundary', 'vertex', 'singular', 'interior'")
        if self.held != (self.constraint is not None):
            raise ValueError(f"a {self.kind} mode needs a constraint, a bang mode none")
        if self.held and self.side not in ("lower", "upper"):
            raise ValueError(f"a {self.kind} mode needs side 'lower' or 'upper'")

    @property
    def held(self) -> bool:
        """True for the modes that hold a constraint at a limit (boundary, vertex)."""
        return self.kind in ("boundary", "vertex")

    def label(self) -> str:
        """``"max"``, ``"min"``, ``"boundary(<constraint> <side>)"`` or
        ``"vertex(<constraint> <side>)"``."""
        if self.held:
            return f"{self.kind}({self.constraint} {self.side})"
        return self.kind


def path_constraint(pr: OptimalControlProblem, name: str) -> Constraint:
    """The path constraint called ``name``.

    Parameters
    ----------
    pr : OptimalControlProblem
    name : str

    Returns
    -------
    Constraint
    """
    for c in pr.structure_path:
        if c.name == name:
            return c
    have = [c.name for c in pr.structure_path]
    raise ValueError(f"no path constraint named {name!r}; have {have}")


def has_running_cost(pr: OptimalControlProblem) -> bool:
    """True when the problem has a Lagrange term.

    Parameters
    ----------
    pr : OptimalControlProblem
        The problem.
    """
    return not (isinstance(pr.lagrange, ca.SX) and pr.lagrange.is_zero())


def is_affine(expr: ca.SX, z: ca.SX) -> bool:
    """True when ``expr`` is affine in ``z``.

    Parameters
    ----------
    expr, z : SX

    Returns
    -------
    bool
    """
    return not ca.depends_on(ca.jacobian(expr, z), z)


def lie_derivative(expr: ca.SX, x: ca.SX, rhs: ca.SX) -> ca.SX:
    """Time derivative ``d expr / dt = grad_x(expr) . rhs`` of an expression of (x, p).

    Parameters
    ----------
    expr : SX
        An expression of the state ``x`` (and parameters).
    x : SX
        The state symbols.
    rhs : SX
        ``x'`` as an expression.

    Returns
    -------
    SX
    """
    return ca.jtimes(expr, x, rhs)


class ArcDynamics:
    """Closed-loop dynamics of one arc mode (one :class:`Mode` per control).

    Parameters
    ----------
    problem : OptimalControlProblem
        Control-affine in every boundary control.
    modes : tuple of Mode
        One per control, in ``problem.control_names`` order.

    Attributes
    ----------
    u : SX (nu,)
        The controls as expressions of ``(problem.x, problem.p)``.
    rhs, lagrange : SX
        Closed-loop ``F(x, p)`` and ``L(x, u(x, p), p)``.
    entry : list of (str, SX)
        Entry conditions ``expr(x, p) = 0`` of the boundary arcs (named).
    law_bounds : list of (str, SX, SX, SX)
        ``(name, expr, lower, upper)``: the boundary controls within their bounds.
    held : tuple of str
        Path constraints held at a limit by this mode.
    orders : dict
        Relative degree of each held constraint.
    exact : bool
        Closed loop and running cost affine in x: exact flow by the matrix exponential.
    """

    def __init__(self, problem: OptimalControlProblem, modes: tuple[Mode, ...]) -> None:
        pr = problem
        if len(modes) != pr.nu:
            raise ValueError(f"{len(modes)} modes for {pr.nu} controls")
        self.problem, self.modes = pr, tuple(modes)
        x, p = pr.x, pr.p
        usyms = [pr.u[i] for i in range(pr.nu)]
        fixed, values, by_name = [], [], {}
        for name, sym, mode in zip(pr.control_names, usyms, modes, strict=True):
            if mode.kind in ("max", "min"):
                lo, hi = pr.control_limits[name]
                bound = hi if mode.kind == "max" else lo
                if bound.is_constant() and not math.isfinite(float(bound)):
                    raise ValueError(f"control {name!r} has no finite {mode.kind} bound")
                fixed.append(sym)
                values.append(bound)
                by_name[name] = bound
        rhs = pr.rhs
        if fixed:
            rhs = ca.substitute(rhs, ca.vertcat(*fixed), ca.vertcat(*values))
        self.entry: list[tuple[str, ca.SX]] = []
        self.law_bounds: list[tuple[str, ca.SX, ca.SX, ca.SX]] = []
        self.orders: dict[str, int] = {}
        by_name.update(self._boundary_laws(rhs, fixed, values))
        by_name.update(free_arc_laws(self, by_name))  # singular and interior arcs
        u = [by_name[name] for name in pr.control_names]
        self.u = ca.vertcat(*u)
        self.rhs = ca.substitute(copy_rhs(pr, tuple(m.run for m in modes)), pr.u, self.u)
        self.lagrange = ca.substitute(ca.SX(pr.lagrange), pr.u, self.u)
        self.held = tuple(m.constraint for m in modes if m.constraint is not None)
        self.has_quad = has_running_cost(pr)
        self.exact = is_affine(self.rhs, x) and (not self.has_quad or is_affine(self.lagrange, x))
        nz = pr.nx + (1 if self.has_quad else 0)
        z = ca.SX.sym("z", nz)
        zdot = ca.vertcat(self.rhs, self.lagrange) if self.has_quad else self.rhs
        zdot = ca.substitute(zdot, x, z[:pr.nx])
        self.nz = nz
        self.f_z = ca.Function("F", [z, p], [zdot], ["z", "p"], ["zdot"])
        self.u_fn = ca.Function("u", [x, p], [self.u], ["x", "p"], ["u"])
        if self.exact:
            A = ca.jacobian(zdot, z)
            b = ca.substitute(zdot, z, ca.DM.zeros(nz))
            self.A_fn = ca.Function("A", [p], [A, b], ["p"], ["A", "b"])

    def _boundary_laws(self, rhs: ca.SX, fixed: list, values: list) -> dict[str, ca.SX]:
        """Solve ``d^r c / dt^r = 0`` of every held constraint for its boundary control."""
        pr = self.problem
        x = pr.x
        bnames = [n for n, m in zip(pr.control_names, self.modes, strict=True) if m.held]
        if not bnames:
            return {}
        uB = ca.vertcat(*[pr.u[pr.control_names.index(n)] for n in bnames])
        eqs = []
        for name in bnames:
            mode = self.modes[pr.control_names.index(name)]
            assert mode.constraint is not None
            c = path_constraint(pr, mode.constraint)
            limit = c.lower if mode.side == "lower" else c.upper
            if limit.is_constant() and not math.isfinite(float(limit)):
                raise ValueError(f"{c.name!r} has no finite {mode.side} limit")
            d = ca.substitute(c.expr, ca.vertcat(*fixed), ca.vertcat(*values)) if fixed else c.expr
            if mode.kind == "vertex" and (ca.depends_on(c.expr, x) or not ca.depends_on(d, uB)):
                raise ValueError(f"vertex mode of {name!r}: {c.name!r} must be a control-only "
                                 "constraint involving it")
            r = 0
            while not ca.depends_on(d, uB):
                if r == 3:
                    raise ValueError(f"constraint {c.name!r}: relative degree above 3 in "
                                     f"{bnames}; not supported")
                what = f"{c.name} = {mode.side} limit" if r == 0 else f"d^{r}/dt^{r} {c.name} = 0"
                self.entry.append((what, d - limit if r == 0 else d))
                d = lie_derivative(d, x, rhs)
                r += 1
            self.orders[c.name] = r
            eqs.append(d - limit if r == 0 else d)
        E = ca.vertcat(*eqs)
        J = ca.jacobian(E, uB)
        if ca.depends_on(J, uB):
            raise ValueError("the boundary control enters nonlinearly: the problem must be "
                             "control-affine for boundary arcs")
        e0 = ca.substitute(E, uB, ca.DM.zeros(uB.numel()))
        kappa = -e0 / J if uB.numel() == 1 else -ca.solve(J, e0)
        out = {}
        for i, name in enumerate(bnames):
            lo, hi = pr.control_limits[name]
            if self.modes[pr.control_names.index(name)].kind == "boundary":
                # a vertex value is a constant of p, checked once (a constant row at a
                # bound would leave an interior-point method no slack)
                self.law_bounds.append((f"{name} within its bounds", kappa[i], lo, hi))
            out[name] = kappa[i]
        return out

    # --------------------------------------------------------------- numeric
    def affine_numeric(self, pv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``A`` (nz, nz) and ``b`` (nz,) of ``z' = A z + b`` at parameters ``pv`` (exact only).

        Parameters
        ----------
        pv : ndarray
            Parameter values, in the problem's order.
        """
        A, b = self.A_fn(pv)
        return np.array(A, dtype=float), np.array(b, dtype=float).ravel()

    def norm_A(self, pv: np.ndarray) -> float:
        """``||A||_1`` at ``pv`` (exact arcs), which sets the sub-steps of the Taylor flow.

        Parameters
        ----------
        pv : ndarray
            Parameter values, in the problem's order.
        """
        return float(np.abs(self.affine_numeric(pv)[0]).sum(axis=0).max())

    def control_law_affine(self, pv: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(K, k0)`` with ``u = K x + k0`` when the controls are affine in x, else None.

        Parameters
        ----------
        pv : ndarray
            Parameter values, in the problem's order.
        """
        x = self.problem.x
        if not is_affine(self.u, x):
            return None
        fn = ca.Function("uk", [self.problem.p], [ca.jacobian(self.u, x),
                                                  ca.substitute(self.u, x, ca.DM.zeros(x.numel()))])
        K, k0 = fn(pv)
        return np.array(K, dtype=float), np.array(k0, dtype=float).ravel()


# ----------------------------------------------------------------- exact flows
def expm_taylor(X: ca.SX, order: int = TAYLOR_ORDER) -> ca.SX:
    """Taylor polynomial of ``expm(X)`` of degree ``order`` in Horner form (no scaling).

    Accurate to rounding while ``||X|| <= 1``; callers split long arcs into
    sub-steps rather than squaring.

    Parameters
    ----------
    X : SX (n, n)
    order : int

    Returns
    -------
    SX (n, n)
    """
    n = X.shape[0]
    eye = ca.SX.eye(n)
    E = eye + X / order
    for k in range(order - 1, 0, -1):
        E = eye + ca.mtimes(X, E) / k
    return E


def expm(M: np.ndarray) -> np.ndarray:
    """Matrix exponential of a small dense matrix, in numpy (accurate to rounding).

    Scaling and squaring with the degree-18 Taylor polynomial
    (``||M / 2^s||_1 <= 1``: truncation error below 1e-17 relative). Used
    instead of ``scipy.linalg.expm`` because scipy's bundled multi-threaded
    OpenBLAS makes every small LAPACK call take milliseconds on a busy machine
    (measured 16 ms for a 5x5 expm under load, 12 us single-threaded), while
    numpy's matrix products stay at microseconds.

    Parameters
    ----------
    M : ndarray
        A small square matrix.
    """
    M = np.asarray(M, dtype=float)
    nrm = float(np.abs(M).sum(axis=0).max()) if M.size else 0.0
    s = max(0, math.ceil(math.log2(nrm))) if nrm > 1.0 else 0
    X = M / 2.0**s
    eye = np.eye(M.shape[0])
    E = eye + X / TAYLOR_ORDER
    for k in range(TAYLOR_ORDER - 1, 0, -1):
        E = eye + (X @ E) / k
    for _ in range(s):
        E = E @ E
    return E


def numeric_affine_flow(A: np.ndarray, b: np.ndarray, z0: np.ndarray, tau: float,
                        m: int) -> np.ndarray:
    """States at ``m + 1`` equally spaced times of ``z' = A z + b`` on ``[0, tau]`` (exact).

    Parameters
    ----------
    A : ndarray (nz, nz)
    b : ndarray (nz,)
    z0 : ndarray (nz,)
        State at the start.
    tau : float
        Duration.
    m : int
        Number of equal steps; the step map is :func:`expm` of the augmented
        matrix ``[[A, b], [0, 0]] tau / m``.

    Returns
    -------
    ndarray (m+1, nz)
    """
    n = len(z0)
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = b
    E = expm(M * (tau / m))
    out = np.empty((m + 1, n))
    z = np.r_[z0, 1.0]
    out[0] = z0
    for j in range(m):
        z = E @ z
        out[j + 1] = z[:n]
    return out


# ------------------------------------------------------------------- RK8 flows
def rk8_step(f: ca.Function, z: Any, h: Any, p: Any) -> Any:
    """One step of the explicit 8th-order Dormand-Prince tableau (12 stages).

    Parameters
    ----------
    f : casadi.Function
        ``(z, p) -> z'``.
    z : SX, MX or DM
        State at the start of the step.
    h : scalar expression
        Step (negative to integrate backward).
    p : SX, MX or DM
        Parameters passed to ``f``.

    Returns
    -------
    The state after the step, of the type of ``z``.
    """
    A, B = rk8_tableau()
    k: list[Any] = []
    for i in range(A.shape[0]):
        zi = z
        for j in range(i):
            if A[i, j] != 0.0:
                zi = zi + h * float(A[i, j]) * k[j]
        k.append(f(zi, p))
    out = z
    for i, bi in enumerate(B):
        if bi != 0.0:
            out = out + h * float(bi) * k[i]
    return out


def rk8_step_function(f: ca.Function, nz: int, np_: int) -> ca.Function:
    """``(z, h, p) -> z_next`` by one RK8 step of ``z' = f(z, p)``, as an SX function.

    Parameters
    ----------
    f : casadi.Function
        ``(z, p) -> z'``.
    nz, np_ : int
        Sizes of ``z`` and ``p``.

    Returns
    -------
    casadi.Function
    """
    z = ca.SX.sym("z", nz)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", np_)
    return ca.Function("rk8", [z, h, p], [rk8_step(f, z, h, p)], ["z", "h", "p"], ["zf"])


_ACCUMULATED: dict[tuple[int, int], tuple[ca.Function, ca.Function]] = {}


def _mapaccum(step: ca.Function, n: int) -> ca.Function:
    """``step.mapaccum(n)``, built once per step function and count: building it costs more
    than a short flow's evaluation, and re-solves ask for the same flows sample after sample
    (the step is kept beside its key, so the id cannot be reused while cached)."""
    key = (id(step), n)
    hit = _ACCUMULATED.get(key)
    if hit is None or hit[0] is not step:
        if len(_ACCUMULATED) > 512:
            _ACCUMULATED.clear()
        hit = _ACCUMULATED[key] = (step, step.mapaccum(n))
    return hit[1]


def numeric_rk8_flow(step: ca.Function, z0: np.ndarray, tau: float, n: int,
                     pv: np.ndarray) -> np.ndarray:
    """States at the ``n + 1`` step points of ``n`` RK8 steps over ``[0, tau]``.

    Parameters
    ----------
    step : casadi.Function
        From :func:`rk8_step_function`.
    z0 : ndarray (nz,)
    tau : float
        Duration (negative: backward).
    n : int
        Number of steps.
    pv : ndarray
        Parameter values.

    Returns
    -------
    ndarray (n+1, nz)
    """
    Z = np.array(_mapaccum(step, n)(z0, tau / n, pv), dtype=float)
    return np.vstack([np.asarray(z0, dtype=float)[None, :], Z.T])


def rk8_steps_for(step: ca.Function, z0: np.ndarray, tau: float, pv: np.ndarray, tol: float,
                  minimum: int = 4, maximum: int = 8192) -> tuple[int, float]:
    """Smallest power-of-two multiple of ``minimum`` RK8 steps meeting ``tol``, by halving.

    The error of ``n`` steps is estimated as ``|z_n - z_2n| / max(1, |z|)``
    (``z_2n`` is ~256 times more accurate).

    Parameters
    ----------
    step : casadi.Function
        From :func:`rk8_step_function`.
    z0 : ndarray (nz,)
    tau : float
        Duration.
    pv : ndarray
        Parameter values.
    tol : float
        Required relative accuracy of the end state.
    minimum, maximum : int
        Fewest and most steps to try.

    Returns
    -------
    (int, float)
        The step count and its error estimate; ``maximum`` steps with a larger
        error when the tolerance cannot be met.
    """
    n = max(1, int(minimum))
    zn = numeric_rk8_flow(step, z0, tau, n, pv)[-1]
    while True:
        z2 = numeric_rk8_flow(step, z0, tau, 2 * n, pv)[-1]
        with np.errstate(invalid="ignore"):  # a non-finite flow ends the loop below
            err = float(np.max(np.abs(zn - z2)) / max(1.0, float(np.max(np.abs(z2)))))
        if err <= tol or 2 * n > maximum or not np.all(np.isfinite(z2)):
            return n, err
        n, zn = 2 * n, z2
