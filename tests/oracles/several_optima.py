"""Published minimum-time problems with several local optima, and their exact optima.

For :func:`ocp.multistart` (tests/ocp/search): each is posed with the public
API as a researcher would (bounds, boundary values, nothing else); each
global optimum comes from an independent computation.

* :func:`dubins_point`: Dubins' car (unit speed, turning radius 1) from the
  origin heading along +x to the point (-2, 0.5) behind it, heading free.
  The shortest paths to a point are an arc then a segment (Dubins 1957;
  Bui, Soueres, Boissonnat, Laumond 1994, "Shortest path synthesis for Dubins
  non-holonomic robot", ICRA): turning left first (LS) or right first (RS)
  gives two local optima, 5.695780 and 6.487899 in closed form
  (:func:`dubins_point_lengths`). The default guess (heading 0 throughout)
  does not converge (Ipopt reports local infeasibility).
* :func:`obstacle_min_time`: the obstacle-avoidance geometry of PROPT's and
  PSOPT's example (Becerra, PSOPT ``examples/obstacle``; from (0, 0) to
  (1.2, 1.6) in the box [0, 2]^2 around the discs of radius sqrt(0.1) at
  (0.4, 0.5) and (0.8, 1.5), speed 2.138, heading the control), posed as
  minimum time. A path passes each disc on either side, so there are several
  local optima; the global one is the shortest path around the discs (tangent
  segments and arcs, :func:`shortest_path_around_discs`) divided by the speed:
  T* = 0.997064. From the default guess (the straight line) a 40-interval
  collocation reaches T = 1.0534, 5.6 % above.
"""

from __future__ import annotations

import heapq
import math

import casadi as ca
import numpy as np

from ocp import OptimalControlProblem

DUBINS_TARGET = (-2.0, 0.5)
SPEED = 2.138
START, GOAL = (0.0, 0.0), (1.2, 1.6)
DISCS = (((0.4, 0.5), math.sqrt(0.1)), ((0.8, 1.5), math.sqrt(0.1)))


def dubins_point() -> OptimalControlProblem:
    """Dubins' car to a point behind it, minimum time, heading free at the end."""
    p = OptimalControlProblem("dubins_point")
    x, y, psi = p.state("x"), p.state("y"), p.state("psi")
    u = p.control("u", -1.0, 1.0)
    p.set_dynamics({"x": ca.cos(psi), "y": ca.sin(psi), "psi": u})
    for s in (x, y, psi):
        p.initial_constraint(s, 0.0)
    p.terminal_constraint(x, DUBINS_TARGET[0])
    p.terminal_constraint(y, DUBINS_TARGET[1])
    p.free_final_time()
    p.minimize_terminal(p.T)
    return p


def dubins_point_lengths(px: float = DUBINS_TARGET[0], py: float = DUBINS_TARGET[1]
                         ) -> tuple[float, float]:
    """Lengths of the left-first (LS) and right-first (RS) paths to ``(px, py)`` (radius 1).

    An arc on the turning circle (centre ``(0, +-1)``) until the heading points at the
    target along the circle's tangent, then the tangent segment: ``alpha + sqrt(D^2 - 1)``
    with ``D`` the target's distance from the centre.
    """
    out = []
    for side in (1.0, -1.0):  # left: counter-clockwise round (0, 1); right: clockwise
        cx, cy = px, py - side
        d = math.hypot(cx, cy)
        beta = math.atan2(cy, cx)
        leave = beta - side * math.acos(1.0 / d)  # where the tangent heads for the target
        alpha = (side * (leave - (-side * math.pi / 2))) % (2 * math.pi)
        out.append(alpha + math.sqrt(d * d - 1.0))
    return out[0], out[1]


def obstacle_min_time() -> OptimalControlProblem:
    """PSOPT's obstacle geometry as a minimum-time problem (heading ``theta`` the control)."""
    p = OptimalControlProblem("obstacle_min_time")
    x, y = p.state("x", 0.0, 2.0), p.state("y", 0.0, 2.0)
    th = p.control("theta", -math.pi, math.pi)
    p.set_dynamics({"x": SPEED * ca.cos(th), "y": SPEED * ca.sin(th)})
    for (cx, cy), r in DISCS:
        p.path_constraint((x - cx) ** 2 + (y - cy) ** 2, r * r)
    p.initial_constraint(x, START[0])
    p.initial_constraint(y, START[1])
    p.terminal_constraint(x, GOAL[0])
    p.terminal_constraint(y, GOAL[1])
    p.free_final_time()
    p.minimize_terminal(p.T)
    return p


def obstacle_exact() -> float:
    """T* = (shortest path from START to GOAL around DISCS) / SPEED (the box is not active)."""
    length, path = shortest_path_around_discs(START, GOAL, DISCS)
    assert all(0.0 <= c <= 2.0 for pt in path for c in pt)  # inside the box [0, 2]^2
    return length / SPEED


def _point_tangents(p: np.ndarray, c: np.ndarray, r: float) -> list[np.ndarray]:
    """The two points where lines from ``p`` touch the circle (centre ``c``, radius ``r``)."""
    d = c - p
    dist = math.hypot(*d)
    a, b, t = math.atan2(d[1], d[0]), math.asin(r / dist), math.sqrt(dist * dist - r * r)
    return [p + t * np.array([math.cos(a + s * b), math.sin(a + s * b)]) for s in (1, -1)]


def _bitangents(c1: np.ndarray, r1: float, c2: np.ndarray, r2: float
                ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The (up to four) segments tangent to two circles, as pairs of touching points."""
    d = c2 - c1
    dist, base = math.hypot(*d), math.atan2(d[1], d[0])
    out = []
    for s in (1, -1):  # outer (same side), inner (crossing)
        if abs(r1 - s * r2) <= dist:
            g = math.acos((r1 - s * r2) / dist)
            for k in (1, -1):
                n = np.array([math.cos(base + k * g), math.sin(base + k * g)])
                out.append((c1 + r1 * n, c2 + s * r2 * n))
    return out


def _clear(a: np.ndarray, b: np.ndarray, discs: list[tuple[np.ndarray, float]]) -> bool:
    """Whether the segment ``ab`` stays out of every disc's interior."""
    ab = b - a
    for c, r in discs:
        t = float(np.clip(np.dot(c - a, ab) / max(float(np.dot(ab, ab)), 1e-300), 0.0, 1.0))
        if math.hypot(*(a + t * ab - c)) < r - 1e-9:
            return False
    return True


def shortest_path_around_discs(start, goal, discs) -> tuple[float, list[np.ndarray]]:
    """Shortest path from ``start`` to ``goal`` outside disjoint discs (exact geometry).

    The shortest path is made of tangent segments and arcs of the discs' circles: a graph
    whose nodes are the start, the goal and every tangent point (from the start and the
    goal to each circle, and between every two circles), whose edges are the tangent
    segments that no disc blocks and both arcs between two points on one circle;
    Dijkstra's algorithm on it. Every path of the graph is a feasible curve, so its
    shortest is the shortest curve.
    """
    cs = [(np.asarray(c, dtype=float), float(r)) for c, r in discs]
    nodes: list[np.ndarray] = [np.asarray(start, float), np.asarray(goal, float)]
    circle: list[int | None] = [None, None]
    edges: dict[int, list[tuple[int, float]]] = {}

    def edge(i: int, j: int, w: float) -> None:
        edges.setdefault(i, []).append((j, w))
        edges.setdefault(j, []).append((i, w))

    def node(p: np.ndarray, k: int) -> int:
        nodes.append(p)
        circle.append(k)
        return len(nodes) - 1

    if _clear(nodes[0], nodes[1], cs):
        edge(0, 1, math.dist(nodes[0], nodes[1]))
    for k, (c, r) in enumerate(cs):
        for end in (0, 1):
            for t in _point_tangents(nodes[end], c, r):
                if _clear(nodes[end], t, cs):
                    edge(end, node(t, k), math.dist(nodes[end], t))
        for m in range(k + 1, len(cs)):
            for p1, p2 in _bitangents(c, r, *cs[m]):
                if _clear(p1, p2, cs):
                    edge(node(p1, k), node(p2, m), math.dist(p1, p2))
    for k, (c, r) in enumerate(cs):
        on = [i for i, ck in enumerate(circle) if ck == k]
        for a in on:
            for b in on:
                if a < b:
                    va, vb = nodes[a] - c, nodes[b] - c
                    ang = abs(math.atan2(va[0] * vb[1] - va[1] * vb[0], float(np.dot(va, vb))))
                    edge(a, b, r * ang)
                    edge(a, b, r * (2 * math.pi - ang))
    dist, prev, queue = {0: 0.0}, {}, [(0.0, 0)]
    while queue:
        d, i = heapq.heappop(queue)
        if d > dist.get(i, math.inf):
            continue
        for j, w in edges.get(i, []):
            if d + w < dist.get(j, math.inf):
                dist[j], prev[j] = d + w, i
                heapq.heappush(queue, (d + w, j))
    path = [1]
    while path[-1] != 0:
        path.append(prev[path[-1]])
    return dist[1], [nodes[i] for i in reversed(path)]


TWO_LINK_PUBLISHED = 2.9822
"""Luus (2000), Iterative Dynamic Programming, section 12.4.2 (PSOPT's ``twolinkarm``)."""


def two_link_arm() -> OptimalControlProblem:
    """The two-link robot arm in minimum time (Luus 2000; PSOPT ``examples/twolinkarm``):
    torques ``|u| <= 1``, states in [-2, 2], from rest at (0.5, 0) to rest at (0.5, 0.522).
    The default guess reaches the published optimum; another local optimum lies at 3.2085
    (seen by multistart's starts): the case where early stopping saves starts."""
    p = OptimalControlProblem("two_link_arm")
    x1, x2, x3, x4 = (p.state(n, -2.0, 2.0) for n in ("x1", "x2", "x3", "x4"))
    u1, u2 = p.control("u1", -1.0, 1.0), p.control("u2", -1.0, 1.0)
    s, c = ca.sin(x3), ca.cos(x3)
    den = 31 / 36 + 9 / 4 * s**2
    n1 = s * (9 / 4 * c * x1**2 + 2 * x2**2) + 4 / 3 * (u1 - u2) - 3 / 2 * c * u2
    n2 = -(s * (7 / 2 * x1**2 + 9 / 4 * c * x2**2) - 7 / 3 * u2 + 3 / 2 * c * (u1 - u2))
    p.set_dynamics({"x1": n1 / den, "x2": n2 / den, "x3": x2 - x1, "x4": x1})
    for x, a, b in ((x1, 0.0, 0.0), (x2, 0.0, 0.0), (x3, 0.5, 0.5), (x4, 0.0, 0.522)):
        p.initial_constraint(x, a)
        p.terminal_constraint(x, b)
    p.free_final_time(1.0, 10.0)
    p.minimize_terminal(p.T)
    return p


def dubins_transcription():
    """A 16-interval collocation of :func:`dubins_point` (a module-level builder: picklable)."""
    from ocp import Collocation

    return Collocation(dubins_point(), intervals=16)
