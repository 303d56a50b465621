"""Pre-impact leg extension as multi-phase OCPs (public :mod:`ocp` API only).

**This changes the paper's initial condition.** The paper fixes the state at
impact to ``[l0, v0, 0, v0]`` with ``l0 = s/2`` and notes (Section III,
footnote) that extending the leg before impact should reduce the depth further.
Two ways to pose that:

* ``mode="impact"`` (the footnote's question): the state at touchdown is
  ``[l, v_b, 0, v_f]`` with the leg length ``l = x_b(0) - x_f(0)`` a decision in
  ``[l_min, l_max]`` (default the whole stroke ``[0, s]``) and, if wanted, the
  relative velocity ``w = v_b(0) - v_f(0)`` in ``[w_min, w_max]`` (default 0),
  the centre of mass arriving at ``v0`` (``m_b v_b + m_f v_f = v0``). Fixing
  ``l_min = l_max = s/2`` and ``w = 0`` is the paper's problem (and gives the
  paper's depth). Then yielding, then the static arrest (as
  :mod:`softlanding.optimal.two_phase_problem`).
* ``mode="drop"``: a flight phase first. The robot is released at rest with the
  leg at ``l0`` (default ``s/2``) and the foot at the height ``h = v0^2 / 2`` from
  which an unactuated drop hits the ground at ``v0``; the actuator is free in
  flight (``|u| <= u_max``, leg within the stroke, foot above the ground); the
  flight ends at touchdown (``x_f = 0``, foot moving down). The leg length and
  relative velocity at touchdown, and the centre of mass's impact velocity, are
  whatever the flight makes of them.

Objective in both: the final depth.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting
from softlanding.optimal.stance_phases import (
    ABOVE_SURFACE,
    ARREST_MAX,
    T_MAX,
    add_flight,
    add_static,
    add_yielding,
    arrest_to_rest,
    parameters,
)

MODES = ("impact", "drop")
EXTRA_PARAMETERS = ("l_min", "l_max", "w_min", "w_max")
"""Bounds of the leg length and relative velocity at impact (``mode="impact"``)."""
NODES = {"impact": (100, 40), "drop": (60, 100, 40)}
"""Shooting intervals per phase."""


def build_leg_extension_problem(mode: str = "impact") -> MultiPhaseProblem:
    """The landing with the leg's state at touchdown optimised (see the module docstring).

    Parameters
    ----------
    mode : {"impact", "drop"}
        Decide the touchdown leg state directly, or through a flight phase from a drop.
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    mp = MultiPhaseProblem(f"leg_extension_{mode}")
    par = parameters(mp)
    r_m = par["r_m"]
    mb, mf = r_m / (1 + r_m), 1 / (1 + r_m)
    phases = []
    if mode == "drop":
        fl = add_flight(mp, "flight", par)
        x = fl.x
        h = par["v0"] ** 2 / 2
        fl.path_constraint(x[2], 0, ca.inf, name=ABOVE_SURFACE)
        release: list[tuple[ca.SX, ca.SX]] = [(x[0], h + par["l0"]), (x[1], ca.SX(0)),
                                              (x[2], h), (x[3], ca.SX(0))]
        for k, (e, v) in enumerate(release):
            fl.initial_constraint(e - v, 0.0, name=f"released at rest ({k})")
        fl.terminal_constraint(x[2], 0.0, name="touchdown x_f(T) = 0")
        fl.terminal_constraint(x[3], -ca.inf, 0.0, name="foot moving down at touchdown")
        fl.free_final_time(1e-3, T_MAX, guess=1.0)
        phases.append(fl)
    y = add_yielding(mp, "yielding", par)
    if mode == "impact":
        ex = [mp.parameter(n) for n in EXTRA_PARAMETERS]
        x = y.x
        y.initial_constraint(x[0] - x[2], ex[0], ex[1], name="leg length at impact")
        y.initial_constraint(x[1] - x[3], ex[2], ex[3], name="relative velocity at impact")
        y.initial_constraint(mb * x[1] + mf * x[3] - par["v0"], 0.0,
                             name="centre of mass arrives at v0")
        y.initial_constraint(x[2], 0.0, name="x_f(0) = 0")
        y.free_final_time(1e-3, T_MAX, guess=0.3)
    else:
        y.free_duration(1e-3, T_MAX, guess=0.3)
    phases.append(y)
    st = add_static(mp, "static", par)
    st.free_duration(1e-6, ARREST_MAX, guess=1.0)
    arrest_to_rest(st, par)
    phases.append(st)
    for a, b in zip(phases[:-1], phases[1:], strict=True):
        mp.link(a, b)
    mp.minimize(-st.at_tf(st.x[2]))
    return mp


def leg_extension_transcription(mode: str = "impact") -> MultipleShooting:
    """The transcribed leg-extension problem, built once per mode (expanded to SX).

    Parameters
    ----------
    mode : {"impact", "drop"}
        See :func:`build_leg_extension_problem`.
    """
    # no bound relaxation: a flight ending at the stroke limit must not overshoot it by
    # Ipopt's default 1e-8 relative relaxation (its end is propagated exactly afterwards)
    return _transcription(mode, False)


def leg_extension_transcription_inner(mode: str = "impact") -> MultipleShooting:
    """As :func:`leg_extension_transcription`, with the path constraints imposed at the
    integrator's inner steps too (a second start when the first solution dives through
    the stroke limit between the nodes and its structure cannot be refined).

    Parameters
    ----------
    mode : {"impact", "drop"}
        See :func:`build_leg_extension_problem`.
    """
    return _transcription(mode, True)


@lru_cache(maxsize=4)
def _transcription(mode: str, inner: bool) -> MultipleShooting:
    # no bound relaxation: a flight ending at the stroke limit must not overshoot it by
    # Ipopt's default 1e-8 relative relaxation (its end is propagated exactly afterwards)
    return MultipleShooting(build_leg_extension_problem(mode), nodes=list(NODES[mode]),
                            integrator="rk4", substeps=4, expand=True,
                            ipopt_options={"bound_relax_factor": 0.0},
                            inner_constraints=inner)


__all__ = ["EXTRA_PARAMETERS", "MODES", "NODES", "build_leg_extension_problem",
           "leg_extension_transcription", "leg_extension_transcription_inner"]
