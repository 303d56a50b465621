"""Which kind of start :func:`ocp.multistart` makes next: a first round shared between the
kinds, then the starts go where they pay.

Two kinds of starts suit different problems. Bang sequences simulated
(:mod:`ocp.search.structured`) reach the optima of problems whose extremals differ in
the control's switching structure (a pendulum pumped in three or four swings, a car
that turns left or right first); waypoint paths (:mod:`ocp.search.waypoints`) reach the
optima of problems whose extremals differ in where the path goes (round an obstacle on
either side). Measured over 16 starts and three seeds (the figures of
``tests/ocp/search/test_several_optima.py``), the share of a kind's starts that reached
the global optimum ranges from 0 to 1 for each, and neither kind is best everywhere.

So the first round (:data:`FIRST` starts) deals the kinds by the share ``structured``
(alternating at the default 1/2), and every later round of :data:`ROUND` starts draws
each start's kind by Thompson sampling: a kind's yield is the fraction of its starts
that reached the best objective found so far (by any start, start 0 included), with a
uniform prior, ``Beta(1 + hits, 1 + misses)``; each start goes to the kind whose draw
is largest. A kind that keeps missing gets fewer starts but never none, so an optimum
only it reaches is still found; a new best objective re-scores every kind. The draws
come from their own seeded generator, so the same seed gives the same starts.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

__all__ = ["BANG", "FIRST", "ROUND", "WAYPOINT", "Allocation"]

BANG, WAYPOINT = "bang", "waypoint"
FIRST = 4
"""Starts after start 0 dealt by the share before any yield is read."""
ROUND = 4
"""Starts per later round (the kinds are drawn from the results of the rounds before)."""


class Allocation:
    """Deals the kinds of the starts (see the module docstring).

    Parameters
    ----------
    share : float
        The share of bang starts in the first round (all rounds when not ``adapt``).
    adapt : bool
        Draw the later rounds' kinds from the yields (else keep the share).
    rng : numpy.random.Generator
        The draws' generator.
    same : callable
        ``(a, b) -> bool``: two objectives are the same level.
    """

    def __init__(self, share: float, adapt: bool, rng: np.random.Generator,
                 same: Callable[[float, float], bool]) -> None:
        self.share, self.adapt, self.rng, self.same = share, adapt, rng, same
        self.dealt = 0  # starts dealt so far (start 0 not counted)

    def next_round(self, size: int, results: list[tuple[str, float]]) -> list[str]:
        """The kinds of the next ``size`` starts.

        Parameters
        ----------
        size : int
            How many starts.
        results : list of tuple
            ``(kind, objective)`` of every start run so far, start 0's kind ``""``;
            the objective NaN where the start reached no verified optimum.
        """
        kinds = []
        for _ in range(size):
            m = self.dealt + 1
            if not self.adapt or self.dealt < FIRST or self.share in (0.0, 1.0):
                bang = math.floor(m * self.share) > math.floor((m - 1) * self.share)
                kinds.append(BANG if bang else WAYPOINT)
            else:
                kinds.append(self._draw(results))
            self.dealt += 1
        return kinds

    def yields(self, results: list[tuple[str, float]]) -> dict[str, tuple[int, int]]:
        """Per kind: ``(hits, tries)``, hits the starts that reached the best objective.

        Parameters
        ----------
        results : list of tuple
            As for :meth:`next_round`.
        """
        found = [f for _, f in results if not math.isnan(f)]
        best = min(found) if found else math.nan
        out = {BANG: (0, 0), WAYPOINT: (0, 0)}
        for kind, f in results:
            if kind in out:
                hits, tries = out[kind]
                hit = not math.isnan(f) and self.same(f, best)
                out[kind] = (hits + int(hit), tries + 1)
        return out

    def _draw(self, results: list[tuple[str, float]]) -> str:
        y = self.yields(results)
        draws = {k: self.rng.beta(1 + h, 1 + n - h) for k, (h, n) in y.items()}
        return BANG if draws[BANG] >= draws[WAYPOINT] else WAYPOINT
