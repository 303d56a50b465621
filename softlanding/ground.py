"""Ground models: the force yielding ground puts on a foot that digs into it.

A ground model is a small frozen value object whose :meth:`yield_force` gives,
as a CasADi expression (or a number), the upward force on a foot moving down at
depth ``d = -x_f`` with velocity ``v_f``. Everything else (the simulator's mode
matrices, the OCP's dynamics, the PMP checks, the energy ledger) is derived
from it through :mod:`softlanding.dynamics`; do not write a ground law anywhere
else.

The hybrid logic is the paper's for every model: the ground is plastic (the
crater keeps its deepest depth ``d``), a foot at rest at the crater bottom is
held by any support force up to ``yield_force(d, 0)`` (beyond that it yields
again), the ground cannot pull (below 0 the foot lifts off), and a foot in
flight lands again at the crater bottom.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable


@runtime_checkable
class Ground(Protocol):
    """What the toolkit needs of a ground model."""

    @property
    def name(self) -> str:
        """Short name (``"linear"``, ``"drag"``, ...)."""

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """Upward force on the foot while it yields (moves down) at ``depth`` >= 0."""

    @property
    def is_affine(self) -> bool:
        """True if the yielding force is affine in the state (exact matrix-exponential path)."""

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, **parameters}`` for JSON output."""

    def __hash__(self) -> int:
        """Ground models are frozen values (mode matrices are cached per model)."""


@dataclass(frozen=True)
class LinearGround:
    """The paper's one-way plastic spring: ``f_g = -x_f = d`` while the foot yields.

    In the paper's units the stiffness is 1 (lengths are scaled by
    ``x_s = m_t g / k_g``), so the model has no parameter. The crater of depth
    ``d`` holds support forces up to ``d``; the work done on the ground by a
    foot that dug to depth ``d`` is ``d^2 / 2``.
    """

    name: ClassVar[str] = "linear"

    def yield_force(self, depth: Any, v_f: Any) -> Any:
        """``f_g = d`` (independent of the foot's velocity).

        Parameters
        ----------
        depth : float or expression
            ``-x_f`` (>= 0).
        v_f : float or expression
            The foot's velocity (unused).
        """
        return depth

    @property
    def is_affine(self) -> bool:
        return True

    def to_dict(self) -> dict[str, Any]:
        return {"model": self.name}


LINEAR_GROUND = LinearGround()
"""The paper's ground (the default everywhere)."""

__all__ = ["Ground", "LINEAR_GROUND", "LinearGround"]
