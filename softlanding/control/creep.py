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
  foot's support at the stop ``(1 - BRAKE) h_0 >= 0`` (it rests; a harder pull lifts it),
  and the drag does the braking. Once the force that stops the foot at ``d_s`` is at most
  ``u_e`` the law applies that force (recomputed every sample); entered a sample late, it
  pulls somewhat harder (measured up to ``2.3 h_0`` from impact): the foot may then leave
  the crater at its stop and land back on it (the plant's flight and landing modes).
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
and ground with no drag (no creep: the law refuses, ``nan``). Its callers:
:mod:`softlanding.control.bangbang` (phase ``CREEPING``); measured in the guide's "The creep
law" (``docs/guides/unknown_ground_controller.md``).

The foot's and body's coefficients are the controller's numbers (from
:func:`softlanding.model.dynamics.robot_rhs`: one definition of the dynamics).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softlanding.simulation.kernel.const import ENTRY, JIT

#: The brake's force as a fraction of the foot's weight share, pulling: the foot's support at
#: its stop is ``1 - BRAKE`` of its weight (it rests on the crater).
BRAKE = 0.5
#: The fraction of the gap to the cruise speed the foot's acceleration closes per sample.
GAIN = 0.5
#: The fraction of the force limit :func:`creep_reachable`'s plan pushes at (the law's push
#: saturates at the limit; 0.8 with the push arc's impulse of the wrong sign took a bang-bang
#: landing over; measured with the sign right: 1.0 lands the creeps as well or better).
REACH = 1.0
#: Bisection steps on the brake's length (the cruise speed to ``2^-BISECT`` of the depth left).
BISECT = 40
#: Newton steps at most on the push's length.
NEWTON = 30

# 8-point Gauss-Legendre on [0, 1] (the brake's time)
_GX, _GW = np.polynomial.legendre.leggauss(8)
GL_X = 0.5 * (_GX + 1.0)
GL_W = 0.5 * _GW


@njit(**ENTRY)
def brake_speed2(sigma: float, c1: float, beta: float, gam: float) -> float:
    """``v_f^2`` from which a constant force with foot deceleration ``c1`` at the stop stops
    the foot exactly ``sigma`` further down (``beta``, ``gam``: the drag's and the spring's
    ``2 g_f c_d``, ``2 g_f K``)."""
    bc = gam / beta
    return -((bc - 2.0 * c1) / beta) * math.expm1(beta * sigma) + bc * sigma


@njit(**ENTRY)
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


@njit(**ENTRY)
def push_speed2(s: float, z0: float, c_p: float, beta: float, gam: float) -> float:
    """``v_f^2`` after the foot moved ``s`` further down under a constant force from
    ``v_f^2 = z0`` (``c_p``: its acceleration's constant part at the start,
    ``a_f0 + b_f u + g_f K d``; forward, ``dz/ds = -2 c_p - gam s - beta z``)."""
    a = (gam / beta - 2.0 * c_p) / beta
    return a - (gam / beta) * s + (z0 - a) * math.exp(-beta * s)


@njit(**ENTRY)
def push_time(s: float, z0: float, c_p: float, beta: float, gam: float) -> float:
    """The push's duration over ``s`` (``s = s_p tau^2``: a foot starting at rest too)."""
    t = 0.0
    for i in range(GL_X.size):
        tau = GL_X[i]
        z = push_speed2(s * tau * tau, z0, c_p, beta, gam)
        if z <= 0.0:
            return np.inf
        t += GL_W[i] * 2.0 * s * tau / math.sqrt(z)
    return t


@njit(**ENTRY)
def plan_impulse(sb: float, v: float, d: float, depth_left: float, k: float, c_d: float,
                 af0: float, bf: float, gf: float, u_push: float, u_max: float,
                 weight: float, c1e: float, beta: float, gam: float) -> float:
    """The ground's impulse in excess of the weight over the plan with a brake of length
    ``sb``: push (at ``u_push``; 0: none, the foot at ``w`` at once) to the brake's speed
    ``w`` if the foot is slower, cruise at ``w``, brake; ``-inf`` where the plan does not fit
    (the push and the brake longer than the depth left, a speed the push does not reach, or
    a cruise the force limit does not hold).

    Parameters
    ----------
    sb : float
        The brake's length.
    v, d : float
        The foot's velocity (< 0) and depth.
    depth_left : float
        The static depth less ``d``.
    k, c_d : float
        The ground.
    af0, bf, gf : float
        The foot's acceleration ``af0 + bf u + gf f_g``.
    u_push, u_max : float
        The push's force (0: no push arc), the force limit.
    weight : float
        The robot's weight.
    c1e, beta, gam : float
        The brake's deceleration at the stop, ``2 g_f c_d``, ``2 g_f K``.
    """
    w2 = brake_speed2(sb, c1e, beta, gam)
    if not w2 > 0.0:
        return np.inf  # (no cruise: the least speed; never the bisection's answer)
    # a cruise the force limit (the push's, else u_max) holds down to the static depth
    if w2 > (-(af0 + bf * (u_push if u_push > 0.0 else u_max)) / gf - weight) / c_d:
        return -np.inf
    w = math.sqrt(w2)
    j = 0.0
    sp = 0.0
    if w2 > v * v and u_push > 0.0:  # the push to it (none: at w at once)
        c_p = af0 + bf * u_push + gf * k * d
        # its length: Newton on z(s) = w^2 from the foot's state (z is concave where it
        # rises: the iterates rise to the root from below), at most NEWTON steps
        sp = 0.0
        z = v * v
        for _ in range(NEWTON):
            slope = -2.0 * c_p - gam * sp - beta * z
            if not slope > 0.0:  # the push no longer speeds the foot up: w out of reach
                return -np.inf
            step = (w2 - z) / slope
            sp += step
            if sp > depth_left - sb:
                return -np.inf
            z = push_speed2(sp, v * v, c_p, beta, gam)
            if abs(step) <= 1e-12 * (depth_left + sp):
                break
        # (the foot's momentum change -w - v_f less the push's force and weight over it)
        j = (-w - v - (af0 + bf * u_push + gf * weight) * push_time(sp, v * v, c_p, beta, gam)) / gf
    cruise = depth_left - sp
    j += c_d * w * (cruise - sb) - k * (cruise * cruise - sb * sb) / (2.0 * w)
    return j + (w - c1e * brake_time(sb, c1e, beta, gam)) / gf


@njit(**JIT)
def _cruise(af0, bf, gf, ab0, bb, u_max, hold0, k, c_d, x, u_push):
    """The cruise speed whose plan (push at ``u_push`` to it, cruise, brake) spends the
    momentum, the brake's speed at the depth left if none is needed
    (braking), and whether the plan reaches the static depth with the momentum spent
    (``nan, False`` where the law does not apply)."""
    v = x[3]
    if not (k > 0.0 and c_d > 0.0 and v < 0.0):
        return np.nan, False
    m_f = 1.0 / gf
    m_b = -bf / (gf * bb)
    weight = -(m_b * ab0 + m_f * af0)
    d = -x[2]
    depth_left = weight / k - d
    if depth_left <= 0.0:
        return 0.0, False
    beta, gam = 2.0 * gf * c_d, 2.0 * gf * k
    c1e = af0 - bf * BRAKE * hold0 + gf * weight
    q = -(m_b * x[1] + m_f * v)
    top = brake_speed2(depth_left, c1e, beta, gam)
    if not top > v * v:  # braking from here: does the brake spend the momentum
        e = math.expm1(beta * depth_left)
        c1 = (v * v + (gam / beta) * (e / beta - depth_left)) * beta / (2.0 * e)
        j = (-v - c1 * brake_time(depth_left, c1, beta, gam)) / gf
        return math.sqrt(top), abs((c1 - af0 - gf * weight) / bf) <= u_max and j >= q
    lo, hi = 0.0, depth_left
    for _ in range(BISECT):
        sb = 0.5 * (lo + hi)
        j = plan_impulse(sb, v, d, depth_left, k, c_d, af0, bf, gf, u_push, u_max, weight, c1e,
                     beta, gam)
        if j < q:  # (-inf: too fast, the plan does not fit)
            if j == -np.inf:
                hi = sb
            else:
                lo = sb
        else:
            hi = sb
    j = plan_impulse(hi, v, d, depth_left, k, c_d, af0, bf, gf, u_push, u_max, weight, c1e, beta,
                 gam)
    w = math.sqrt(max(brake_speed2(0.5 * (lo + hi), c1e, beta, gam), 0.0))
    return w, j >= q and math.isfinite(j)


@njit(**ENTRY)
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
    if not (k > 0.0 and c_d > 0.0 and v < 0.0 and h > 0.0 and math.isfinite(x[0])
            and math.isfinite(x[1]) and math.isfinite(x[2]) and math.isfinite(v)):
        return np.nan
    m_f = 1.0 / gf
    m_b = -bf / (gf * bb)
    weight = -(m_b * ab0 + m_f * af0)
    d = -x[2]
    depth_left = weight / k - d
    u_e = -BRAKE * hold0
    if depth_left <= 0.0:  # past the static depth: stop the foot at the brake's force
        return max(min(u_e, u_max), -u_max)
    beta, gam = 2.0 * gf * c_d, 2.0 * gf * k
    # the constant force that stops the foot exactly at the static depth
    e = math.expm1(beta * depth_left)
    c1 = (v * v + (gam / beta) * (e / beta - depth_left)) * beta / (2.0 * e)
    u_b = (c1 - af0 - gf * weight) / bf
    # braking once the brake's force is reached (entered a sample late, the force that stops
    # the foot pulls somewhat harder than u_e; measured, braking a sample early instead, or
    # never pulling beyond the foot's weight share, lands deeper: up to 32 %)
    if u_b <= u_e:
        return max(min(u_b, u_max), -u_max)
    # (the force's cruise speed counts no push: measured, a push in its plan left the body
    # 0.3-0.5 descending at the foot's stop from impact, 2 % deeper; the push arc serves
    # the decision to take over, creep_reachable)
    w, _ = _cruise(af0, bf, gf, ab0, bb, u_max, hold0, k, c_d, x, 0.0)
    a = -GAIN / h * (v + w)
    u = (a - af0 - gf * (k * d + c_d * v * v)) / bf
    return max(min(u, u_max), -u_max)


@njit(**ENTRY)
def creep_reachable(af0: float, bf: float, gf: float, ab0: float, bb: float, u_max: float,
                    hold0: float, k: float, c_d: float, x: np.ndarray) -> bool:
    """The creep law's plan (push at :data:`REACH` of the force limit to a cruise speed,
    cruise, brake) spends the robot's momentum before the static depth: the landing then
    ends at the least depth any landing can (``W / K``), and the law should take over.
    Arguments as :func:`creep_force`'s.

    A bound first (most bang-bang samples end there, no bisection): the ground's impulse
    beyond the weight is ``int (K d - W + c_d v_f^2) dt <= c_d int |v_f| dsigma <= c_d V D``
    over the depth ``D`` left, ``V`` the plan's largest foot speed (the foot's own, or the
    fastest cruise the force holds, or the brake's from here)."""
    v = x[3]
    if not (k > 0.0 and c_d > 0.0 and v < 0.0):
        return False
    m_f = 1.0 / gf
    m_b = -bf / (gf * bb)
    weight = -(m_b * ab0 + m_f * af0)
    depth_left = weight / k + x[2]
    top = min(brake_speed2(depth_left, af0 - bf * BRAKE * hold0 + gf * weight, 2.0 * gf * c_d,
                           2.0 * gf * k),
              (-(af0 + bf * REACH * u_max) / gf - weight) / c_d)
    if c_d * math.sqrt(max(top, v * v)) * depth_left < -(m_b * x[1] + m_f * v):
        return False
    return _cruise(af0, bf, gf, ab0, bb, u_max, hold0, k, c_d, x, REACH * u_max)[1]


__all__ = ["BISECT", "BRAKE", "GAIN", "GL_W", "GL_X", "NEWTON", "REACH", "brake_speed2",
           "brake_time", "creep_force", "creep_reachable", "plan_impulse", "push_speed2",
           "push_time"]
