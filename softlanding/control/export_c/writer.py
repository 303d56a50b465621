"""Fill the C templates of this folder with the controller's (and the foot filter's)
numbers and write the files.

The templates (``controller.c.in``, ``controller.h.in``, ``README.txt.in``) are hand-written
C and text with ``@NAME@`` placeholders; :mod:`.layout` gives the numbers.
"""

from __future__ import annotations

import re
import textwrap
from importlib import resources
from pathlib import Path

import numpy as np

from softlanding._version import __version__
from softlanding.control import bangbang as bb
from softlanding.control.export_c.layout import (
    c_double,
    constant_lines,
    creep_constant_lines,
    creep_gl_text,
    dop853_text,
    filter_constant_lines,
    filtered_constant_lines,
    layout_lines,
    robot_lines,
)

#: The files written, by role.
HEADER, SOURCE, README = "softlanding_controller.h", "softlanding_controller.c", "README.txt"
FILES = (HEADER, SOURCE, README)

_PLACEHOLDER = re.compile(r"@[A-Z0-9_]+@")


def _template(name: str) -> str:
    return resources.files("softlanding.control.export_c").joinpath(name).read_text("utf-8")


def _fill(text: str, values: dict[str, str]) -> str:
    for k, v in values.items():
        text = text.replace(f"@{k}@", v)
    left = _PLACEHOLDER.search(text)
    if left:  # a template names a number this writer does not give: a bug, not bad input
        raise RuntimeError(f"placeholder {left.group()} left unfilled")
    return text


def controller_sources(P: np.ndarray, robot_text: str,
                       sensor_noise: float = 0.0) -> dict[str, str]:
    """The exported files' texts, by file name (:data:`FILES`).

    Parameters
    ----------
    P : array
        :func:`~softlanding.control.bangbang.robot_numbers`: the numbers the C file's
        ``SL_ROBOT_NUMBERS`` holds.
    robot_text : str
        What they are, in words (the header and the README say it).
    sensor_noise : float
        The sensors' noise the foot filter is exported for (``SL_SENSOR_NOISE``).

    Raises
    ------
    ValueError
        ``P`` has not :data:`~softlanding.control.bangbang.NP` finite entries, or the noise
        is not finite and >= 0.
    """
    P = np.asarray(P, float)
    if P.shape != (bb.NP,) or not np.all(np.isfinite(P)):
        raise ValueError(f"P must hold {bb.NP} finite numbers")
    if not (np.isfinite(sensor_noise) and sensor_noise >= 0):
        raise ValueError("sensor_noise must be finite and >= 0")
    common = {"VERSION": __version__, "HEADER": HEADER, "SOURCE": SOURCE,
              "ROBOT_TEXT": robot_text}
    header = _fill(_template("controller.h.in"), {
        **common, "GUARD": "SOFTLANDING_CONTROLLER_H",
        "P_LAYOUT": "\n".join(layout_lines("P_")), "M_LAYOUT": "\n".join(layout_lines("M_")),
        "CONSTANTS": "\n".join(constant_lines()), "F_LAYOUT": "\n".join(layout_lines("F_")),
        "FILTER_CONSTANTS": "\n".join(filter_constant_lines()),
        "FILTERED_CONSTANTS": "\n".join(filtered_constant_lines()),
        "CREEP_CONSTANTS": "\n".join(creep_constant_lines())})
    source = _fill(_template("controller.c.in"), {
        **common, "DOP853": dop853_text(), "CREEP_GL": creep_gl_text(),
        "ROBOT": "\n".join(robot_lines(P)),
        "SENSOR_NOISE": c_double(sensor_noise)})
    readme = _fill(_template("README.txt.in"), {
        **common, "EXPORTED_FOR": textwrap.fill(f"Exported for: {robot_text}.", 90)})
    return {HEADER: header, SOURCE: source, README: readme}


def write_controller(folder: Path, sources: dict[str, str]) -> list[Path]:
    """Write ``sources`` (:func:`controller_sources`) into the existing folder ``folder``.

    Parameters
    ----------
    folder : Path
        A new folder (the caller's temporary one: :func:`softlanding.util.files.atomic_folder`).
    sources : dict
        File name -> text.

    Returns
    -------
    list of Path
        The files written.
    """
    out = []
    for name, text in sources.items():
        path = folder / name
        with open(path, "x", encoding="utf-8") as f:
            f.write(text)
        out.append(path)
    return out


__all__ = ["FILES", "HEADER", "README", "SOURCE", "controller_sources", "write_controller"]
