"""The samples of creep landings as ``mpc_landing`` lands them, recorded for the exported C's
comparison: the landings whose optimum creeps to the static depth, where the compiled
controller hands over to the creep law (:mod:`softlanding.control.creep`, status
``creep law``) for most of the landing.

Each landing of :data:`CREEP_LANDINGS` runs through
:func:`~softlanding.control.mpc.mpc_landing` with ``controller="bangbang"`` (the creep law
on, ``P_CREEP = 1``); its compiled samples (:attr:`~softlanding.control.MPCLanding.compiled`)
are run again in order from its impact memory, as
:func:`~softlanding.control.loop_replay.replay` does, and every sample's inputs recorded:
``P`` and ``M`` before it, and, with the filtered estimate, the foot filter's memory and the
filtered state after the sample's filter step (the inputs of
:func:`~softlanding.control.recovery.sample_weight` and
:func:`~softlanding.control.recovery.filtered_step`, which the C's ``sl_filtered_weight`` and
``sl_filtered_step`` mirror).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from softlanding.control import bangbang as bb
from softlanding.control import foot_filter as ff
from softlanding.control.export_c.filter_check import StepCall
from softlanding.control.export_c.samples import Call
from softlanding.control.mpc import mpc_landing
from softlanding.control.recovery import filtered_step, sample_weight
from softlanding.model.ground import DragGround
from softlanding.model.robot import Robot

#: The creep landings: ``(v0, c_d, K, noise, delay)`` of ``mpc_landing(v0, robot,
#: DragGround(c_d, K), controller="bangbang", noise=noise, delay=delay)``: exact sensing on
#: the unknown-ground study's creep at ``K = 1.5``, ``c_d = 1``, and noisy filtered sensing
#: (one sample's delay) on its ``K = 0.5``, ``c_d = 0.2``.
CREEP_LANDINGS = ((-1.0, 1.0, 1.5, 0.0, 0), (-1.0, 0.2, 0.5, 1e-3, 1))


@dataclass
class CreepCalls:
    """The recorded samples of the creep landings.

    Attributes
    ----------
    exact : list of Call
        The samples of the exactly sensed landings
        (:func:`~softlanding.control.bangbang.control_step`).
    filtered : list of StepCall
        The samples of the filtered ones.
    landings : int
        How many landings they make.
    """

    exact: list[Call] = field(default_factory=list)
    filtered: list[StepCall] = field(default_factory=list)
    landings: int = 0


def creep_calls(robot: Robot,
                landings: tuple[tuple[float, float, float, float, int], ...] = CREEP_LANDINGS
                ) -> CreepCalls:
    """The samples of the creep ``landings`` of ``robot``.

    Parameters
    ----------
    robot : Robot
        With a force limit.
    landings : tuple of (v0, c_d, K, noise, delay)
        As :data:`CREEP_LANDINGS` (the default).

    Raises
    ------
    RuntimeError
        A sample run again does not give the landing's status (the record and the compiled
        controller disagree: a bug).
    """
    out = CreepCalls()
    ws = bb.workspace()
    for v0, c_d, k, noise, delay in landings:
        record = mpc_landing(v0, robot, DragGround(c_d, k), controller="bangbang",
                             noise=noise, delay=delay).compiled
        if record is None or not record.samples:
            continue
        out.landings += 1
        P, M = record.P.copy(), record.M.copy()
        F = None if record.F is None else record.F.copy()
        recovering = 0
        for s in record.samples:
            x = s.x.copy()
            if F is None:
                out.exact.append(Call(P.copy(), M.copy(), x.copy(), s.a_f, s.u, s.h, False,
                                      s.estimate))
                st = int(bb.control_step(P, M, x, s.a_f, s.u, s.h, s.estimate, *ws))
            else:  # (recovery.filtered_sample: the filter's step, then the filtered sample)
                g, u1, u2, beta, fnoise, stop = s.filtered  # type: ignore[misc]
                ff.filter_step(F, x, g, u1, u2, s.h, beta, fnoise)
                x[3] = min(x[3], -stop)
                out.filtered.append(StepCall(P.copy(), M.copy(), F.copy(), x.copy(), s.a_f,
                                             s.u, s.h, s.estimate, recovering))
                weight = sample_weight(P, M, F, x, s.a_f, s.u) if s.estimate else 1.0
                st, recovering = filtered_step(P, M, x, s.a_f, s.u, s.h, s.estimate, weight,
                                               recovering, *ws)
            if int(st) != s.status:
                raise RuntimeError(f"a creep landing's sample gave status {int(st)}, its "
                                   f"record {s.status}")
    return out


def creep_law_samples(statuses: dict[str, int]) -> int:
    """How many samples of ``statuses`` (name -> count) the creep law covered.

    Parameters
    ----------
    statuses : dict
        Status name -> count.
    """
    return statuses.get(bb.STATUS_NAMES[bb.CREEP_LAW], 0)


__all__ = ["CREEP_LANDINGS", "CreepCalls", "creep_calls", "creep_law_samples"]
