"""Output files that never clobber a user's file by surprise and are never left half-written.

Paths are checked before any work starts (:func:`output_path`); every file is
written under a temporary name in the same folder and renamed into place only
once complete (:func:`atomic`), so a failed or interrupted run leaves nothing
behind.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from softlanding.errors import ParameterError


def output_path(path: str | os.PathLike[str], option: str, force: bool,
                default_suffix: str | None = None) -> Path:
    """The file a run will write, checked up front.

    Parameters
    ----------
    path : str or PathLike
        What the user gave.
    option : str
        The option's name, for messages (``"plot"``, ``"out"``).
    force : bool
        Overwrite an existing file.
    default_suffix : str, optional
        Appended when the name has none (matplotlib adds ``.png`` the same way).

    Raises
    ------
    ParameterError
        Empty name, a folder, a missing parent folder, or an existing file without ``force``.
    """
    if not str(path):
        raise ParameterError(option, "needs a file name")
    p = Path(path)
    if p.is_dir() or not p.name:
        raise ParameterError(option, f"{p} is a folder; give a file name")
    if default_suffix and not p.suffix:
        p = p.with_name(p.name + default_suffix)
    if not p.parent.is_dir():
        raise ParameterError(option, f"folder {p.parent} does not exist")
    if p.exists() and not force:
        raise ParameterError(option, f"{p} exists; pass --force to overwrite it")
    return p


def output_folder(path: str | os.PathLike[str], option: str, force: bool) -> Path:
    """A folder a run will fill: new, empty, or (with ``force``) one whose files may be replaced.

    Parameters
    ----------
    path : str or PathLike
        What the user gave.
    option : str
        The option's name, for messages.
    force : bool
        Allow a non-empty folder.

    Raises
    ------
    ParameterError
        Empty name, a file, or a non-empty folder without ``force``.
    """
    if not str(path):
        raise ParameterError(option, "needs a folder name")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ParameterError(option, f"{p} exists and is not a folder")
    if p.is_dir() and any(p.iterdir()) and not force:
        raise ParameterError(option, f"{p} is not empty; pass --force to replace its files")
    if not p.parent.is_dir():
        raise ParameterError(option, f"folder {p.parent} does not exist")
    return p


@contextlib.contextmanager
def atomic(path: Path) -> Iterator[Path]:
    """Yield a temporary name beside ``path`` (same suffix); rename it to ``path`` on success.

    Parameters
    ----------
    path : Path
        The final file.
    """
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".partial{path.suffix}",
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


@contextlib.contextmanager
def atomic_folder(path: Path) -> Iterator[Path]:
    """Yield a temporary folder beside ``path``; move its contents into ``path`` on success.

    Parameters
    ----------
    path : Path
        The final folder (created if missing; existing files of the same names replaced).
    """
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".partial", dir=path.parent))
    try:
        yield tmp
        path.mkdir(exist_ok=True)
        for src in sorted(tmp.rglob("*")):
            dst = path / src.relative_to(tmp)
            if src.is_dir():
                dst.mkdir(exist_ok=True)
            else:
                os.replace(src, dst)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def save_figure(fig, path: Path, dpi: int = 130, **kw) -> Path:
    """Write a matplotlib figure atomically and close it; returns the path written.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : Path
        From :func:`output_path` (with its suffix).
    dpi : int
        Resolution of raster formats.
    **kw
        Passed to ``savefig``.
    """
    import matplotlib.pyplot as plt

    try:
        with atomic(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png", **kw)
    finally:
        plt.close(fig)
    return path
