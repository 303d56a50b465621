"""The one definition of the soft-landing dynamics.

Everything else in the toolkit (the OCP, the PMP checks, the hybrid
simulator's mode matrices, the impedance layer) is derived from
:func:`robot_rhs` below; do not write the equations anywhere else.

State ``x = [x_b, v_b, x_f, v_f]`` (dimensionless body height, body velocity,
foot height, foot velocity, measured up from the undisturbed ground surface),
control ``u`` (actuator force, > 0 pushes body and foot apart), ground reaction
``f_g`` (upward force on the foot), all in the units of the paper's Section II-C.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from softlanding.errors import POSITIVE, check
from softlanding.model.ground import LINEAR_GROUND, Ground
from softlanding.model.robot import STATE_NAMES, VB, VF, XB, XF  # the state layout (re-exported)


def robot_rhs(x, u, f_g, r_m, m_a=0.0):
    """Time derivative of the state for a given actuator force and ground force.

    Newton's law for the body (mass ``r_m/(1+r_m)``) and the foot (mass
    ``1/(1+r_m)``) in units of the total mass:

    ``x_b'' = -1 + (1 + r_m)/r_m * u`` and ``x_f'' = -1 + (1 + r_m) (f_g - u)``;

    with grains of mass ``m_a`` moving with the foot (an added-mass ground model),
    ``(m_f + m_a) x_f'' = -m_f + f_g - u`` (their weight is carried by the bed; the
    momentum they take is part of ``f_g``).

    Parameters
    ----------
    x : casadi SX/MX/DM or array of 4
        State ``[x_b, v_b, x_f, v_f]``.
    u : scalar expression
        Actuator force.
    f_g : scalar expression
        Ground reaction on the foot (upward positive).
    r_m : scalar expression or float
        Mass ratio ``m_b / m_f``.
    m_a : scalar expression or float
        Added mass moving with the foot (units of ``m_t``; 0 for the paper's ground).

    Returns
    -------
    casadi expression of shape (4, 1)
    """
    if isinstance(m_a, int | float) and m_a == 0.0:
        foot = -1 + (1 + r_m) * (f_g - u)  # the paper's form (bit-identical mode matrices)
    else:
        m_f = 1 / (1 + r_m)
        foot = (-m_f + f_g - u) / (m_f + m_a)
    return ca.vertcat(x[VB], -1 + (1 + r_m) / r_m * u, x[VF], foot)


def yielding_ground_force(x, ground: Ground = LINEAR_GROUND):
    """Upward ground force on a yielding foot, from the ground model: ``f(-x_f, v_f)``.

    Parameters
    ----------
    x : casadi expression or array of 4
        State ``[x_b, v_b, x_f, v_f]``.
    ground : Ground
        Ground model.
    """
    return ground.yield_force(-x[XF], x[VF])


def mechanical_energy(x, r_m):
    """Robot mechanical energy (kinetic + gravitational), in units of ``m_t g x_s``.

    Gravitational energy is measured from heights 0, so differences are what
    matter; :mod:`softlanding.simulation.simulator` reports energies relative to the
    configuration at impact (its kernel reads this quadratic form off here).

    Parameters
    ----------
    x : casadi expression or array of 4
        State ``[x_b, v_b, x_f, v_f]``.
    r_m : float or expression
        Mass ratio.
    """
    mb, mf = r_m / (1 + r_m), 1 / (1 + r_m)
    return 0.5 * mb * x[VB] ** 2 + 0.5 * mf * x[VF] ** 2 + mb * x[XB] + mf * x[XF]


@lru_cache(maxsize=1)
def _symbols():
    x = ca.SX.sym("x", 4)
    u = ca.SX.sym("u")
    fg = ca.SX.sym("f_g")
    r = ca.SX.sym("r_m")
    return x, u, fg, r


@lru_cache(maxsize=16)
def stance_functions(ground: Ground = LINEAR_GROUND) -> tuple[ca.Function, ca.Function]:
    """The paper's control-affine yielding-stance dynamics ``x' = f(x) + g(x) u``.

    Parameters
    ----------
    ground : Ground
        Ground model of the yielding stance.

    Returns
    -------
    f, g : casadi.Function
        ``f(x, r_m)`` (4x1) and ``g(x, r_m)`` (4x1), derived from
        :func:`robot_rhs` with the ground model's yielding force.
    """
    x, u, _, r = _symbols()
    xdot = stance_dynamics(x, u, r, ground)
    g = ca.jacobian(xdot, u)
    f = ca.substitute(xdot, u, 0)
    return (
        ca.Function("f", [x, r], [f], ["x", "r_m"], ["f"]),
        ca.Function("g", [x, r], [g], ["x", "r_m"], ["g"]),
    )


def stance_dynamics(x, u, r_m, ground: Ground = LINEAR_GROUND):
    """``f(x) + g(x) u`` for symbolic or numeric arguments (used by the OCP).

    Parameters
    ----------
    x : casadi expression or array of 4
        State ``[x_b, v_b, x_f, v_f]``.
    u : scalar expression
        Actuator force.
    r_m : float or expression
        Mass ratio.
    ground : Ground
        Ground model of the yielding stance.
    """
    return robot_rhs(x, u, yielding_ground_force(x, ground), r_m,
                     ground.added_mass(-x[XF]))


@lru_cache(maxsize=16)
def _affine_parts(ground: Ground) -> ca.Function:
    """Jacobians of :func:`robot_rhs` (affine in x, u and f_g), of the ground law, and the
    energy's quadratic form (all exact: every one of them is at most quadratic)."""
    x, u, fg, r = _symbols()
    rhs = robot_rhs(x, u, fg, r)
    c = ca.substitute(rhs, ca.vertcat(x, u, fg), ca.DM.zeros(6))
    force = yielding_ground_force(x, ground)
    E = mechanical_energy(x, r)
    zero = ca.DM.zeros(4)
    depth = ca.SX.sym("d")
    return ca.Function(
        "affine_parts",
        [r],
        [ca.jacobian(rhs, x), ca.jacobian(rhs, u), ca.jacobian(rhs, fg), c,
         ca.substitute(ca.jacobian(force, x), x, zero), ca.substitute(force, x, zero),
         ca.hessian(E, x)[0], ca.substitute(ca.gradient(E, x), x, zero),
         ca.substitute(ca.jacobian(ground.yield_force(depth, 0.0), depth), depth, 0.0)],
    )


@lru_cache(maxsize=64)
def mode_matrices(r_m: float, ground: Ground = LINEAR_GROUND) -> dict[str, np.ndarray]:
    """Numeric affine matrices of the three ground modes, read off :func:`robot_rhs`.

    Uses the augmented state ``z = [x_b, v_b, x_f, v_f, 1]`` so each mode is
    ``z' = A z + B u`` with ``A`` 5x5 (last row zero) and ``B`` of length 5.

    * ``yielding``: ``f_g`` = the ground model's yielding force (affine in x);
    * ``flight``:   ``f_g = 0``;
    * ``static``:   ``f_g`` is the support force that keeps the foot still,
      ``F_req(z, u) = Fz . z + Fu u``; the foot rows are exactly zero.

    Parameters
    ----------
    r_m : float
        Mass ratio (> 0).
    ground : Ground
        Must be affine (``ground.is_affine``).

    Returns
    -------
    dict
        ``A`` (3, 5, 5) and ``B`` (3, 5) indexed by mode (0 yielding, 1 static,
        2 flight), ``Fz`` (5,), ``Fu`` (float); the mechanical energy as the
        quadratic form ``E(z) = z . EQ z / 2 + Ec . z`` (``EQ`` (5, 5), ``Ec`` (5,));
        ``Wg``, the ground work ``Wg d^2`` done by a foot that dug to depth
        ``d`` (``Wg = f'(d) / 2`` for the affine ground law ``f``); and ``hold``, the
        crater's stiffness ``f(d, 0) / d`` (``K`` of ``f = K d``: the crater of depth ``d``
        holds support forces up to ``hold * d``; for a law whose ``f(d, 0)`` is not
        proportional to ``d`` it is the slope at the surface, and the simulator
        integrates, see :func:`softlanding.simulation.groundcode.needs_integration`).
    """
    r_m = check("r_m", r_m, POSITIVE)  # the Robot holds the range; any mass ratio > 0 here
    if not ground.is_affine:
        raise ValueError(f"the {ground.name} ground is not affine: no mode matrices")
    parts = [np.array(m, dtype=float) for m in _affine_parts(ground)(r_m)]
    Ax, Bu, Bg, c, Cg, cg, Hq, dE, kg = parts
    Bu, Bg, c, Cg, dE = Bu.ravel(), Bg.ravel(), c.ravel(), Cg.ravel(), dE.ravel()

    def aug(A4, c4):
        A = np.zeros((5, 5))
        A[:4, :4] = A4
        A[:4, 4] = c4
        return A

    A = np.zeros((3, 5, 5))
    B = np.zeros((3, 5))
    # yielding: f_g = Cg . x + cg
    A[0] = aug(Ax + np.outer(Bg, Cg), c + Bg * cg.item())
    B[0, :4] = Bu
    # static: choose f_g so that the foot acceleration vanishes
    Fz = np.zeros(5)
    Fz[:4] = -Ax[VF] / Bg[VF]
    Fz[4] = -c[VF] / Bg[VF]
    Fu = float(-Bu[VF] / Bg[VF])
    A[1] = aug(Ax + np.outer(Bg, Fz[:4]), c + Bg * Fz[4])
    B[1, :4] = Bu + Bg * Fu
    A[1, XF, :] = 0.0  # foot pinned: exact zeros, not rounding residue
    A[1, VF, :] = 0.0
    B[1, XF] = B[1, VF] = 0.0
    # flight: no ground force
    A[2] = aug(Ax, c)
    B[2, :4] = Bu
    EQ = np.zeros((5, 5))
    EQ[:4, :4] = Hq
    Ec = np.zeros(5)
    Ec[:4] = dE
    return {"A": A, "B": B, "Fz": Fz, "Fu": Fu, "EQ": EQ, "Ec": Ec, "Wg": 0.5 * kg.item(),
            "hold": kg.item(),
            # gravitational weights of body and foot (dE/dx_b, dE/dx_f): the mass fractions
            "E": np.array([dE[XB], dE[XF]])}


__all__ = ["STATE_NAMES", "mechanical_energy", "mode_matrices", "robot_rhs", "stance_dynamics",
           "stance_functions", "yielding_ground_force"]
