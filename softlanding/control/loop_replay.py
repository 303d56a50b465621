"""A landing's compiled controller samples replayed as a robot's control loop runs them.

In :func:`~softlanding.control.mpc_landing` the plant's simulation, the sensors and the
bookkeeping run in the same process as the controller, between its samples: every sample
then starts with the controller's code and data evicted from the CPU's caches, which a
robot's control loop (read the sensors, compute, write the command, wait for the next
period) does not do to itself. Measured (2026-11-26, noise 1e-3, filtered estimate): the
same compiled sample 15.9 us median in the landing, 5.6 us repeated warm. The landing's
step times keep that cost (they are what the simulation measured); :func:`replay` measures
the controller as a control loop: the landing's recorded inputs, in order, from the
landing's initial memory, one sample per period of the rig (idle in between, as the loop
waiting for its sensors), nothing else in the loop; each sample's status and memory are
checked identical to the landing's to the last bit (the controller's and the foot filter's
memory byte for byte, the status and the recovery's count; :class:`ReplayMismatch`
otherwise), so the timed work is the landing's own.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control.recovery import filtered_sample
from softlanding.errors import SoftlandingError


class ReplayMismatch(SoftlandingError):
    """A replayed sample did not give the landing's status and memory (the replay would
    time another computation)."""


@dataclass(frozen=True)
class CompiledSample:
    """One compiled sample of a landing: its inputs and what it gave.

    Attributes
    ----------
    x : array of 4
        The measured state, before the foot filter's step.
    a_f, u, h : float
        The foot's measured acceleration, the force the sample ended under, its length.
    estimate : bool
        The sample updated the estimate.
    filtered : tuple of 6 floats, or None
        With the filtered estimate, the foot filter's inputs ``g, U1, U2, beta, noise`` and
        the foot's stop speed (:func:`~softlanding.control.recovery.filtered_sample`).
    status : int
        The sample's status.
    memory : array
        The controller's memory ``M`` after it.
    filter_memory : array or None
        The foot filter's memory ``F`` after it (the filtered estimate).
    recovering : int
        The recovery's count after it (the filtered estimate; 0 otherwise).
    """

    x: np.ndarray
    a_f: float
    u: float
    h: float
    estimate: bool
    filtered: tuple[float, float, float, float, float, float] | None
    status: int
    memory: np.ndarray
    filter_memory: np.ndarray | None = None
    recovering: int = 0


@dataclass
class CompiledRecord:
    """A landing's compiled samples and the controller's arrays at its impact.

    Attributes
    ----------
    P, M : array
        The controller's numbers and memory at the impact.
    F : array or None
        The foot filter's memory at the impact (the filtered estimate only).
    samples : list of CompiledSample
        In order.
    """

    P: np.ndarray
    M: np.ndarray
    F: np.ndarray | None
    samples: list[CompiledSample] = field(default_factory=list)


def replay(record: CompiledRecord, pace_s: float = 0.0) -> tuple[list[float], list[float]]:
    """The recorded samples run again as a control loop; each sample's wall and CPU time
    (ms).

    Parameters
    ----------
    record : CompiledRecord
        A landing's (:attr:`~softlanding.control.MPCLanding.compiled`).
    pace_s : float
        Seconds of wall time from one sample's start to the next (the rig's period: the
        loop sleeps until then); 0: back to back.

    Raises
    ------
    ReplayMismatch
        A sample's status or memory differs from the landing's.
    """
    P, M = record.P.copy(), record.M.copy()
    F = None if record.F is None else record.F.copy()
    K, W = bb.workspace()
    xs = [s.x.copy() for s in record.samples]  # (allocated before the loop)
    wall: list[float] = []
    cpu: list[float] = []
    recovering = 0
    deadline = time.perf_counter()
    for i, (s, x) in enumerate(zip(record.samples, xs, strict=True)):
        if pace_s > 0.0:  # the loop waits for its next sample
            deadline += pace_s
            wait = deadline - time.perf_counter()
            if wait > 0.0:
                time.sleep(wait)
        if F is None:
            c0, t0 = time.process_time(), time.perf_counter()
            st = bb.control_step(P, M, x, s.a_f, s.u, s.h, s.estimate, K, W)
            t1, c1 = time.perf_counter(), time.process_time()
        else:
            g, u1, u2, beta, noise, stop = s.filtered  # type: ignore[misc]
            c0, t0 = time.process_time(), time.perf_counter()
            st, recovering = filtered_sample(P, M, F, x, g, u1, u2, s.h, beta, noise, s.a_f,
                                             s.u, s.estimate, stop, recovering, K, W)
            t1, c1 = time.perf_counter(), time.process_time()
        wall.append(1e3 * (t1 - t0))
        cpu.append(1e3 * (c1 - c0))
        # (bytes: -0.0 is not 0.0, a NaN's payload counts)
        same = int(st) == s.status and M.tobytes() == s.memory.tobytes() and (
            F is None or (s.filter_memory is not None and F.tobytes() == s.filter_memory.tobytes()
                          and recovering == s.recovering))
        if not same:
            raise ReplayMismatch(f"sample {i} of the replay gave status {int(st)} and a memory "
                                 f"other than the landing's (status {s.status})")
    return wall, cpu


__all__ = ["CompiledRecord", "CompiledSample", "ReplayMismatch", "replay"]
