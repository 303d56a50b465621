"""The reproduction's sections as one registry: each brings its run and its Markdown.

A :class:`Section` computes its numbers (writing its figures and data into the run's folder
through the :class:`Context`) and turns them into lines of ``summary.md``;
:mod:`softlanding.report.reproduction` runs the registered sections in order and assembles
``summary.json`` and ``summary.md`` from them. A new section is one :class:`Section` value
added to :data:`softlanding.report.reproduction.SECTIONS`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Settings:
    """Grid sizes of one reproduction run.

    Parameters
    ----------
    quick : bool
        The quick run.
    map_n, optimizer_grid : int
        Points per axis of the depth maps and of the optimiser's starting grid.
    curve_v0, compare_v0, cot_v0 : tuple of float
        Impact velocities of the optimal-gain curves, the comparison and the CoT study.
    experiment_kd_n : int
        Damping values of the experiment curves.
    robustness_n : int
        Factors of the robustness study.
    unknown_v0, unknown_stiffness, unknown_drag : tuple of float
        The unknown-ground study's impact velocities and true grounds' ``K`` and ``c_d``.
    """

    quick: bool
    map_n: int
    optimizer_grid: int
    curve_v0: tuple[float, ...]
    compare_v0: tuple[float, ...]
    cot_v0: tuple[float, ...]
    experiment_kd_n: int
    robustness_n: int
    unknown_v0: tuple[float, ...]
    unknown_stiffness: tuple[float, ...]
    unknown_drag: tuple[float, ...]

    @classmethod
    def make(cls, quick: bool) -> Settings:
        """The quick run's grids, or the full run's.

        Parameters
        ----------
        quick : bool
            The quick run.
        """
        if quick:
            # robustness: the factors 0.7, 1 and 1.3 (the worst regrets are at the ends)
            return cls(True, 41, 41, _grid(0.0, -10.0, 6), _grid(0.0, -10.0, 6),
                       _grid(-1.0, -10.0, 5), 51, 3, (-3.0,), (0.5, 2.0), (0.0, 1.0))
        from softlanding.studies.unknown_ground import STUDY_DRAG, STUDY_STIFFNESS, STUDY_V0

        return cls(False, 101, 101, _grid(0.0, -10.0, 41), _grid(0.0, -10.0, 21),
                   _grid(-0.5, -10.0, 20), 251, 13, tuple(STUDY_V0), tuple(STUDY_STIFFNESS),
                   tuple(STUDY_DRAG))


def _grid(a: float, b: float, n: int) -> tuple[float, ...]:
    return tuple(float(x) for x in np.round(np.linspace(a, b, n), 12))


def save_figure(fig: Any, out: Path, stem: str, files: list[str]) -> None:
    """Write ``fig`` as ``stem.png`` and ``stem.pdf`` into ``out`` and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    out : Path
        The run's (temporary) folder.
    stem : str
        File name without extension.
    files : list of str
        Receives the names written.
    """
    import matplotlib.pyplot as plt

    for ext in ("png", "pdf"):
        path = out / f"{stem}.{ext}"
        fig.savefig(path, dpi=130, bbox_inches="tight")
        files.append(path.name)
    plt.close(fig)


@dataclass
class Context:
    """What a section's run receives.

    Parameters
    ----------
    out : Path
        The run's (temporary) folder; ``data/`` exists.
    settings : Settings
        Grid sizes.
    progress : bool
        Progress bars for the long sweeps.
    files : list of str
        Names of the files written so far (a section appends its own).
    shared : dict
        Results that later sections reuse (the depth maps, the depth-optimal impedance).
    """

    out: Path
    settings: Settings
    progress: bool
    files: list[str] = field(default_factory=list)
    shared: dict[str, Any] = field(default_factory=dict)

    def save(self, fig: Any, stem: str) -> None:
        """Write ``fig`` as PNG and PDF (see :func:`save_figure`).

        Parameters
        ----------
        fig : matplotlib.figure.Figure
            The figure.
        stem : str
            File name without extension.
        """
        save_figure(fig, self.out, stem, self.files)


@dataclass(frozen=True)
class Section:
    """One section of the reproduction.

    Parameters
    ----------
    key : str
        Its key in ``summary.json``.
    title : str
        Its name in the progress lines.
    run : callable
        ``run(context) -> entry``: computes the section, writes its files, returns its
        JSON-able numbers.
    markdown : callable
        ``markdown(entry) -> list of str``: its lines of ``summary.md``.
    """

    key: str
    title: str
    run: Callable[[Context], Any]
    markdown: Callable[[Any], list[str]]


__all__ = ["Context", "Section", "Settings", "save_figure"]
