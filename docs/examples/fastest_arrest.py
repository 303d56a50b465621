"""
A new landing variant in one module: the fastest arrest within a depth budget
=============================================================================

The paper minimises the depth. A robot that must be ready to move again soon may rather
bring its body to rest as early as possible, as long as the foot sinks no deeper than a
budget ``depth_max``. This module is the whole variant, written against the public API:
the problem (the paper's yielding and static stance phases from
:mod:`softlanding.optimal.stance_phases`, a new objective and one more terminal condition),
a result class, and the hooks :func:`softlanding.optimal.solve_phased` runs: a transcription
started from the two-phase minimum-depth landing, every switch refined with exact arcs, the
schedule replayed in the exact simulator. Run it: ``python docs/examples/fastest_arrest.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import ClassVar

import casadi as ca

from ocp import MultiPhaseProblem, MultipleShooting
from softlanding.errors import InfeasibleLandingError
from softlanding.model import LINEAR_GROUND, PAPER_ROBOT, Impact, Robot
from softlanding.optimal import (
    TwoPhase,
    TwoPhaseLanding,
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


@lru_cache(maxsize=1)
def fastest_arrest_transcription() -> MultipleShooting:
    """Yielding, then static stance until the body rests; minimise that time, depth <= budget."""
    mp = MultiPhaseProblem("fastest_arrest")
    par = parameters(mp)
    depth_max = mp.parameter("depth_max")
    yielding = add_yielding(mp, "yielding", par)
    yielding.free_final_time(1e-3, T_MAX, guess=0.3)
    static = add_static(mp, "static", par)
    static.free_duration(1e-6, ARREST_MAX, guess=1.0)
    impact_state(yielding, par)
    arrest_to_rest(static, par)
    mp.link(yielding, static)
    static.terminal_constraint(-static.x[2] - depth_max, -ca.inf, 0.0, name="depth budget")
    mp.minimize(static.T)
    return MultipleShooting(mp, nodes=[100, 40], integrator="rk4", substeps=4, expand=True)


@dataclass(kw_only=True)
class FastestArrest(TwoPhaseLanding):
    """The fastest arrest; ``paper_depth`` holds the budget, so ``gain`` is the margin.

    Attributes
    ----------
    depth_max : float
        The depth budget.
    """

    VARIANT: ClassVar[str] = "fastest-arrest"
    WORSE_THAN_REFERENCE: ClassVar[str] = "the depth budget is exceeded by {:.2e}"

    depth_max: float


class FastestArrestVariant(TwoPhase):
    """The hooks: the two-phase landing's guess, replay and result, with this problem."""

    def __init__(self, robot: Robot, impact: Impact, depth_max: float) -> None:
        super().__init__(robot, impact, LINEAR_GROUND, 1, None)
        self.depth_max = depth_max
        self.paper_depth = depth_max
        self.start = solve_two_phase(impact, robot)  # the minimum-depth landing: the guess

    def parameters(self) -> dict[str, float]:
        """The landing's parameters and the budget."""
        return {**super().parameters(), "depth_max": self.depth_max}

    def transcription(self) -> MultipleShooting:
        """This variant's problem."""
        return fastest_arrest_transcription()

    def guess(self):
        """The minimum-depth two-phase landing, cut into the phases."""
        assert self.start.refined is not None
        return phase_guess(self.start.refined.trajectory(400), [self.start.T1])

    def accepts(self, neighbour) -> bool:
        """Only a neighbour of this variant."""
        return isinstance(neighbour, FastestArrest)

    def bound(self) -> float | None:
        """No depth bound for a re-solved structure (the budget is a constraint)."""
        return None

    def explain(self, err, guess) -> Exception:
        """Ipopt's verdict as it is (the two-phase diagnosis does not apply)."""
        return InfeasibleLandingError(f"no arrest within the depth budget {self.depth_max:g} "
                                      f"(Ipopt: {err.status})")

    def assemble(self, sol, ref, notes, path) -> FastestArrest:
        """The two-phase result, with the budget."""
        two = super().assemble(sol, ref, notes, path)
        return FastestArrest(**two.__dict__, depth_max=self.depth_max)


def solve_fastest_arrest(impact: Impact | float, depth_max: float,
                         robot: Robot = PAPER_ROBOT) -> FastestArrest:
    """The landing that brings the body to rest soonest with the foot at most ``depth_max``
    deep.

    Parameters
    ----------
    impact : Impact or float
        Impact velocity.
    depth_max : float
        Depth budget (at least the minimum-depth landing's depth, or it is infeasible).
    robot : Robot
        The robot (with a force limit).
    """
    out = solve_phased(FastestArrestVariant(robot, Impact.of(impact), depth_max))
    assert isinstance(out, FastestArrest)
    return out


if __name__ == "__main__":
    best = solve_two_phase(-3.0)
    for extra in (0.01, 0.1, 0.5):
        r = solve_fastest_arrest(-3.0, best.depth + extra)
        print(f"budget {r.depth_max:.6f}: rest at T = {r.T:.6f} (min-depth landing: "
              f"{best.T:.6f}), depth {r.depth:.6f}, replay difference "
              f"{r.replay_difference:.1e}, verified: {not r.unverified_reasons()}")
