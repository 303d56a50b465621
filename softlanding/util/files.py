"""Output files that never clobber a user's file by surprise and are never left half-written.

Paths are checked before any work starts (:func:`output_path`, :func:`output_folder`): the
folder must exist and accept a new file, the name must fit the file system. Every file is
written under a short temporary name in the same folder and placed only once complete
(:func:`atomic`): without ``force`` the placement itself is exclusive (a hard link, which
fails if the name appeared meanwhile, e.g. from a concurrent run), with ``force`` an atomic
replace. Inside :func:`output_run` (one CLI command) the files placed are rolled back if the
run fails later, so a run leaves all its outputs or none. Modes follow the umask.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from softlanding.errors import DiskFullError, ParameterError
from softlanding.util.signals import deferred_signals, raise_if_interrupted

_TMP_STEM = 24
"""Characters of the final name kept in a temporary name (keeps it short: NAME_MAX)."""
# errors of os.link on file systems without hard links (FAT, SMB, some FUSE)
_NO_HARD_LINKS = {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK, errno.ENOSYS,
                  errno.EXDEV}
_FULL = {errno.ENOSPC, errno.EDQUOT}


def disk_full(exc: BaseException) -> OSError | None:
    """The "no space left" error behind ``exc``, if any (following its chain of causes).

    A writer may hide it: matplotlib's PDF backend, cleaning up after the failed write,
    raises ``AttributeError: 'Stream' object has no attribute 'pos'`` with the
    :class:`OSError` as its context.

    Parameters
    ----------
    exc : BaseException
        The error a write raised.

    Returns
    -------
    OSError or None
        The first error of the chain whose ``errno`` is ``ENOSPC`` or ``EDQUOT``.
    """
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        if isinstance(e, OSError) and e.errno in _FULL:
            return e
        e = e.__cause__ or e.__context__
    return None


@contextlib.contextmanager
def _full_means(where: Path) -> Iterator[None]:
    """A full disk inside the body becomes one :class:`DiskFullError` naming ``where``."""
    try:
        yield
    except DiskFullError as exc:  # from a file of a temporary folder: name the final one
        raise DiskFullError(f"no space left on {where}") from exc.__cause__
    except Exception as exc:
        if disk_full(exc) is None:
            raise
        raise DiskFullError(f"no space left on {where}") from exc


def current_umask() -> int:
    """The process's umask (read without changing it where the system allows).

    Returns
    -------
    int
        The umask bits, e.g. ``0o022``.
    """
    with contextlib.suppress(OSError, ValueError):  # Linux >= 4.7 reports it race-free
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    mask = os.umask(0o022)  # elsewhere: set and restore (process-global, fine for a CLI)
    os.umask(mask)
    return mask


def file_mode() -> int:
    """Mode of a new output file: ``0o666`` less the umask (as ``open`` would create it).

    Returns
    -------
    int
        Permission bits.
    """
    return 0o666 & ~current_umask()


def folder_mode() -> int:
    """Mode of a new output folder: ``0o777`` less the umask (as ``mkdir`` would create it).

    Returns
    -------
    int
        Permission bits.
    """
    return 0o777 & ~current_umask()


def _name_max(folder: Path) -> int:
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        return 255


def _temp_prefix(path: Path) -> str:
    return f".{path.stem[:_TMP_STEM]}."


def _check_folder(folder: Path, name: str, option: str, what: str) -> None:
    """The folder exists, takes new entries, and ``name`` fits; refused up front otherwise."""
    if not folder.is_dir():
        raise ParameterError(option, f"folder {folder} does not exist")
    if len(os.fsencode(name)) > _name_max(folder):
        raise ParameterError(option, f"{what} name {name[:20]}...{name[-8:]} is longer than "
                                     f"the file system allows ({_name_max(folder)} bytes)")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ParameterError(option, f"folder {folder} is not writable")
    # os.access says yes to root everywhere, even in /proc or on a read-only mount: a real
    # probe, under the temporary name's pattern, is the only sure test
    try:
        fd, probe = tempfile.mkstemp(prefix=".softlanding.", suffix=".probe", dir=folder)
    except OSError as exc:
        raise ParameterError(option, f"cannot create files in {folder}: "
                                     f"{exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(probe)


@dataclass
class _Placed:
    path: Path
    inode: int
    backup: Path | None


@dataclass
class OutputRun:
    """The output files of one run: claimed up front, rolled back together on failure.

    Parameters
    ----------
    force : bool
        Existing files may be replaced (``--force``).

    Attributes
    ----------
    force : bool
        Existing files may be replaced.
    claimed : dict
        Resolved path -> the option that named it.
    """

    force: bool
    claimed: dict[str, str] = field(default_factory=dict, init=False)
    _placed: list[_Placed] = field(default_factory=list, init=False)

    def claim(self, path: Path, option: str) -> None:
        """Reserve ``path`` for ``option``; a second option naming the same file is refused.

        Parameters
        ----------
        path : Path
            The output file.
        option : str
            The option naming it.
        """
        key = os.path.realpath(path)
        other = self.claimed.get(key)
        if other is not None:
            raise ParameterError(option, f"{path} is also the --{other} file; give each "
                                         "output its own name")
        self.claimed[key] = option

    def option_of(self, path: Path) -> str:
        """The option that claimed ``path`` (``"out"`` if none did), for messages.

        Parameters
        ----------
        path : Path
            The output file.
        """
        return self.claimed.get(os.path.realpath(path), "out")

    def placed(self, path: Path, inode: int, backup: Path | None) -> None:
        """Record a file placed by this run (rolled back if the run fails).

        Parameters
        ----------
        path : Path
            The file.
        inode : int
            Its inode: rollback leaves alone a file someone else has put there since.
        backup : Path or None
            A hard link to the file it replaced (``force``), restored on rollback.
        """
        self._placed.append(_Placed(path, inode, backup))

    def rollback(self) -> None:
        """Remove every file this run placed, restoring the files they replaced."""
        with deferred_signals():
            for p in reversed(self._placed):
                try:
                    ours = os.lstat(p.path).st_ino == p.inode
                except OSError:
                    ours = False
                with contextlib.suppress(OSError):
                    if ours and p.backup is not None:
                        os.replace(p.backup, p.path)
                    elif ours:
                        os.unlink(p.path)
                if p.backup is not None:
                    with contextlib.suppress(FileNotFoundError):
                        os.unlink(p.backup)
            self._placed.clear()

    def commit(self) -> None:
        """Keep every file placed: drop the backups of the files replaced."""
        for p in self._placed:
            if p.backup is not None:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(p.backup)
        self._placed.clear()


_ACTIVE: list[OutputRun] = []


@contextlib.contextmanager
def output_run(force: bool = False) -> Iterator[OutputRun]:
    """One run's outputs: all kept if the body returns, all removed if it raises.

    A closed standard output (:class:`BrokenPipeError`, e.g. piped into ``head``) is not a
    failure: the files stay.

    Parameters
    ----------
    force : bool
        Existing files may be replaced (``--force``).
    """
    run = OutputRun(force)
    _ACTIVE.append(run)
    try:
        yield run
        raise_if_interrupted()  # a signal swallowed on the way (a failed solve) still fails
    except BrokenPipeError:
        run.commit()
        raise
    except BaseException:
        run.rollback()
        raise
    else:
        run.commit()
    finally:
        _ACTIVE.remove(run)


def active_run() -> OutputRun | None:
    """The innermost :func:`output_run` in progress, if any.

    Returns
    -------
    OutputRun or None
        The run.
    """
    return _ACTIVE[-1] if _ACTIVE else None


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
        Empty name, a folder, a missing or unwritable parent folder, a name too long for the
        file system, an existing file without ``force``, or (inside :func:`output_run`) a
        file another option of the same run names.
    """
    if not str(path):
        raise ParameterError(option, "needs a file name")
    p = Path(path)
    # before the suffix is added: "adir/" or an existing folder "adir" must not become adir.png
    if not p.name or str(path).endswith(("/", os.sep)) or os.path.isdir(p):
        raise ParameterError(option, f"{path} is a folder; give a file name")
    if default_suffix and not p.suffix:
        p = p.with_name(p.name + default_suffix)
    _check_folder(p.parent, p.name, option, "file")  # first: a long name fails stat() too
    if p.is_dir():
        raise ParameterError(option, f"{p} is a folder; give a file name")
    if p.exists() and not force:
        raise ParameterError(option, f"{p} exists; pass --force to overwrite it")
    run = active_run()
    if run is not None:
        run.claim(p, option)
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
        Empty name, a file, a non-empty folder without ``force``, a missing or unwritable
        parent folder, or a name too long for the file system.
    """
    if not str(path):
        raise ParameterError(option, "needs a folder name")
    p = Path(path)
    _check_folder(p.absolute().parent, p.absolute().name, option, "folder")
    if p.exists() and not p.is_dir():
        raise ParameterError(option, f"{p} exists and is not a folder")
    if p.is_dir() and any(p.iterdir()):
        if not force:
            raise ParameterError(option, f"{p} is not empty; pass --force to replace its files")
        _replaceable(p, option)
    return p


MAX_KEPT_ENTRIES = 10_000
"""Most entries a folder replaced with ``--force`` may hold (they are linked into the new
folder, :func:`atomic_folder`): a larger folder is not a run's output folder."""


def _replaceable(folder: Path, option: str) -> None:
    """A folder ``--force`` may swap: one file system, at most :data:`MAX_KEPT_ENTRIES`."""
    dev = folder.stat().st_dev
    n = 0
    for root, dirs, files in os.walk(folder):
        n += len(dirs) + len(files)
        if n > MAX_KEPT_ENTRIES:
            raise ParameterError(option, f"{folder} holds more than {MAX_KEPT_ENTRIES} files; "
                                         "give a new or empty folder")
        for d in dirs:
            if os.lstat(os.path.join(root, d)).st_dev != dev:
                raise ParameterError(option, f"{folder} has another file system mounted "
                                             f"inside ({os.path.join(root, d)}); give a new "
                                             "or empty folder")


def own_folder(path: str | os.PathLike[str], names: tuple[str, ...], option: str) -> Path:
    """A command's own output folder (a fixed name): missing, or holding only its ``names``.

    Such a folder is the command's to replace on every run (:func:`atomic_folder` with
    ``force``); a folder of that name holding anything else is someone else's and refused.

    Parameters
    ----------
    path : str or PathLike
        The folder.
    names : tuple of str
        The files the command writes into it.
    option : str
        The option that would name another output, for messages.

    Raises
    ------
    ParameterError
        ``path`` is a file, or a folder holding other entries, or its parent folder takes no
        new entries.
    """
    p = Path(path)
    _check_folder(p.absolute().parent, p.name, option, "folder")
    if p.exists() and not p.is_dir():
        raise ParameterError(option, f"{p} exists and is not a folder; name another output "
                                     f"with --{option}")
    if p.is_dir():
        others = sorted(set(os.listdir(p)) - set(names))
        if others:
            raise ParameterError(option, f"{p} holds files this command did not write "
                                         f"({others[0]}...); name another output with "
                                         f"--{option}")
    return p


def _backup(path: Path) -> Path | None:
    """A hard link to the file about to be replaced, so a rollback can restore it."""
    name = path.with_name(f"{_temp_prefix(path)}{secrets.token_hex(4)}.backup")
    try:
        os.link(path, name)
    except OSError:  # no file there, or no hard links here: nothing to restore
        return None
    return name


def place(tmp: Path, path: Path, force: bool | None = None) -> None:
    """Move the finished ``tmp`` to ``path``: exclusively, or replacing with ``force``.

    Parameters
    ----------
    tmp : Path
        The complete file, in the same folder.
    path : Path
        Its final name.
    force : bool, optional
        Replace an existing file (default: the active :func:`output_run`'s, else False).

    Raises
    ------
    ParameterError
        ``path`` exists (it may have appeared since the check: a concurrent run) and
        ``force`` is not set; ``tmp`` is left for the caller to remove.
    """
    run = active_run()
    if force is None:
        force = run.force if run is not None else False
    inode = os.stat(tmp).st_ino
    # a signal between placing the file and recording it would leave it behind on rollback
    with deferred_signals():
        backup = _backup(path) if force and run is not None else None
        if force:
            os.replace(tmp, path)
        else:
            _place_exclusive(tmp, path, run.option_of(path) if run is not None else "out")
        if run is not None:
            run.placed(path, inode, backup)


def _place_exclusive(tmp: Path, path: Path, option: str) -> None:
    exists = ParameterError(option, f"{path} exists; pass --force to overwrite it")
    try:
        os.link(tmp, path)  # atomic, and fails if the name exists
    except FileExistsError:
        raise exists from None
    except OSError as exc:
        if exc.errno not in _NO_HARD_LINKS:
            raise
        try:  # no hard links: reserve the name exclusively, then fill it
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        except FileExistsError:
            raise exists from None
        os.replace(tmp, path)
    else:
        os.unlink(tmp)


@contextlib.contextmanager
def atomic(path: Path, force: bool | None = None) -> Iterator[Path]:
    """Yield a temporary name beside ``path``; place it at ``path`` on success (:func:`place`).

    The temporary file is removed whatever happens; the file placed gets the umask's mode.

    Parameters
    ----------
    path : Path
        The final file.
    force : bool, optional
        Replace an existing file (default: the active :func:`output_run`'s, else False).
    """
    fd, name = tempfile.mkstemp(prefix=_temp_prefix(path),
                                suffix=f".partial{path.suffix[:12]}", dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        with _full_means(path.parent):
            yield tmp
        os.chmod(tmp, file_mode())  # mkstemp makes it 0600
        place(tmp, path, force)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


@contextlib.contextmanager
def atomic_folder(path: Path, force: bool = True) -> Iterator[Path]:
    """Yield a temporary folder beside ``path``; put it in place, all at once, on success.

    If ``path`` does not exist or is an empty folder, the temporary folder is renamed to it
    in one step, which fails if a concurrent run got there first. Otherwise, with ``force``,
    the files of ``path`` the run did not write are linked into the temporary folder (the
    run's files of the same names replace them) and the two folders are swapped: readers see
    the old folder or the new one, never a mixture, and a failed or interrupted run leaves
    the old one as it was.

    Parameters
    ----------
    path : Path
        The final folder.
    force : bool
        Allow replacing a non-empty folder.

    Raises
    ------
    ParameterError
        ``path`` is a non-empty folder (it may have been filled since the check) and
        ``force`` is not set, or it is not a folder.
    DiskFullError
        The disk filled up (nothing of the run is left).
    """
    path = Path(os.path.abspath(path))  # "." or "out/" named: the folder itself
    tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(path), suffix=".partial", dir=path.parent))
    try:
        with _full_means(path):
            yield tmp
            os.chmod(tmp, folder_mode())  # mkdtemp makes it 0700
            with deferred_signals():
                try:
                    os.rename(tmp, path)  # atomic; fails unless path is missing or empty
                    return
                except OSError as exc:
                    if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR):
                        raise
                    if not path.is_dir():
                        raise ParameterError("out", f"{path} exists and is not a folder") \
                            from None
                    if not force:
                        raise ParameterError("out", f"{path} is not empty; pass --force to "
                                                    "replace its files") from None
                _keep_others(path, tmp)
                _swap(path, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _keep_others(old: Path, new: Path) -> None:
    """Link (or copy) into ``new`` every file of ``old`` that ``new`` has no file for."""
    for src in sorted(old.rglob("*")):
        dst = new / src.relative_to(old)
        if src.is_dir() and not src.is_symlink():
            if not dst.exists():
                dst.mkdir()
                shutil.copystat(src, dst)
        elif not os.path.lexists(dst) and dst.parent.is_dir() and not dst.parent.is_symlink():
            try:
                os.link(src, dst, follow_symlinks=False)
            except OSError:
                shutil.copy2(src, dst, follow_symlinks=False)


def _swap(path: Path, new: Path) -> None:
    """Put the folder ``new`` at ``path`` and remove the folder that was there."""
    old = path.with_name(f"{_temp_prefix(path)}{secrets.token_hex(4)}.replaced")
    os.chmod(new, stat.S_IMODE(os.stat(path).st_mode))  # the folder keeps its mode
    os.rename(path, old)
    try:
        os.rename(new, path)
    except BaseException:
        os.rename(old, path)
        raise
    shutil.rmtree(old, ignore_errors=True)


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
