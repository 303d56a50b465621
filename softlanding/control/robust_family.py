"""The robust schedule's family and what each of its points measures, made smooth.

A point is the pieces of a force schedule: durations ``d_1..d_n`` and forces ``u_1..u_{n-1}``;
the last piece's force stops the body at its end (then the body's weight holds). Each point is
replayed on every ground by the exact simulator. Two measures of a replay are not smooth
functions of the pieces, and an epigraph search (``min z`` s.t. ``depth_k <= z``) that meets
them stalls (SLSQP zigzags, a KKT check by finite differences fails); both are lifted here:

* **A limit over time.** ``0 <= x_b - x_f <= s`` throughout is a limit on the smallest and
  largest stroke, the minimum (maximum) of several local extrema; where two of them reach the
  limit together (the stroke touching 0 twice on a stiff ground, once in flight and once at
  the body's arrest), their minimum has a kink. Each of the :data:`SLOTS` lowest local minima
  (zeros of ``v_b - v_f``, located on the exact solution) is a row of its own: the same
  feasible set, smooth rows (:func:`stroke_slots`).
* **A foot that stops at a switch.** Ended a little earlier, a piece leaves the foot still
  moving when the next force comes: it digs on to that force's equilibrium plus the amplitude
  of its remaining motion (a cone in the pieces); ended a little later, the foot stops under
  the pull and lifts off. The clairvoyant optimum sits there (its pull ends when the foot
  stops, the arrest force at the crater's capacity), and so does a robust optimum whose
  binding ground does the same. With a :class:`Pin` the piece ends when that ground's foot
  first stops (its duration is a function of the other pieces, found by the exact simulator),
  the ground's depth is the depth at that stop, and the crater's capacity against every later
  force is a row of its own (``support <= capacity``, ``support >= 0``): smooth again.

An unpinned family is the search for the structure (which ground binds, where its foot
stops): its depths have kinks anyway, so its stroke rows are the simulator's global extrema
(no extrema located: cheaper; from the nominal plan at ``v0 = -10`` on the study's grounds it
also ends nearer the optimum than with the split rows, 13.94 against 14.27). Its path is
sensitive: the same rows without the repeated slots ended at 13.95, where the pinned search
did not converge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softlanding.model.controllers import ForceSchedule
from softlanding.model.ground import Ground
from softlanding.model.robot import Impact, Robot
from softlanding.optimal.limits import force_limit
from softlanding.optimal.stance_phases import crater_capacity, support_force
from softlanding.simulation import kernel as K
from softlanding.simulation.on_grounds import simulate_on_grounds
from softlanding.simulation.simulator import LandingResult, simulate

SLOTS = 2
"""Local extrema of the stroke kept as rows per ground and limit (the lowest minima, the
highest maxima)."""
NEAR = 0.05
"""The stroke's local extrema are located on a ground whose stroke comes within this fraction
of ``s`` of a limit (elsewhere the simulator's global extrema, far from the limit, stand for
every slot)."""
ROOT_ITERATIONS = 40
"""Iterations of the Illinois root search of ``v_b - v_f = 0`` on the exact solution."""


@dataclass(frozen=True)
class Pin:
    """Piece ``piece`` (0-based) ends when the foot on ground ``ground`` (an index into the
    grounds) first stops.

    Parameters
    ----------
    piece : int
        The pinned piece.
    ground : int
        The ground whose foot's stop ends it.
    """

    piece: int
    ground: int


@dataclass(frozen=True)
class Point:
    """A resolved point of the family.

    Parameters
    ----------
    d : ndarray
        Every duration.
    u : ndarray
        The forces but the last.
    u_last : float
        The last piece's force (the body stops at its end).
    stop : ndarray or None
        The pinned ground's state at its foot's stop (None without a pin).
    held : LandingResult or None
        The pinned ground's replay until its stop.
    """

    d: np.ndarray
    u: np.ndarray
    u_last: float
    stop: np.ndarray | None
    held: LandingResult | None = None  # the pinned ground's replay until its stop


class PieceFamily:
    """The schedules of ``n`` pieces, one piece's end optionally pinned to a foot's stop.

    ``theta`` is the durations (the pinned one left out), then the forces ``u_1..u_{n-1}``.

    Parameters
    ----------
    robot, impact : Robot, Impact
        The landing.
    grounds : tuple of Ground
        The grounds.
    n : int
        Pieces (>= 2).
    pin : Pin, optional
        The piece whose end is a foot's stop (not the last one: it ends at the body's stop).
    """

    def __init__(self, robot: Robot, impact: Impact, grounds: tuple[Ground, ...], n: int,
                 pin: Pin | None = None) -> None:
        if pin is not None and not 0 <= pin.piece <= n - 2:
            raise ValueError(f"pin {pin}: the pinned piece must be one of 0..{n - 2}")
        self.robot, self.impact, self.grounds, self.n, self.pin = robot, impact, grounds, n, pin
        self.gain = (1 + robot.r_m) / robot.r_m  # body acceleration per unit force
        self.u_max = force_limit(robot)
        self.n_free = n - (pin is not None)  # free durations

    def theta(self, d: np.ndarray, u: np.ndarray) -> np.ndarray:
        """The family's coordinates of the pieces.

        Parameters
        ----------
        d, u : ndarray
            Durations and forces (without the last).
        """
        d = np.asarray(d, float)
        free = np.delete(d, self.pin.piece) if self.pin is not None else d
        return np.concatenate([free, np.asarray(u, float)[:self.n - 1]])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of ``theta``."""
        k = self.n_free
        return (np.concatenate([np.full(k, 1e-6), np.full(self.n - 1, -self.u_max)]),
                np.concatenate([np.full(k, np.inf), np.full(self.n - 1, self.u_max)]))

    def last_force(self, d: np.ndarray, u: np.ndarray) -> float:
        """The force of the last piece that brings ``v_b`` to zero at its end.

        Parameters
        ----------
        d, u : ndarray
            Durations and forces (without the last).
        """
        v = self.impact.v0 + float(np.sum((-1 + self.gain * u) * d[:-1]))
        return (1 - v / d[-1]) / self.gain

    def resolve(self, theta: np.ndarray) -> Point | None:
        """Every duration and force of ``theta`` (projected onto the bounds), or None where
        the pinned foot stops before its piece starts (no such schedule).

        Parameters
        ----------
        theta : ndarray
            The family's coordinates.
        """
        theta = np.asarray(theta, float)
        d = np.maximum(theta[:self.n_free], 1e-9)
        u = np.clip(theta[self.n_free:], -self.u_max, self.u_max)
        stop = None
        if self.pin is not None:
            found = self.first_stop(d, u)
            if found is None:
                return None
            held, stop = found
            d = np.insert(d, self.pin.piece,
                          held.t_first_stop - float(np.sum(d[:self.pin.piece])))
            return Point(d, u, self.last_force(d, u), stop, held)
        return Point(d, u, self.last_force(d, u), stop)

    def first_stop(self, d: np.ndarray, u: np.ndarray) -> tuple[LandingResult, np.ndarray] | None:
        """The pinned ground's first stop under the pieces before the pin, the pinned piece's
        force held: the replay and the state at the stop (None if it stops before the pinned
        piece).

        Parameters
        ----------
        d, u : ndarray
            Durations (without the pinned one) and forces.
        """
        pin = self.pin
        assert pin is not None  # (a pinned family's)
        j = pin.piece
        t0 = float(np.sum(d[:j]))
        held = ForceSchedule(tuple(np.cumsum(d[:j])), tuple(u[:j + 1]))
        r = simulate(self.robot, self.impact, held, self.grounds[pin.ground],
                     energy=False, max_segments=j + 8)
        if not (math.isfinite(r.t_first_stop) and r.t_first_stop > t0):
            return None
        seg = r.segments
        at = np.flatnonzero(seg["t"] == r.t_first_stop)
        if len(at):
            x = np.asarray(seg["z"][at[0]][:4], float)
        else:  # not a segment start: the exact solution there
            sampler = K.sample_segments_nl if "law" in seg else K.sample_segments
            x = sampler(seg, np.array([r.t_first_stop]))[0][0, :4]
        return r, x

    def schedule(self, p: Point) -> ForceSchedule:
        """The force schedule of a resolved point (then the body's weight).

        Parameters
        ----------
        p : Point
            The point.
        """
        values = [*map(float, p.u), p.u_last, self.robot.r_m / (1 + self.robot.r_m)]
        return ForceSchedule(tuple(np.cumsum(p.d)), tuple(values))

    def later_forces(self, p: Point) -> list[float]:
        """The forces after the pinned piece: the pinned ground's foot must rest under each.

        Parameters
        ----------
        p : Point
            A point of the pinned family.
        """
        assert self.pin is not None  # (a pinned family's)
        j = self.pin.piece
        return [*map(float, p.u[j + 1:]), p.u_last, self.robot.r_m / (1 + self.robot.r_m)]


def stroke_extrema(r: LandingResult, t_end: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """The local minima and maxima of the stroke ``x_b - x_f`` over a replay: the zeros of
    ``v_b - v_f`` (sign changes on 12 samples per segment, then Illinois on the exact
    solution).

    Parameters
    ----------
    r : LandingResult
        A replay.
    t_end : float
        Only the extrema before this time.
    """
    seg = r.segments
    sampler = K.sample_segments_nl if "law" in seg else K.sample_segments
    ts = np.asarray(seg["t"], float)
    if t_end < ts[-1]:
        ts = np.r_[ts[ts < t_end], t_end]
    grid = np.unique(np.concatenate([np.linspace(a, b, 12) for a, b in zip(ts[:-1], ts[1:],
                                                                             strict=True)]))
    if not t_end < ts[-1]:
        # the replay's end: at rest ``v_b - v_f`` is zero there to rounding, whose sign would
        # make a minimum come and go with a change of 1e-13 in the schedule (a row that jumps);
        # the end's stroke is a row of its own (:func:`stroke_slots`)
        grid = grid[:-1]

    def rate(t: np.ndarray) -> np.ndarray:
        order = np.argsort(t)
        z = sampler(seg, t[order])[0]
        out = np.empty(len(t))
        out[order] = z[:, 1] - z[:, 3]
        return out

    w = rate(grid)
    i = np.flatnonzero(np.sign(w[:-1]) * np.sign(w[1:]) < 0)
    a, b, fa, fb = grid[i], grid[i + 1], w[i], w[i + 1]
    rising = fa < 0  # v_b - v_f from - to +: a minimum of the stroke
    side = np.zeros(len(a))
    for _ in range(ROOT_ITERATIONS):
        if not len(a) or np.all(b - a <= 4e-16 * np.maximum(1.0, np.abs(b))):
            break
        c = np.clip((a * fb - b * fa) / (fb - fa), a, b)
        fc = rate(c)
        right = np.sign(fc) == np.sign(fa)  # the root is in [c, b]
        fb = np.where(right & (side == 1), fb / 2, fb)  # Illinois: halve the stale end
        fa = np.where(~right & (side == -1), fa / 2, fa)
        a, fa = np.where(right, c, a), np.where(right, fc, fa)
        b, fb = np.where(right, b, c), np.where(right, fb, fc)
        side = np.where(right, 1, -1)
        a, b = np.where(fc == 0, c, a), np.where(fc == 0, c, b)
    t = np.where(np.abs(fa) < np.abs(fb), a, b)
    order = np.argsort(t)
    z = sampler(seg, t[order])[0]
    value = np.empty(len(t))
    value[order] = z[:, 0] - z[:, 2]
    return value[rising], value[~rising]


def _lowest(values: np.ndarray, bound: float) -> list[float]:
    """The :data:`SLOTS` lowest of ``values`` in their order; the lowest never above ``bound``
    (the simulator's own extremum, which also sees the impact and the rest's future)."""
    if not len(values):
        return [bound] * SLOTS
    keep = np.sort(np.argsort(values, kind="stable")[:SLOTS])
    slots = [float(v) for v in values[keep]]
    low = int(np.argmin(slots))
    slots[low] = min(slots[low], bound)
    return slots + [slots[low]] * (SLOTS - len(slots))


def stroke_slots(r: LandingResult) -> tuple[list[float], list[float]]:
    """The rows of the stroke limits of a replay: the :data:`SLOTS` lowest local minima of
    the stroke and the :data:`SLOTS` highest maxima (the global ones where the stroke stays
    :data:`NEAR` away from both limits).

    Parameters
    ----------
    r : LandingResult
        A replay whose rest is proven.
    """
    s = r.robot.s
    if r.stroke_min >= NEAR * s and r.stroke_max <= (1 - NEAR) * s:
        return [r.stroke_min] * SLOTS, [r.stroke_max] * SLOTS
    minima, maxima = stroke_extrema(r)
    end = final_stroke(r)  # at rest the stroke stays there: a minimum and a maximum
    minima, maxima = np.r_[minima, end], np.r_[maxima, end]
    return _lowest(minima, r.stroke_min), [-v for v in _lowest(-maxima, -r.stroke_max)]


def final_stroke(r: LandingResult) -> float:
    """The stroke ``x_b - x_f`` where a replay ends (at its rest).

    Parameters
    ----------
    r : LandingResult
        A replay.
    """
    seg = r.segments
    sampler = K.sample_segments_nl if "law" in seg else K.sample_segments
    z = sampler(seg, np.array([float(seg["t"][-1])]))[0][0]
    return float(z[0] - z[2])


def body_extrema(family: PieceFamily, p: Point) -> tuple[list[float], list[float]]:
    """The local minima and maxima of the body's height after the pinned stop (the body's
    motion holds no ground: ``x_b'' = -1 + (1 + r_m)/r_m u``, piece by piece in closed form),
    the final rest included."""
    assert p.stop is not None and family.pin is not None  # (a pinned family's point)
    x, v = float(p.stop[0]), float(p.stop[1])
    j = family.pin.piece
    forces = [*map(float, p.u[j + 1:]), p.u_last]
    minima: list[float] = []
    maxima: list[float] = []
    last = len(forces) - 1
    for i, (dur, f) in enumerate(zip(p.d[j + 1:], forces, strict=True)):
        a = -1 + family.gain * f
        t = -v / a if a != 0 else math.nan
        # v_b changes sign inside the piece (the last piece's zero is its end: the rest)
        if i < last and 0 < t < dur:
            (minima if a > 0 else maxima).append(x + v * t / 2)
        x, v = x + v * dur + a * dur * dur / 2, v + a * dur
    # the body rests at the last piece's end (v_b = 0 by construction)
    (minima if forces[-1] * family.gain - 1 > 0 else maxima).append(x)
    return minima, maxima


def pinned_stroke_slots(family: PieceFamily, p: Point) -> tuple[list[float], list[float]]:
    """The stroke rows of the pinned ground as the family poses it: its replay until its
    foot's stop, then the foot at rest there while the body moves on (the crater's capacity
    is a row of its own, so a force beyond it does not make these rows jump)."""
    held = p.held
    assert held is not None and p.stop is not None  # (a pinned family's point)
    t_stop = held.t_first_stop
    minima, maxima = stroke_extrema(held, t_stop)
    after_min, after_max = body_extrema(family, p)
    foot = float(p.stop[2])
    ends = [family.robot.rest_length,
            float(p.stop[0]) - foot]  # at the impact and at the stop
    low = np.r_[minima, np.asarray(after_min) - foot]
    high = np.r_[maxima, np.asarray(after_max) - foot]
    return (_lowest(low, min(ends + list(low))),
            [-v for v in _lowest(-high, -max(ends + list(high)))])


class Measures:
    """The rows of the epigraph problem at each point of a family, cached: per ground its
    depth, :data:`SLOTS` stroke minima and maxima (unpinned: the global ones, repeated); the
    last force's margin; with a pin, per later force the crater's capacity and the ground's
    no-pull margins at the pinned stop.

    Parameters
    ----------
    family : PieceFamily
        The family.
    """

    def __init__(self, family: PieceFamily) -> None:
        self.family = family
        self.cache: dict[bytes, np.ndarray] = {}
        self.holds: dict[bytes, bool] = {}  # every ground's replay holds every limit
        self.replayed: dict[bytes, float] = {}  # the worst depth of the replays
        self.slots = SLOTS
        self.per_ground = 1 + 2 * self.slots
        g = len(family.grounds)
        self.n_pin = 0 if family.pin is None else family.n - family.pin.piece
        self.size = self.per_ground * g + 1 + 2 * self.n_pin

    def names(self) -> list[tuple[str, int | None]]:
        """Each row's kind and ground (None: not a ground's)."""
        rows: list[tuple[str, int | None]] = []
        for k in range(len(self.family.grounds)):
            rows += ([("depth", k)] + [("stroke >= 0", k)] * self.slots
                     + [("stroke <= s", k)] * self.slots)
        rows.append(("last force <= u_max", None))
        pinned = None if self.family.pin is None else self.family.pin.ground
        rows += [("crater holds the support", pinned)] * self.n_pin
        rows += [("support >= 0", pinned)] * self.n_pin
        return rows

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        key = np.asarray(theta, float).tobytes()
        if key not in self.cache:
            self.cache[key], self.holds[key], self.replayed[key] = self._measure(
                np.asarray(theta, float))
        return self.cache[key]

    def nowhere(self, u_margin: float) -> np.ndarray:
        """The rows of a point with no landing (infinite depth, every limit broken).

        Parameters
        ----------
        u_margin : float
            The last force's margin row.
        """
        s = self.family.robot.s
        ground = [math.inf] + [-s] * (2 * self.slots)
        return np.array(ground * len(self.family.grounds) + [u_margin]
                        + [-s] * (2 * self.n_pin))

    def _measure(self, theta: np.ndarray) -> tuple[np.ndarray, bool, float]:
        """The rows, whether the replays hold every limit (and the pinned foot rests where
        pinned, to rounding), the worst replayed depth."""
        fam = self.family
        if not np.all(np.isfinite(theta)):
            return self.nowhere(-fam.u_max), False, math.inf
        p = fam.resolve(theta)
        if p is None:
            return self.nowhere(-fam.u_max), False, math.inf
        margin = fam.u_max - abs(p.u_last)
        times = np.cumsum(p.d)
        if not margin >= 0 or not np.all(np.diff(np.r_[0.0, times]) > 0.0):
            # the actuator cannot stop the body in time; or a search step far out (durations
            # of 1e11 swallow one of 1e-6: the pieces' times are no schedule)
            return (self.nowhere(min(margin, 0.0) if math.isfinite(margin) else -fam.u_max),
                    False, math.inf)
        sched = fam.schedule(p)
        rows: list[float] = []
        holds, replayed = True, -math.inf
        replays = simulate_on_grounds(fam.robot, fam.impact, sched, fam.grounds)
        for k, r in enumerate(replays):
            holds = holds and r.stroke_held and r.rest_proven
            replayed = max(replayed, r.depth)
            if not (r.rest_proven and math.isfinite(r.stroke_min)
                    and math.isfinite(r.stroke_max)):
                rows += [math.inf] + [-fam.robot.s] * (2 * self.slots)
                continue
            pinned = fam.pin is not None and fam.pin.ground == k
            if pinned:
                low, high = pinned_stroke_slots(fam, p)
            elif fam.pin is not None:
                low, high = stroke_slots(r)
            else:  # the structure search: the global extrema (its depths have kinks anyway)
                low, high = [r.stroke_min] * SLOTS, [r.stroke_max] * SLOTS
            rows += [-float(p.stop[2]) if pinned else r.depth, *low,  # type: ignore[index]
                     *[fam.robot.s - v for v in high]]
        rows.append(margin)
        if fam.pin is not None:
            g, r_m = fam.grounds[fam.pin.ground], fam.robot.r_m
            support = [float(support_force(p.stop, f, r_m)) for f in fam.later_forces(p)]
            capacity = float(crater_capacity(p.stop, g))
            loads = [capacity - f for f in support] + support
            rows += loads
            holds = holds and min(loads) >= -K.FEAS_TOL * max(1.0, capacity)
        return np.array(rows), holds, replayed


__all__ = ["NEAR", "SLOTS", "Measures", "PieceFamily", "Pin", "Point", "stroke_extrema",
           "stroke_slots"]
