"""Singular arcs: the switching function's time derivatives, the order, the singular control.

Conventions of the minimum principle (:mod:`ocp.certificate.certify`): ``H = L + lambda^T f``
with ``f`` and ``L`` affine in control ``u_j``, whose switching function is
``sigma_j = dH/du_j``. On a singular arc ``sigma_j`` vanishes on an interval, and so do
its time derivatives along the extremal flow ``x' = f``, ``lambda' = -H_x``. The control
first appears, with a coefficient not identically zero, in an even derivative
``sigma^(2k) = a + b u_j``: ``k`` is the arc's *order*, the *singular control* is
``u_j = -a / b`` (a function of state and costate), and Kelley's generalised
Legendre--Clebsch condition, necessary for a minimum, is ``(-1)^k b >= 0``.

:func:`singular_algebra` builds these once per problem and control (the other controls
are held constant along the derivatives: bang arcs of theirs). Whether a coefficient is
*identically* zero is decided numerically at random points (CasADi does not simplify
the Lie brackets that cancel): a term that vanishes there is dropped.
:func:`singular_feedback` eliminates the costate from the singular control with the
arc's own conditions ``sigma = sigma' = ... = sigma^(2k-1) = 0`` (affine in the
costate) so that the refinement (:mod:`ocp.structure.flows`, mode ``"singular"``)
can fly the arc as a state feedback. Both the certificate and the refinement use this
module; it imports only :mod:`ocp.definition`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..definition.problem import OptimalControlProblem

MAX_DERIVATIVE = 8
"""Highest derivative of the switching function searched for the control (order 4)."""

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass
class SingularAlgebra:
    """The switching function of one control, its derivatives, order and singular control.

    Attributes
    ----------
    control : str
        The control's name.
    order : int or None
        ``k`` (the control appears first in ``sigma^(2k)``); None when it appears in an
        odd derivative (``irregular``) or not up to :data:`MAX_DERIVATIVE`.
    derivatives : list of SX
        ``sigma, sigma', ..., sigma^(2k-1)``: expressions of ``(x, lam, u, p)`` free of
        this control (the other controls are constants on the arc).
    a, b : SX
        ``sigma^(2k) = a + b u_j``.
    lam : SX
        The costate symbols of the expressions.
    reason : str
        Why there is no order ("" when there is one).
    """

    control: str
    order: int | None
    derivatives: list[ca.SX]
    a: ca.SX
    b: ca.SX
    lam: ca.SX
    reason: str = ""

    @property
    def law(self) -> ca.SX:
        """The singular control ``-a / b`` as an expression of ``(x, lam, u, p)``."""
        return -self.a / self.b

    @property
    def kelley(self) -> ca.SX:
        """``(-1)^k b``: Kelley's condition asks it to be >= 0 (minimum principle)."""
        return (-1) ** int(self.order or 0) * self.b

    def functions(self, pr: OptimalControlProblem) -> ca.Function:
        """``(x, u, lam, p) -> (derivatives (2k,), law, kelley)`` as one CasADi function.

        Parameters
        ----------
        pr : OptimalControlProblem
            The problem the algebra was built for.
        """
        d = ca.vertcat(*self.derivatives) if self.derivatives else ca.SX(0, 1)
        return ca.Function("singular", [pr.x, pr.u, self.lam, pr.p], [d, self.law, self.kelley])


def hamiltonian(pr: OptimalControlProblem, lam: ca.SX) -> ca.SX:
    """``H = L + lam^T f`` (minimum principle).

    Parameters
    ----------
    pr : OptimalControlProblem
    lam : SX (nx,)
        Costate symbols.
    """
    return ca.SX(pr.lagrange) + ca.dot(lam, pr.rhs)


def _vanishes(expr: ca.SX, args: list[ca.SX], points: int = 5) -> bool:
    """``expr`` is zero (to rounding) at ``points`` random points of ``args`` in [0.5, 1.5]
    (positive: square roots and logarithms of states stay defined)."""
    if expr.is_zero():
        return True
    fn = ca.Function("v", args, [expr])
    rng = np.random.default_rng(12345)
    for _ in range(points):
        vals = [rng.uniform(0.5, 1.5, a.numel()) for a in args]
        with np.errstate(all="ignore"):
            v = np.abs(np.array(fn(*vals), dtype=float))
        if not np.all(np.isfinite(v)) or np.any(v > 1e-10):
            return False
    return True


def singular_algebra(pr: OptimalControlProblem, control: str) -> SingularAlgebra:
    """The switching function of ``control``, differentiated until the control appears.

    Parameters
    ----------
    pr : OptimalControlProblem
        Control-affine in ``control``, with a running cost affine in it.
    control : str

    Returns
    -------
    SingularAlgebra
        Cached per problem and control.

    Raises
    ------
    ValueError
        When H is not linear in the control (no singular arc: an interior arc of a
        strictly convex H is regular).
    """
    per = _CACHE.setdefault(pr, {})
    if control in per:
        return per[control]
    j = pr.control_names.index(control)
    uj = pr.u[j]
    lam = ca.SX.sym("lam", pr.nx)
    H = hamiltonian(pr, lam)
    args = [pr.x, pr.u, lam, pr.p]
    if not _vanishes(ca.hessian(H, uj)[0], args):
        raise ValueError(f"H is not linear in {control!r}: an interior arc of it is regular "
                         "(H_u = 0, H_uu > 0), not singular")
    f, Hx = pr.rhs, ca.gradient(H, pr.x)
    e = ca.substitute(ca.jacobian(H, uj), uj, 0)
    out: list[ca.SX] = []
    for q in range(MAX_DERIVATIVE + 1):
        out.append(e)
        de = ca.jtimes(e, pr.x, f) - ca.jtimes(e, lam, Hx)
        b = ca.jacobian(de, uj)
        a = ca.substitute(de, uj, 0)
        if not _vanishes(b, args):
            if q % 2 == 0:  # u in an odd derivative: no intrinsic order
                alg = SingularAlgebra(control, None, out, a, b, lam,
                                      f"{control!r} appears in the odd derivative "
                                      f"d^{q + 1} sigma/dt^{q + 1}: no intrinsic order")
            else:
                alg = SingularAlgebra(control, (q + 1) // 2, out, a, b, lam)
            per[control] = alg
            return alg
        e = a
    alg = SingularAlgebra(control, None, out, ca.SX(0), ca.SX(0), lam,
                          f"{control!r} does not appear in the first {MAX_DERIVATIVE} "
                          "derivatives of its switching function")
    per[control] = alg
    return alg


def singular_feedback(pr: OptimalControlProblem, control: str,
                      others: dict[str, ca.SX]) -> ca.SX:
    """The singular control of ``control`` as a state feedback ``u_j(x, p)``.

    The law ``-a / b`` depends on the costate in general; the arc's conditions
    ``sigma^(i) = 0`` (``i < 2k``) are affine in it, ``E(x) lam + e(x) = 0``. With ``e``
    identically zero (no running cost in the rows) the law is homogeneous of degree 0
    in the costate, which is taken along the generalised cross product of the first
    ``nx - 1`` rows; otherwise the first ``nx`` rows are solved for it.

    Parameters
    ----------
    pr : OptimalControlProblem
    control : str
    others : dict of str to SX
        The other controls' values on the arc (expressions of ``x`` and ``p``).

    Returns
    -------
    SX
        ``u_j(x, p)``.

    Raises
    ------
    ValueError
        When the control has no order, or the arc's conditions do not determine the
        costate the law depends on.
    """
    alg = singular_algebra(pr, control)
    if alg.order is None:
        raise ValueError(f"no singular control for {control!r}: {alg.reason}")
    names = [n for n in pr.control_names if n != control]
    syms = ca.vertcat(*[pr.u[pr.control_names.index(n)] for n in names]) if names else None

    def sub(e: ca.SX) -> ca.SX:
        return ca.substitute(e, syms, ca.vertcat(*[others[n] for n in names])) \
            if syms is not None else e

    law = sub(alg.law)
    lam = alg.lam
    if not ca.depends_on(law, lam):
        return law
    rows = ca.vertcat(*[sub(d) for d in alg.derivatives])
    E = ca.jacobian(rows, lam)
    e = ca.substitute(rows, lam, ca.DM.zeros(pr.nx))
    n = pr.nx
    if _vanishes(e, [pr.x, pr.p]):
        if rows.numel() < n - 1:
            raise ValueError(_underdetermined(control, rows.numel(), n - 1))
        M = E[:n - 1, :]
        value = ca.vertcat(*[(-1) ** i * ca.det(M[:, [c for c in range(n) if c != i]])
                             for i in range(n)]) if n > 1 else ca.SX(1)
    else:
        if rows.numel() < n:
            raise ValueError(_underdetermined(control, rows.numel(), n))
        value = -ca.solve(E[:n, :], e[:n])
    return ca.substitute(law, lam, value)


def _underdetermined(control: str, have: int, need: int) -> str:
    return (f"the singular control of {control!r} depends on the costate, and its arc's "
            f"{have} condition(s) sigma^(i) = 0 do not determine it from the state ({need} "
            "needed): it cannot be flown as a state feedback")


__all__ = ["MAX_DERIVATIVE", "SingularAlgebra", "hamiltonian", "singular_algebra",
           "singular_feedback"]
