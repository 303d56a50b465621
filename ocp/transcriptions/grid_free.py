"""What a transcription's build does not take from its grid (:class:`GridFree`: the compiled
phases, the default guesses; shared by the transcriptions of one problem on other meshes),
and the check of the ``expand`` argument."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..definition.compiled import CompiledPhase
from ..definition.errors import ProblemDefinitionError
from ..definition.guess import DefaultChoices, control_guess, fixed_ends, state_ends, variable_guess
from ..definition.multiphase import MultiPhaseProblem

__all__ = ["GridFree", "expand_mode"]

def expand_mode(expand: Any) -> bool | str:
    """``expand`` checked: True, False or ``"auto"`` (anything else is refused).

    Parameters
    ----------
    expand : bool or str
        A transcription's ``expand`` argument.
    """
    if expand == "auto" and isinstance(expand, str):
        return "auto"
    if isinstance(expand, (bool, np.bool_)):
        return bool(expand)
    raise ProblemDefinitionError(f"expand must be True, False or 'auto', got {expand!r}")


@dataclass
class GridFree:
    """What a transcription's build does not take from its grid, shared by the
    transcriptions of one problem on other meshes (mesh refinement builds each
    round's NLP from it: the problem is compiled, its default guesses and its
    scaling references are derived once).

    Attributes
    ----------
    multiphase : MultiPhaseProblem
        The problem as phases.
    times : list of PhaseTimes
        How each phase's times enter the NLP.
    compiled : list of CompiledPhase
        Each phase's functions.
    choices : DefaultChoices
        The replaceable bare defaults of the guesses.
    ends, plain : list of tuple of SX
        Each phase's state start and end guesses, with the replaceable defaults
        and without them.
    controls : list of SX
        Each phase's control guess.
    variables : SX
        The decision variables' guess.
    sizes : list or None
        The states' sizes for the scaling (:mod:`ocp.definition.sizes`), once known.
    functions : dict
        Grid-independent CasADi functions of a discretisation, by key.
    """

    multiphase: MultiPhaseProblem
    times: list[Any]
    compiled: list[CompiledPhase]
    choices: DefaultChoices
    ends: list[tuple[ca.SX, ca.SX]]
    plain: list[tuple[ca.SX, ca.SX]]
    controls: list[ca.SX]
    variables: ca.SX
    sizes: list[list[float | None]] | None = None
    functions: dict[Any, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, multiphase: MultiPhaseProblem) -> GridFree:
        """Compile a validated problem and derive its default guesses.

        Parameters
        ----------
        multiphase : MultiPhaseProblem
            The problem.
        """
        mp = multiphase
        choices = DefaultChoices()
        ends: list[tuple[ca.SX, ca.SX]] = []
        plain: list[tuple[ca.SX, ca.SX]] = []
        controls = []
        for i, ph in enumerate(mp.phases):
            fixed = fixed_ends(ph)  # the costly part, shared by both
            ends.append(state_ends(ph, _previous_ends(mp, i, ends), choices, fixed))
            plain.append(state_ends(ph, _previous_ends(mp, i, plain), fixed=fixed))
            controls.append(control_guess(ph, choices))
        return cls(mp, mp.times(), [CompiledPhase(ph) for ph in mp.phases], choices, ends,
                   plain, controls, variable_guess(mp.shared, choices))


def _previous_ends(mp: MultiPhaseProblem, i: int, ends: list) -> dict[str, ca.SX] | None:
    """End guesses of the phase that phase ``i`` is time-linked from, by state name."""
    for a, b in mp.time_links:
        if b == i and a < i:
            prev = mp.phases[a]
            return {n: ends[a][1][k] for k, n in enumerate(prev.state_names)}
    return None
