"""Output of the ``softlanding`` command: exit codes, tables, JSON, files, one-line errors.

Exit codes: 0 ok, 1 a well-posed run that failed (rest not proven, solver failure),
2 bad input, 3 internal error (a bug: ``--debug`` shows the traceback), 130 interrupted
(Ctrl-C), 143 terminated (SIGTERM), 129 hung up (SIGHUP; :mod:`softlanding.util.signals`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
from collections.abc import Sequence
from typing import Any

from softlanding.errors import ParameterError, SoftlandingError
from softlanding.model.robot import Robot
from softlanding.util.jsonable import json_safe

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_BUG, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

#: What matplotlib's Agg backend writes (a test keeps this list equal to matplotlib's own,
#: which it would take a 0.2 s import to ask before the arguments are checked).
FIGURE_FORMATS = ("avif", "eps", "gif", "jpeg", "jpg", "pdf", "pgf", "png", "ps", "raw",
                  "rgba", "svg", "svgz", "tif", "tiff", "webp")


class CliParser(argparse.ArgumentParser):
    """argparse, but usage errors are one line (exit 2) and ``-1e-3`` is a number.

    Parameters
    ----------
    *args, **kw
        As :class:`argparse.ArgumentParser`.
    """

    def __init__(self, *args: Any, **kw: Any) -> None:
        super().__init__(*args, **kw)
        # argparse reads "-1e-3" or "-inf" as an option; they are values here
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*([eE][-+]?\d+)?|\.\d+([eE][-+]?\d+)?|inf|infinity|nan)$", re.I)

    def error(self, message: str) -> None:  # type: ignore[override]
        """Print the usage error as one line and exit with code 2.

        Parameters
        ----------
        message : str
            argparse's message.
        """
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def fmt(x: Any) -> str:
    """A table cell: yes/no for booleans, 10 significant digits for floats.

    Parameters
    ----------
    x : object
        The value.
    """
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return f"{x:.10g}" if math.isfinite(x) else str(x)
    return str(x)


def print_table(rows: Sequence[tuple[str, object]]) -> None:
    """Print ``label  value`` rows, labels aligned.

    Parameters
    ----------
    rows : sequence of (str, object)
        The rows.
    """
    w = max(len(k) for k, _ in rows)
    write_out("".join(f"{k:<{w}}  {fmt(v)}\n" for k, v in rows))


def print_json(obj: Any) -> None:
    """Print one JSON object (numpy to Python, non-finite floats to null).

    Parameters
    ----------
    obj : object
        A JSON-able structure.
    """
    write_out(json.dumps(json_safe(obj)) + "\n")


def write_out(text: str) -> None:
    """Write ``text`` to standard output, flushed. A closed one (piped into ``head``, which
    has read enough) ends the output, not the run: the rest goes nowhere and the command
    still ends with its own exit code (a failed landing is still 1).

    Parameters
    ----------
    text : str
        What to write.
    """
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def robot_of(a: argparse.Namespace) -> Robot:
    """The robot of the model arguments (validated by :class:`Robot`).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments with ``rm``, ``s``, ``umax``, ``l0``.
    """
    return Robot(r_m=a.rm, s=a.s, u_max=a.umax, l0=a.l0)


def ground_of_args(a: argparse.Namespace) -> Any:
    """The ground model of the ``--ground`` options (validated by the model).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    from softlanding.cli.ground import ground_of

    return ground_of(a)


def target(a: argparse.Namespace, option: str = "plot") -> Any:
    """The figure or data file an option names, checked before any work (None if not given).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments (``force`` allows replacing an existing file).
    option : str
        The option's attribute name (``"plot"``, ``"out"``).
    """
    from softlanding.util.files import output_path

    value = getattr(a, option, None)
    if value is None:
        return None
    figure = option == "plot" or a.command == "demo"
    path = output_path(value, option, a.force, ".png" if figure else None)
    if figure and path.suffix.lower().lstrip(".") not in FIGURE_FORMATS:
        raise ParameterError(option, f"cannot write a figure as {path.suffix!r}; use one of "
                                     + ", ".join(f".{f}" for f in FIGURE_FORMATS))
    return path


def savefig(fig: Any, path: Any) -> str:
    """Write the figure atomically; the path actually written.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : pathlib.Path
        Where (checked by :func:`target`).
    """
    from softlanding.util.files import save_figure

    return str(save_figure(fig, path))



API_DESTS = {"r_m": "rm", "u_max": "umax", "k_p": "kp", "k_d": "kd", "c_d": "cd", "m_b": "mb",
             "m_f": "mf", "k_g": "kg", "U_max": "umax_si", "V0": "v0_si", "K_p": "Kp",
             "K_d": "Kd", "m_t": "mt"}
"""The API's parameter names whose command-line option is spelled otherwise (``c_d`` is
``--cd``); the others are spelled alike (``depth_max`` is ``--depth-max``)."""


def name_the_flag(exc: ParameterError, a: argparse.Namespace | None) -> ParameterError:
    """``exc`` naming the command line's option (``--cd``) instead of the API's parameter
    (``c_d``) when the user gave that option (a value derived from others keeps its name).

    Parameters
    ----------
    exc : ParameterError
        The error, as the API raised it (changed in place).
    a : argparse.Namespace or None
        The parsed command line.
    """
    name = exc.parameter
    dest = API_DESTS.get(name, name)
    given = None if a is None else getattr(a, dest, None)
    if name.startswith("-") or given is None or given is False:  # (0 is a value given)
        return exc
    flag = "--" + dest.replace("_", "-")
    exc.args = (flag + str(exc)[len(name):],)
    exc.parameter = flag
    return exc


def report_error(exc: BaseException, a: argparse.Namespace | None = None) -> int:
    """One line on stderr for an error; the exit code it means.

    Parameters
    ----------
    exc : BaseException
        The error a command raised.
    a : argparse.Namespace, optional
        The parsed command line (a bad value is then named by its option).
    """
    from ocp import SolveError

    if isinstance(exc, ParameterError):
        exc = name_the_flag(exc, a)
    if isinstance(exc, SoftlandingError):
        print(f"softlanding: {exc.label}: {exc}", file=sys.stderr)
        return exc.exit_code
    if isinstance(exc, SolveError):
        print(f"softlanding: solver failed: {exc} (Ipopt status {exc.status})", file=sys.stderr)
        return EXIT_FAILURE
    from softlanding.util.files import disk_full

    full = disk_full(exc)  # a full disk outside the outputs (e.g. numba's cache): a failure
    if full is not None:
        where = f" ({full.filename})" if full.filename else ""
        print(f"softlanding: error: no space left on the device{where}", file=sys.stderr)
        return EXIT_FAILURE
    if isinstance(exc, OSError):  # a file the user named cannot be written or read
        where = f": {exc.filename}" if exc.filename else ""
        print(f"softlanding: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"softlanding: internal error (a bug, please report it): {type(exc).__name__}: "
          f"{exc}; run again with --debug for the traceback", file=sys.stderr)
    return EXIT_BUG
