"""What the phases of a problem share: its parameters (set at solve time) and decision
variables (optimised), and the checks of the bounds and guesses that may depend on them."""

from __future__ import annotations

from typing import Any

import casadi as ca

from .errors import ProblemDefinitionError
from .symbols import require_only, to_sx

__all__ = ["RESERVED", "Bound", "Shared", "guess_value"]

RESERVED = ("t", "t0", "T")
Bound = float | ca.SX


class Shared:
    """Parameters (set at solve time) and decision variables (optimised), shared by phases."""

    def __init__(self) -> None:
        self.param_names: list[str] = []
        self.params: list[ca.SX] = []
        self.var_names: list[str] = []
        self.vars: list[ca.SX] = []
        self.var_bounds: dict[str, tuple[ca.SX, ca.SX]] = {}
        self.var_guess: dict[str, ca.SX | None] = {}
        self.var_ref: dict[str, tuple[float, float] | None] = {}
        self.objective_ref: float | None = None  # set by minimize(..., ref=)
        self.phase_names: set[str] = set()  # states and controls of every phase

    @property
    def p(self) -> ca.SX:
        """The parameters, stacked."""
        return ca.vertcat(*self.params) if self.params else ca.SX(0, 1)

    @property
    def v(self) -> ca.SX:
        """The decision variables, stacked."""
        return ca.vertcat(*self.vars) if self.vars else ca.SX(0, 1)

    def taken(self, name: str) -> bool:
        """Whether ``name`` is already a parameter, a variable or reserved.

        Parameters
        ----------
        name : str
            A candidate name.
        """
        return name in self.param_names or name in self.var_names or name in RESERVED

    def bound(self, value: Bound, what: str) -> ca.SX:
        """A bound or guess: a number or an expression of the parameters.

        Parameters
        ----------
        value : float or SX
            A number or an expression of the parameters.
        what : str
            Named in the error if ``value`` is not acceptable.
        """
        b = to_sx(value, what)
        require_only(b, self.params, what, "bounds and guesses may depend on parameters only")
        return b

    def limit(self, value: Bound, what: str) -> ca.SX:
        """A control's bound: a number or an expression of the parameters and the decision
        variables (``u <= peak``: the control set moves with the variable).

        Parameters
        ----------
        value : float or SX
            A number or an expression of the parameters and variables.
        what : str
            Named in the error if ``value`` is not acceptable.
        """
        b = to_sx(value, what)
        require_only(b, [*self.params, *self.vars], what,
                     "a control's bounds may depend on parameters and decision variables only")
        return b


def guess_value(shared: Shared, guess: Any, what: str) -> Any:
    """None, a number/parameter expression, or a ``(start, end)`` pair of them.

    Parameters
    ----------
    shared : Shared
        The parameters a guess may depend on.
    guess : None, float, SX or (start, end) pair
        A state's, control's or variable's guess as given.
    what : str
        Named in the error if ``guess`` is not acceptable.
    """
    if guess is None:
        return None
    if isinstance(guess, tuple | list):
        if len(guess) != 2:
            raise ProblemDefinitionError(f"{what}: give one value or a (start, end) pair")
        return tuple(shared.bound(g, what) for g in guess)
    return shared.bound(guess, what)
