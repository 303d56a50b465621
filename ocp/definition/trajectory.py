"""One trajectory type for every sampled solution in the toolkit.

A :class:`Trajectory` is what a transcribed solution, a refined (switching-time)
solution and the exact hybrid simulator of :mod:`softlanding` all return when
sampled: times, states and controls with their names, and optionally a mode
label per sample (a ground mode, an arc kind) and a phase index. It knows no
application; the names say what the columns are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Samples of a trajectory.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times, non-decreasing (an event time may appear twice: the
        state just before and just after a jump).
    x : ndarray, shape (n, nx)
        States.
    u : ndarray, shape (n, nu)
        Controls.
    state_names, control_names : sequence of str
        Column names of ``x`` and ``u``.
    mode : ndarray of str, shape (n,), optional
        A label per sample (e.g. the ground mode, or the arc kind).
    phase : ndarray of int, shape (n,), optional
        Phase index per sample (multi-phase problems).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    state_names: tuple[str, ...]
    control_names: tuple[str, ...]
    mode: np.ndarray | None = None
    phase: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).ravel()
        n = t.size
        x = np.asarray(self.x, dtype=float).reshape(n, -1)
        u = np.asarray(self.u, dtype=float).reshape(n, -1) if n else np.zeros((0, 0))
        set_ = object.__setattr__
        set_(self, "t", t)
        set_(self, "x", x)
        set_(self, "u", u)
        set_(self, "state_names", tuple(self.state_names))
        set_(self, "control_names", tuple(self.control_names))
        if len(self.state_names) != x.shape[1]:
            raise ValueError(f"{x.shape[1]} state columns but {len(self.state_names)} names")
        if n and len(self.control_names) != u.shape[1]:
            raise ValueError(f"{u.shape[1]} control columns but {len(self.control_names)} names")
        if self.mode is not None:
            set_(self, "mode", np.asarray(self.mode).astype(str).reshape(n))
        if self.phase is not None:
            set_(self, "phase", np.asarray(self.phase, dtype=int).reshape(n))

    def __len__(self) -> int:
        return self.t.size

    def state(self, name: str) -> np.ndarray:
        """The column of state ``name``.

        Parameters
        ----------
        name : str
            State name.
        """
        return self.x[:, _index(self.state_names, name, "state")]

    def control(self, name: str) -> np.ndarray:
        """The column of control ``name``.

        Parameters
        ----------
        name : str
            Control name.
        """
        return self.u[:, _index(self.control_names, name, "control")]

    def __getitem__(self, name: str) -> np.ndarray:
        """A state or control column by name, or ``"t"``."""
        if name == "t":
            return self.t
        if name in self.state_names:
            return self.state(name)
        return self.control(name)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict: ``t``, one list per state and control, ``mode``, ``phase``
        (a value a phase does not have, NaN in the arrays, is None: strict JSON has no NaN)."""
        def col(a: np.ndarray) -> list[float | None]:
            return [float(v) if np.isfinite(v) else None for v in a]

        d: dict[str, Any] = {"t": self.t.tolist()}
        d.update({n: col(self.x[:, i]) for i, n in enumerate(self.state_names)})
        d.update({n: col(self.u[:, i]) for i, n in enumerate(self.control_names)})
        if self.mode is not None:
            d["mode"] = self.mode.tolist()
        if self.phase is not None:
            d["phase"] = self.phase.tolist()
        return d

    def after(self, t0: float) -> Trajectory:
        """The samples from ``t0`` on, their times counted from ``t0`` (e.g. the rest of a
        plan, as the guess of a re-solve started there).

        Parameters
        ----------
        t0 : float
            The new time origin.
        """
        keep = self.t >= t0
        return Trajectory(self.t[keep] - t0, self.x[keep], self.u[keep], self.state_names,
                          self.control_names,
                          None if self.mode is None else self.mode[keep],
                          None if self.phase is None else self.phase[keep])

    def to_xarray(self):
        """An :class:`xarray.Dataset` with one variable per state and control, over ``t``."""
        import xarray as xr

        data: dict[str, Any] = {n: ("t", self.x[:, i]) for i, n in enumerate(self.state_names)}
        data.update({n: ("t", self.u[:, i]) for i, n in enumerate(self.control_names)})
        if self.mode is not None:
            data["mode"] = ("t", self.mode)
        if self.phase is not None:
            data["phase"] = ("t", self.phase)
        return xr.Dataset(data, coords={"t": self.t})

    @classmethod
    def concatenate(cls, parts: Sequence[Trajectory]) -> Trajectory:
        """Join trajectories with the same columns (e.g. the phases of a solution)."""
        if not parts:
            raise ValueError("nothing to concatenate")
        first = parts[0]
        for p in parts[1:]:
            if p.state_names != first.state_names or p.control_names != first.control_names:
                raise ValueError("trajectories have different columns")
        modes = [p.mode for p in parts]
        phases = [p.phase for p in parts]
        return cls(
            np.concatenate([p.t for p in parts]), np.vstack([p.x for p in parts]),
            np.vstack([p.u for p in parts]), first.state_names, first.control_names,
            None if any(m is None for m in modes) else np.concatenate(modes),  # type: ignore[arg-type]
            None if any(q is None for q in phases) else np.concatenate(phases),  # type: ignore[arg-type]
        )


def _index(names: tuple[str, ...], name: str, what: str) -> int:
    try:
        return names.index(name)
    except ValueError:
        raise KeyError(f"no {what} named {name!r}; have {list(names)}") from None
