"""A landing variant in one module: the smallest peak force that lands within a depth budget.

An actuator's size is set by its peak force. Given a budget ``depth_max`` for the final
depth, what is the smallest ``max |u|`` that still lands within it? The problem is the
two-phase landing (yielding, then static stance until the body rests; see
:mod:`softlanding.optimal.two_phase_problem`) in epigraph form: a decision variable
``peak``, ``-peak <= u <= peak`` in both phases, ``peak`` minimised, the final depth at
most ``depth_max``. Where the budget binds (``budget_active``: the landing reaches
``depth_max``), its answer ``P`` is the force limit at which the two-phase landing's least
depth is exactly ``depth_max``. A budget beyond the depth of the landing with the least peak
that lands at all (it stops the body within the stroke on a crater that holds) is slack:
``P`` is that least peak whatever the budget, and the two-phase landing with ``u_max = P``
lands shallower than ``depth_max``.

This module is the whole variant, written against public names only: the problem, the
result (its own table rows and JSON fields), the hooks that
:func:`softlanding.optimal.solve_phased` runs (a transcription started from the two-phase
landing, the switches refined with exact arcs where the arcs allow, the schedule replayed
in the exact simulator), and :data:`VARIANT`, which gives the command line its name and
option: ``softlanding solve --variant min-peak-force --v0 -3 --depth-max 2``. A copy
outside the package runs as ``--variant mymodule:VARIANT``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting
from softlanding.errors import ParameterError
from softlanding.model import LINEAR_GROUND, PAPER_ROBOT, Ground, Impact, Robot
from softlanding.optimal import (
    Option,
    PhasedVariant,
    TwoPhase,
    TwoPhaseLanding,
    Variant,
    phase_guess,
    solve_phased,
    solve_two_phase,
)
from softlanding.optimal.stance_phases import (
    ARREST_MAX,
    T_MAX,
    add_static,
    add_yielding,
    arrest_to_rest,
    impact_state,
    parameters,
)

BUDGET_CAP = 1e6
"""A budget above ``BUDGET_CAP`` times the least depth (at least 1) is solved at that cap:
a budget of 1e300 in the constraint ``-x_f <= depth_max`` defeats Ipopt's arithmetic. When
the depth reached is below the cap the constraint is inactive, and the answer is the same
for every larger budget (the problem without the budget); a result that reaches the cap
is flagged (:meth:`MinPeakForceLanding.own_reasons`)."""


def budget_solved(depth_max: float, least_depth: float) -> float:
    """The budget the NLP is given: ``depth_max`` up to its cap (:data:`BUDGET_CAP`).

    Parameters
    ----------
    depth_max : float
        The budget asked for.
    least_depth : float
        The two-phase landing's least depth.
    """
    return min(depth_max, BUDGET_CAP * max(1.0, least_depth))


BUDGET_RTOL = 1e-6
"""The budget binds where the depth is within this of it (relative to ``max(1, D)``): the
refined depth meets an active budget to 1e-14, the transcribed one to Ipopt's tolerance; a
slack budget leaves order-one room."""


@lru_cache(maxsize=4)
def min_peak_force_transcription(ground: Ground = LINEAR_GROUND) -> MultipleShooting:
    """Yielding, then static until the body rests, ``|u| <= peak``; minimise ``peak``
    with the final depth at most the parameter ``depth_max``. The peak is at least the
    body's weight, which the leg holds once the body rests.

    Parameters
    ----------
    ground : Ground
        Ground model.
    """
    mp = MultiPhaseProblem("min_peak_force")
    par = parameters(mp)
    depth_max = mp.parameter("depth_max")
    weight = par["r_m"] / (1 + par["r_m"])  # the body's weight: the leg holds it at rest
    peak = mp.variable("peak", weight, par["u_max"], guess=par["u_max"])
    yielding = add_yielding(mp, "yielding", par, ground, u_bound=peak)
    yielding.free_final_time(1e-3, T_MAX, guess=0.3)
    static = add_static(mp, "static", par, ground, u_bound=peak)
    static.free_duration(1e-6, ARREST_MAX, guess=1.0)
    impact_state(yielding, par)
    arrest_to_rest(static, par, ground)
    mp.link(yielding, static)
    static.terminal_constraint(-static.x[2] - depth_max, -ca.inf, 0.0, name="depth budget")
    mp.minimize(peak)
    return MultipleShooting(mp, nodes=[100, 40], integrator="rk4", substeps=4, expand=True)


@dataclass(kw_only=True)
class MinPeakForceLanding(TwoPhaseLanding):
    """The least peak force within a depth budget (a two-phase landing).

    ``paper_depth`` holds the budget, so ``gain`` is the depth left unused (>= 0).

    Attributes
    ----------
    depth_max : float
        The depth budget.
    peak : float
        The least peak force ``max |u|`` (refined, else transcribed).
    least_depth : float
        The two-phase landing's least depth with the robot's own force limit.
    budget_active : bool
        The depth budget binds (the depth reaches it, to :data:`BUDGET_RTOL`): ``peak`` is
        the force limit whose two-phase least depth is ``depth_max``. Slack: ``peak`` is the
        least peak that lands at all, and the budget plays no part.
    """

    VARIANT: ClassVar[str] = "min-peak-force"
    LABEL: ClassVar[str] = "least peak force"
    REFERENCE: ClassVar[str] = "depth budget"
    WORSE_THAN_REFERENCE: ClassVar[str] = "the depth budget, exceeded by {:.2e}"

    depth_max: float
    peak: float
    least_depth: float

    @property
    def budget_active(self) -> bool:
        """The depth budget binds (see the class notes)."""
        return self.depth_max - self.depth <= BUDGET_RTOL * max(1.0, self.depth_max)

    def own_rows(self) -> list[tuple[str, object]]:
        """The peak force first, then the two-phase rows."""
        budget = ("active (the depth reaches D)" if self.budget_active else
                  f"slack (D - depth = {self.depth_max - self.depth:.6g}: the peak is the "
                  f"least that lands at all)")
        return [("peak force max |u|", self.peak), ("depth budget", budget),
                ("least depth at u_max", self.least_depth), *super().own_rows()]

    def own_reasons(self) -> list[str]:
        """The exact replay's largest force must be the peak (a transcription's, at most
        it); a budget solved at its cap (:data:`BUDGET_CAP`) must not bind there."""
        out = []
        cap = budget_solved(self.depth_max, self.least_depth)
        if cap < self.depth_max and not self.depth < cap * (1 - 1e-6):
            out.append(f"the depth budget was solved at {cap:.3g} and binds there")
        if self.replay is None:
            return out
        gap = self.replay.u_peak - self.peak  # the transcription's forces: at most the peak
        if self.refined is not None:
            gap = abs(gap)
        return out if gap <= 1e-9 * max(1.0, self.peak) else out + [
            f"the replay's largest force differs from the peak by {gap:.2e}"]

    @property
    def force_bound(self) -> float:
        """The peak: the force bound of this landing."""
        return self.peak

    def own_dict(self) -> dict[str, Any]:
        """The two-phase fields and the peak."""
        return {**super().own_dict(), "peak": self.peak, "depth_max": self.depth_max,
                "least_depth": self.least_depth, "budget_active": self.budget_active,
                "budget_slack": self.depth_max - self.depth}


class MinPeakForce(TwoPhase):
    """The hooks: the two-phase landing's result and replay, with this problem.

    Parameters
    ----------
    robot, impact, ground
        The landing.
    depth_max : float
        The depth budget.
    start : TwoPhaseLanding
        The two-phase minimum-depth landing (the guess: its force is within ``u_max``).
    """

    def __init__(self, robot: Robot, impact: Impact, ground: Ground, depth_max: float,
                 start: TwoPhaseLanding) -> None:
        super().__init__(robot, impact, ground, 1, None)
        self.depth_max, self.start = depth_max, start
        self.paper_depth = depth_max

    def parameters(self) -> dict[str, float]:
        """The landing's parameters and the budget (at most its cap, :func:`budget_solved`)."""
        return {**super().parameters(),
                "depth_max": budget_solved(self.depth_max, self.start.depth)}

    def transcription(self) -> MultipleShooting:
        """This variant's problem."""
        return min_peak_force_transcription(self.ground)

    def guess(self) -> Any:
        """The two-phase minimum-depth landing, cut into the phases."""
        start = self.start.refined if self.start.refined is not None else self.start.transcribed
        assert start is not None
        return phase_guess(start.trajectory(400), [self.start.T1])

    def accepts(self, neighbour: Any) -> bool:
        """Only a neighbour of this variant.

        Parameters
        ----------
        neighbour : PhasedLanding
            The warm start.
        """
        return isinstance(neighbour, MinPeakForceLanding)

    # the pipeline's own hooks, not the two-phase landing's: no bound on a re-solved
    # structure's objective, and Ipopt's verdict as it is (the budget was checked before)
    bound = PhasedVariant.bound
    explain = PhasedVariant.explain

    def assemble(self, sol: Any, ref: Any, notes: list[str], path: str) -> MinPeakForceLanding:
        """The two-phase result, with the peak and the budget.

        Parameters
        ----------
        sol : ocp.Solution or None
            The transcription (None on the structure path).
        ref : RefinedPhases or None
            The refined phases.
        notes : list of str
            What the solve noticed.
        path : str
            ``"transcription"`` or ``"structure"``.
        """
        two = super().assemble(sol, ref, notes, path)
        if two.depth < budget_solved(self.depth_max, self.start.depth) * (1 - 1e-6):
            notes.append(f"the depth budget does not bind: the least peak lands at depth "
                         f"{two.depth:.9g}, below {self.depth_max:.9g}")
        src = ref if ref is not None else sol
        return MinPeakForceLanding(**two.__dict__, depth_max=self.depth_max,
                                   peak=float(src.variables["peak"]),
                                   least_depth=self.start.depth)


def solve_min_peak_force(impact: Impact | float, robot: Robot = PAPER_ROBOT,
                         ground: Ground = LINEAR_GROUND, *, depth_max: float,
                         refine: bool = True, warm_start: Any = None) -> MinPeakForceLanding:
    """The least peak force ``max |u|`` that lands with the final depth at most
    ``depth_max``.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    robot : Robot
        The robot; its force limit ``u_max`` bounds the peak.
    ground : Ground
        Ground model.
    depth_max : float
        The depth budget: at least the two-phase landing's least depth with ``u_max``.
    refine : bool
        Refine the switching times with exact arcs.
    warm_start : MinPeakForceLanding, optional
        A neighbour (continuation).

    Raises
    ------
    ParameterError
        A budget below the least depth that ``u_max`` reaches.
    """
    impact = Impact.of(impact)
    if not (isinstance(depth_max, float | int) and math.isfinite(depth_max)
            and depth_max > 0):
        raise ParameterError("depth_max", f"must be a finite depth > 0, got {depth_max!r}")
    start = solve_two_phase(impact, robot, ground, replay=False)
    if depth_max < start.depth:
        raise ParameterError("depth_max", f"{depth_max:.9g} is below the least depth "
                                          f"{start.depth:.9g} that u_max={robot.u_max:g} "
                                          "reaches: no force within it lands")
    warm = warm_start if isinstance(warm_start, MinPeakForceLanding) else None
    out = solve_phased(MinPeakForce(robot, impact, ground, float(depth_max), start), warm,
                       refine=refine)
    assert isinstance(out, MinPeakForceLanding)
    return out


def _positive(d: float) -> str | None:
    return None if d > 0 else f"must be a depth > 0, got {d:g}"


VARIANT = Variant(
    "min-peak-force", "the least peak force max |u| landing within a depth budget",
    solve_min_peak_force, ground=True, objective=("peak", "peak force max |u|"),
    options=(Option("depth_max", float, help="the depth budget D (at least the two-phase "
                    "least depth)", check=_positive, required=True, metavar="D"),))
"""``softlanding solve --variant min-peak-force --depth-max D``."""

__all__ = ["BUDGET_CAP", "BUDGET_RTOL", "VARIANT", "MinPeakForce", "MinPeakForceLanding",
           "budget_solved",
           "min_peak_force_transcription", "solve_min_peak_force"]
