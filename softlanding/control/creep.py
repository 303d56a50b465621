"""The creep law: a compiled feedback that lands at the static depth ``W / K`` on ground with
drag, where the optimal landing is not bang-bang.

On ground ``f_g = K d + c_d v_f^2`` no landing ends shallower than the static depth
``d_s = W / K`` (at rest the crater holds the robot's weight ``W``), and where the drag can
take the robot's momentum before the foot reaches it, every landing that ends there is
optimal: the optimum is degenerate (the transcription's control is interior) and the
bang-bang plan of :mod:`softlanding.control.bangbang` ends with the body rising (its status
``CREEP``). From any measured state this law makes the foot stop exactly at ``d_s`` with the
robot's momentum spent, in closed form (no NLP):

* **The brake.** Under a constant force ``u`` the foot's ``z = v_f^2`` is linear in the
  distance ``sigma = d_s - d`` left: ``dz/dsigma = 2 c_1 - gamma sigma + beta z`` with
  ``c_1 = a_f0 + b_f u + g_f W``, ``beta = 2 g_f c_d``, ``gamma = 2 g_f K`` (the foot's
  acceleration ``a_f0 + b_f u + g_f f_g``), so from ``z(0) = 0``
  ``z(sigma) = -A expm1(beta sigma) + (gamma / beta) sigma``, ``A = (gamma/beta - 2 c_1) /
  beta``: the constant force that stops the foot exactly at ``d_s`` from ``(d, v_f)`` is
  linear in ``z``. The brake is ``u_e = -BRAKE h_0`` (``h_0`` the foot's weight share): the
  foot's support at the stop stays ``(1 - BRAKE) h_0 >= 0`` (it rests; a pull would lift
  it), and the drag does the braking. Once the force that stops the foot at ``d_s`` is at
  most ``u_e`` the law applies that force (recomputed every sample).
* **The cruise.** Before that, the foot is driven to a speed ``w`` (a proportional step of
  :data:`GAIN` of the gap per sample, through the foot's acceleration), cruising at ``w``
  then braking at ``u_e`` from ``w``: ``w`` is chosen so that the ground's impulse in excess
  of the weight over the rest, ``J = c_d w L - K (D^2 - sigma_b^2) / (2 w) + (w - c_1 t_b) /
  g_f`` (cruise over ``L = D - sigma_b``, then the brake over ``sigma_b``, ``w^2 =
  z(sigma_b)``, its time ``t_b`` by 8-point Gauss-Legendre on ``sigma = sigma_b tau^2``),
  equals ``-p``, the robot's momentum ``p = m_b v_b + m_f v_f``: the body is then at rest
  when the foot stops. Solved by bisection on ``sigma_b`` (monotone), every sample from the
  measured state and the estimated ground (feedback: the errors of the last sample are
  taken up by the next).

What it does not reach: a momentum larger than the drag can take at the force limit (the
foot's speed saturates; the body then arrives moving and its arrest digs a little deeper),
and ground with no drag (no creep: the law refuses, ``nan``). Measured on the 9 creep cases
of the unknown-ground study with exact sensing: see :func:`creep_force`'s callers
(:mod:`softlanding.control.bangbang`, phase ``CREEPING``).

The foot's and body's coefficients are the controller's numbers (from
:func:`softlanding.model.dynamics.robot_rhs`: one definition of the dynamics).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

JIT: dict[str, Any] = {"cache": True, "fastmath": False}

#: The brake's force as a fraction of the foot's weight share, pulling: the foot's support at
#: its stop is ``1 - BRAKE`` of its weight (it rests on the crater).
BRAKE = 0.5
#: The fraction of the gap to the cruise speed the foot's acceleration closes per sample.
GAIN = 0.5
#: The fraction of the force limit whose foot speed :func:`creep_reachable` counts on (the
#: rest accelerates the foot to it).
REACH = 0.8
#: Bisection steps on the brake's length (the cruise speed to ``2^-BISECT`` of the depth left).
BISECT = 48

# 8-point Gauss-Legendre on [0, 1] (the brake's time)
_GX, _GW = np.polynomial.legendre.leggauss(8)
GL_X = 0.5 * (_GX + 1.0)
GL_W = 0.5 * _GW


@njit(**JIT)
def brake_speed2(sigma: float, c1: float, beta: float, gam: float) -> float:
    """``v_f^2`` from which a constant force with foot deceleration ``c1`` at the stop stops
    the foot exactly ``sigma`` further down (``beta``, ``gam``: the drag's and the spring's
    ``2 g_f c_d``, ``2 g_f K``)."""
    bc = gam / beta
    return -((bc - 2.0 * c1) / beta) * math.expm1(beta * sigma) + bc * sigma


@njit(**JIT)
def brake_time(sigma: float, c1: float, beta: float, gam: float) -> float:
    """The brake's duration over ``sigma`` (``int dsigma / |v_f|``; ``sigma = sigma_b tau^2``
    takes the stop's inverse square root away)."""
    t = 0.0
    for i in range(GL_X.size):
        tau = GL_X[i]
        z = brake_speed2(sigma * tau * tau, c1, beta, gam)
        if z <= 0.0:
            return np.inf
        t += GL_W[i] * 2.0 * sigma * tau / math.sqrt(z)
    return t


@njit(**JIT)
def creep_force(af0: float, bf: float, gf: float, ab0: float, bb: float, u_max: float,
                hold0: float, k: float, c_d: float, x: np.ndarray, h: float) -> float:
    """The creep law's force from the state ``x`` (``nan``: the law does not apply: no drag
    or no spring, or a foot that does not descend).

    Parameters
    ----------
    af0, bf, gf : float
        The foot's acceleration ``af0 + bf u + gf f_g``.
    ab0, bb : float
        The body's ``ab0 + bb u``.
    u_max : float
        The force limit.
    hold0 : float
        The foot's weight share (the support a resting foot needs at no force).
    k, c_d : float
        The ground's ``K`` and drag number (the estimate).
    x : array of 4
        ``[x_b, v_b, x_f, v_f]``.
    h : float
        The sample period (the cruise's gain is per sample).
    """
    v = x[3]
    if not (k > 0.0 and c_d > 0.0 and v < 0.0 and h > 0.0):
        return np.nan
    m_f = 1.0 / gf
    m_b = -bf / (gf * bb)
    weight = -(m_b * ab0 + m_f * af0)
    d = -x[2]
    depth_left = weight / k - d
    u_e = -BRAKE * hold0
    beta, gam = 2.0 * gf * c_d, 2.0 * gf * k
    c1e = af0 + bf * u_e + gf * weight
    if depth_left <= 0.0:  # past the static depth: stop the foot at the brake's force
        return max(min(u_e, u_max), -u_max)
    # the constant force that stops the foot exactly at the static depth
    e = math.expm1(beta * depth_left)
    c1 = (v * v + (gam / beta) * (e / beta - depth_left)) * beta / (2.0 * e)
    u_b = (c1 - af0 - gf * weight) / bf
    if u_b <= u_e:
        return max(min(u_b, u_max), -u_max)
    # cruise: the brake's length sigma_b whose cruise speed spends the momentum
    q = -(m_b * x[1] + m_f * v)
    lo, hi = 0.0, depth_left
    for _ in range(BISECT):
        s = 0.5 * (lo + hi)
        w2 = brake_speed2(s, c1e, beta, gam)
        if not w2 > 0.0:
            lo = s
            continue
        w = math.sqrt(w2)
        j = c_d * w * (depth_left - s) - k * (depth_left * depth_left - s * s) / (2.0 * w) \
            + (w - c1e * brake_time(s, c1e, beta, gam)) / gf
        if j < q:
            lo = s
        else:
            hi = s
    w = math.sqrt(max(brake_speed2(0.5 * (lo + hi), c1e, beta, gam), 0.0))
    a = -GAIN / h * (v + w)
    u = (a - af0 - gf * (k * d + c_d * v * v)) / bf
    return max(min(u, u_max), -u_max)


@njit(**JIT)
def creep_reachable(af0: float, bf: float, gf: float, ab0: float, bb: float, u_max: float,
                    hold0: float, k: float, c_d: float, x: np.ndarray) -> bool:
    """The creep law can spend the robot's momentum before the static depth, cruising at
    most at the speed the foot holds under :data:`REACH` of the force limit (or its own, or
    the brake's from here), then braking: the landing then ends at the least depth any
    landing can (``W / K``), and the law should take over. Arguments as
    :func:`creep_force`'s."""
    v = x[3]
    if not (k > 0.0 and c_d > 0.0 and v < 0.0):
        return False
    m_f = 1.0 / gf
    m_b = -bf / (gf * bb)
    weight = -(m_b * ab0 + m_f * af0)
    d = -x[2]
    depth_left = weight / k - d
    if depth_left <= 0.0:
        return False
    beta, gam = 2.0 * gf * c_d, 2.0 * gf * k
    c1e = af0 - bf * BRAKE * hold0 + gf * weight
    top = brake_speed2(depth_left, c1e, beta, gam)
    if not top > v * v:  # braking from here: the force that stops the foot at the depth
        e = math.expm1(beta * depth_left)
        c1 = (v * v + (gam / beta) * (e / beta - depth_left)) * beta / (2.0 * e)
        if abs((c1 - af0 - gf * weight) / bf) > u_max:
            return False
        return (-v - c1 * brake_time(depth_left, c1, beta, gam)) / gf >= -(m_b * x[1] + m_f * v)
    # the fastest cruise: the speed the foot holds at REACH of the force limit (the rest of
    # it to get there), at least its own, at most the brake's from here
    w2 = (-(af0 + bf * REACH * u_max) / gf - k * d) / c_d
    w2 = min(max(w2, v * v), top)
    lo, hi = 0.0, depth_left  # the brake's length from that speed
    for _ in range(BISECT):
        s = 0.5 * (lo + hi)
        if brake_speed2(s, c1e, beta, gam) < w2:
            lo = s
        else:
            hi = s
    s, w = 0.5 * (lo + hi), math.sqrt(w2)
    j = c_d * w * (depth_left - s) - k * (depth_left * depth_left - s * s) / (2.0 * w) \
        + (w - c1e * brake_time(s, c1e, beta, gam)) / gf
    return j >= -(m_b * x[1] + m_f * v)


__all__ = ["BISECT", "BRAKE", "GAIN", "REACH", "GL_W", "GL_X", "brake_speed2", "brake_time",
           "creep_force", "creep_reachable"]
