"""Reproduce the paper end to end: every figure, the headline numbers, a robustness study.

:func:`reproduce` writes, into one folder, each figure of the paper as PNG and
PDF, ``summary.json`` (every headline number, machine-readable), ``summary.md``
(the same as tables, with the paper's values beside ours where it gives them)
and the computed datasets under ``data/`` (netCDF; the unknown-ground study's rows as
JSON and CSV). ``quick=True`` uses
coarser grids and fewer impact velocities (about 3 minutes of CPU); the
numbers it reports are still exact for the grids it uses, and each of them is
what the public API returns for the same arguments (the test suite checks).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

from softlanding.report.paper import PAPER_SECTIONS
from softlanding.report.phased import PHASED_SECTION
from softlanding.report.registry import Context, Section, Settings
from softlanding.report.terrain import TERRAIN_SECTION
from softlanding.report.unknown_ground import UNKNOWN_GROUND_SECTION
from softlanding.util.files import atomic_folder
from softlanding.util.jsonable import json_safe
from softlanding.util.progress import activity

SECTIONS: tuple[Section, ...] = (*PAPER_SECTIONS, TERRAIN_SECTION, PHASED_SECTION,
                                 UNKNOWN_GROUND_SECTION)
"""The registry: every section of the reproduction, in the order run and reported."""


def reproduce(out_dir: str | Path, quick: bool = False, *, progress: bool = True,
              log: Callable[[str], None] | None = print, force: bool = True) -> dict:
    """Regenerate every figure of the paper, the summary files and the robustness study.

    Parameters
    ----------
    out_dir : str or Path
        Folder to write into (created if missing; files of the same names are replaced,
        and only once the whole run has succeeded).
    quick : bool
        Coarser grids and fewer impact velocities (about 3 minutes of CPU).
    progress : bool
        Progress bars for the long sweeps.
    log : callable or None
        Receives one line per finished section (None: silent).
    force : bool
        Allow a folder that is not empty when the run ends (its files of the same names are
        replaced). With False a missing or empty folder is filled in one atomic rename, and
        a folder a concurrent run filled meanwhile is refused
        (:class:`~softlanding.errors.ParameterError`).

    Returns
    -------
    dict
        The contents of ``summary.json``.
    """
    final = Path(out_dir)
    if not final.parent.is_dir():
        final.parent.mkdir(parents=True)
    # written into a temporary folder and moved into place at the end: an interrupted or
    # failed run leaves nothing half-written in out_dir
    with atomic_folder(final, force) as out:
        (out / "data").mkdir()
        summary = _run_sections(out, Settings.make(quick), progress, log)
    return summary


def _run_sections(out: Path, st: Settings, progress: bool,
                  log: Callable[[str], None] | None) -> dict:
    ctx = Context(out, st, progress)
    summary: dict = {}
    timings: dict[str, float] = {}
    t_all = time.perf_counter()
    for i, section in enumerate(SECTIONS, 1):
        t0 = time.perf_counter()
        # sections of seconds to minutes: on a terminal a line with its elapsed time
        with activity(f"[{i}/{len(SECTIONS)}] {section.title}", enabled=progress):
            summary[section.key] = section.run(ctx)
        timings[section.key] = time.perf_counter() - t0
        if log is not None:
            log(f"[{i}/{len(SECTIONS)}] {section.title:<20} {timings[section.key]:6.1f} s")
    from softlanding._version import __version__

    summary["meta"] = {"quick": st.quick, "elapsed_s": time.perf_counter() - t_all,
                       "section_s": timings, "version": __version__,
                       "settings": {k: v for k, v in st.__dict__.items()},
                       "units": "dimensionless (x_s = m_t g / k_g, tau_s = sqrt(m_t / k_g), "
                                "force m_t g) unless a key says otherwise"}
    files = ctx.files + ["summary.json", "summary.md"]
    summary["files"] = files
    (out / "summary.json").write_text(json.dumps(json_safe(summary), indent=1))
    (out / "summary.md").write_text(summary_markdown(summary))
    return summary


def summary_markdown(s: dict) -> str:
    """The summary as Markdown tables (paper values beside ours where it gives them).

    Parameters
    ----------
    s : dict
        The contents of ``summary.json`` (see :func:`reproduce`); a section missing from it
        is left out.
    """
    m = s["meta"]
    out = [f"# Soft landing: reproduction of the paper ({'quick' if m['quick'] else 'full'} run)",
           "", f"Computed in {m['elapsed_s']:.1f} s by softlanding {m['version']}. Units are the "
           "paper's dimensionless ones unless stated. Figures: PNG and PDF beside this file.", ""]
    for section in SECTIONS:
        if section.key in s:
            out += section.markdown(s[section.key])
    out += ["## Files", "", ", ".join(s["files"]), ""]
    return "\n".join(out)


__all__ = ["SECTIONS", "Settings", "reproduce", "summary_markdown"]
