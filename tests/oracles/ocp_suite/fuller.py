"""Fuller's problem: the optimal control chatters (infinitely many switches), then rests.

mintOC "Fuller's problem" (Sager's benchmark library, https://mintoc.de, after
A. T. Fuller, "Study of an optimum nonlinear control system", J. Electronics and
Control 15 (1963) 63-71; analysis in M. I. Zelikin and V. F. Borisov, *Theory of
Chattering Control*, Birkhaeuser 1994)::

    min int_0^1 x1^2 dt,  x1' = x2,  x2' = u,  |u| <= 1,
    x(0) = x(1) = (0.01, 0).

(mintOC writes ``x2' = 1 - 2 w`` with ``w`` in {0, 1}; its relaxation is ``u = 1 - 2 w``
in [-1, 1].) mintOC publishes 1.5296058259296967e-05, a direct discretisation
(jModelica/Optimica with Ipopt), so only to about 1e-3.

Independent value (closed form, :func:`fuller_value`): Fuller's synthesis
``u = -sign(x1 + C x2 |x2|)``, ``C = sqrt((sqrt(33) - 1) / 24) = 0.4446236...``,
drives a state to the origin in finite time with switch intervals shrinking by
``r = sqrt((1/2 - C) / (1/2 + C)) = 0.2421...`` each (chattering); the cost to
go from ``(a, 0)`` is a polynomial integral summed as a geometric series
(:func:`cost_to_origin`, degree-5 homogeneous in ``sqrt(a)``). With time to spare
(``T >= 2 T_0``), the optimum chatters into the origin, rests there on the
singular arc ``u = 0``, and chatters out, the mirror image in time (the problem
is invariant under ``t -> T - t, x2 -> -x2``): ``J* = 2 V(x0)`` = 1.5280351e-05.
The tests also recover ``C`` by minimising ``V`` over the switching-curve
constant (a check of the constant itself).

Fuller's problem is homogeneous: ``x1 -> k^2 x1, x2 -> k x2, t -> k t`` maps
solutions to solutions and multiplies the cost by ``k^5``. :func:`fuller` takes
the initial value and horizon, so the same problem posed at ``x0 = (1, 0)``
(``k = 10``: horizon 10, cost 1.5280351) is well scaled for Ipopt; at the mintOC
scale the objective (1.5e-5) sits at Ipopt's default tolerance.
"""

from __future__ import annotations

import math

from ocp import OptimalControlProblem
from tests.oracles.ocp_suite.problems import SuiteProblem

FULLER_C = math.sqrt((math.sqrt(33.0) - 1.0) / 24.0)
"""Fuller's switching-curve constant: the switching curve is ``x1 = -C x2 |x2|``."""

MINTOC_PUBLISHED = 1.5296058259296967e-05
"""mintOC's value (a discretisation; Optimica/jModelica with Ipopt)."""


def ratio(C: float = FULLER_C) -> float:
    """Ratio of consecutive switch intervals of the synthesis with constant ``C``."""
    return math.sqrt((0.5 - C) / (0.5 + C))


def cost_to_origin(a: float, C: float = FULLER_C) -> tuple[float, float]:
    """Cost ``int x1^2`` and time to reach the origin from ``(a, 0)``, ``a > 0``, under
    the synthesis ``u = -sign(x1 + C x2 |x2|)`` (closed form).

    The first arc (``u = -1``) lasts ``t1 = sqrt(a / (C + 1/2))`` and reaches the
    switching curve at ``x2 = -t1``; every later arc starts on the curve with
    speed ``y``, lasts ``(1 + r) y`` and ends on it with speed ``r y``. Along one
    such arc ``x1 = y^2 (C - s + s^2 / 2)`` in ``s = time / y``, so its cost is
    ``K y^5`` with ``K = int_0^(1+r) (C - s + s^2/2)^2 ds``.
    """
    t1 = math.sqrt(a / (C + 0.5))
    r = ratio(C)
    L = 1.0 + r
    first = a * a * t1 - a * t1**3 / 3.0 + t1**5 / 20.0
    K = C * C * L - C * L**2 + (1.0 + C) * L**3 / 3.0 - L**4 / 4.0 + L**5 / 20.0
    return first + K * t1**5 / (1.0 - r**5), t1 + t1 * L / (1.0 - r)


def fuller(x0: float = 0.01, T: float = 1.0, free_end: bool = False) -> OptimalControlProblem:
    """min int_0^T x1^2, x1' = x2, x2' = u, |u| <= 1, x(0) = (x0, 0), x(T) = (x0, 0)
    (free with ``free_end``)."""
    p = OptimalControlProblem("fuller" + ("_free_end" if free_end else ""))
    x1, x2 = p.state("x1"), p.state("x2")
    u = p.control("u", lower=-1.0, upper=1.0)
    p.set_dynamics({"x1": x2, "x2": u})
    p.initial_constraint(x1, x0)
    p.initial_constraint(x2, 0.0)
    if not free_end:
        p.terminal_constraint(x1, x0)
        p.terminal_constraint(x2, 0.0)
    p.fixed_final_time(T)
    p.minimize_integral(x1**2)
    return p


def fuller_value(x0: float = 0.01, T: float = 1.0, free_end: bool = False) -> float:
    """The optimal cost when the horizon leaves time to rest at the origin: ``2 V(x0)``
    (``V(x0)`` with a free end, where ``T >= T_0`` suffices)."""
    V, T0 = cost_to_origin(x0)
    if T < (1 if free_end else 2) * T0:
        raise ValueError(f"horizon {T} too short to reach the origin (T_0 = {T0:.6g})")
    return V if free_end else 2.0 * V


PROBLEM = SuiteProblem(
    name="fuller", source="mintOC Fuller's problem (Fuller 1963; Zelikin & Borisov 1994)",
    published=MINTOC_PUBLISHED, rtol=2e-3, build=fuller, exact=fuller_value,
    exact_rtol=3e-4, covers=("chattering", "singular arc"), bang_bang=False,
    notes="chattering into and out of a singular arc at the origin on [0.2715, 0.7285]: "
          "no finite switching structure; certify must not certify it. Radau collocation "
          "with mesh refinement (defaults): 1.52819e-05, 1.0e-4 above the closed form (the "
          "objective sits at Ipopt's tolerance at this scale)")

PROBLEM_FREE_END = SuiteProblem(
    name="fuller_free_end", source="Fuller 1963, free final state, x0 = (1, 0), T = 10",
    published=cost_to_origin(1.0)[0], rtol=1e-5,
    build=lambda: fuller(1.0, 10.0, free_end=True),
    exact=lambda: fuller_value(1.0, 10.0, free_end=True), exact_rtol=1e-5,
    covers=("chattering", "singular arc", "free end"), bang_bang=False,
    notes="published value: Fuller's cost to go V(1, 0) (closed form)")

PROBLEMS_HERE = [PROBLEM, PROBLEM_FREE_END]
