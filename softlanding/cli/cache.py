"""``softlanding cache``: what the compiled ground-law cache holds; ``--clear`` empties it."""

from __future__ import annotations

import argparse

from softlanding.cli.output import EXIT_OK, print_json, print_table


def cache_command(a: argparse.Namespace) -> int:
    """Run ``softlanding cache`` (the parsed arguments; the exit code).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments (``clear``, ``json``).
    """
    from softlanding.simulation.groundcode import clear_law_cache, law_cache_info

    removed = clear_law_cache() if a.clear else None
    info = law_cache_info()
    if a.json:
        print_json({**info, "removed": removed})
        return EXIT_OK
    rows: list[tuple[str, object]] = [
        ("compiled ground laws", info["path"]),
        ("laws", f"{info['laws']} (at most {info['max_laws']})"),
        ("size", f"{info['bytes'] / 2**20:.2f} MiB (at most {info['max_bytes'] / 2**20:g} MiB)")]
    if removed is not None:
        rows.insert(0, ("removed", f"{removed} laws"))
    print_table(rows)
    return EXIT_OK


__all__ = ["cache_command"]
