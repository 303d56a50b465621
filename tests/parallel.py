"""Which tests must share a worker when the second test command runs on both cores.

``pytest -m "slow or notebook" -n 2 --dist loadgroup`` (pytest-xdist) sends each group of tests
to one worker: a session or module fixture is computed once per worker that needs it, so tests
reading the same costly result (the documentation build, ``reproduce --quick``, the robust search
over the study's grounds, a module's fixtures) are kept together. The groups are the connected
components of "same file" and "same shared fixture"; the longest known groups go first so that
neither core idles at the end. xdist honours the groups only in its ``loadgroup`` mode, and
pytest-xdist 3.8 not under pytest 9.2 (pytest-xdist#1386): tests/conftest.py refuses both.
"""

from __future__ import annotations

from collections.abc import Sequence

import pytest

SHARED = ("docs_site", "study_robust", "grid_hop", "arrest_infeasible",
          "paper_impedance_optimum", "suite_refined", "suite_switching", "moon_lander_shooting")
"""Session fixtures of the conftests that more than one file reads."""

REPRODUCE = "reproduce --out paper --quick"
"""The one console run that two files read (the landing guide's command and
tests/softlanding/report/test_reproduce.py)."""

INDEPENDENT_FILES = ("tests/test_docs_commands.py",)
"""Files whose tests share no module fixture: each documented command runs alone."""

LONG_FIRST = ("docs_site", "console:reproduce", "study_robust")
"""Groups of several minutes, started first (longest first) so the others fill in beside."""


def require_loadgroup(dist: str) -> None:
    """Refuse a run on several workers whose groups xdist would ignore.

    Parameters
    ----------
    dist : str
        pytest-xdist's ``--dist`` mode of the run.

    Raises
    ------
    pytest.UsageError
        Unless ``dist`` is ``"loadgroup"``: in any other mode xdist does not tag a test with
        its group, so the tests of a group would be spread over the workers and each worker
        would build what they share (the documentation build twice at once, in one folder).
    """
    if dist != "loadgroup":
        raise pytest.UsageError(
            f"tests/conftest.py: on several workers run the tests with --dist loadgroup (not "
            f"{dist!r}): tests that share a costly result must share a worker (tests/parallel.py)")


def require_group_tags(ids: Sequence[str]) -> None:
    """Stop a run whose tests xdist did not tag with their groups.

    Parameters
    ----------
    ids : sequence of str
        The test ids a worker collected, each tagged ``...::test@group`` by xdist's
        ``--dist loadgroup`` (:func:`assign_groups` gives every test a group).

    Raises
    ------
    pytest.exit.Exception
        If a test's id has no group: xdist would then spread the group's tests over the
        workers (pytest-xdist 3.8 under pytest 9.2, pytest-xdist#1386).
    """
    untagged = [i for i in ids if i.rfind("@") <= i.rfind("]")]
    if untagged:
        pytest.exit(f"tests/conftest.py: pytest-xdist did not tag {untagged[0]} with its group; "
                    f"the groups would be ignored (pytest-xdist#1386: use pytest<9.2)", 4)


class _Groups:
    """Union-find over keys: items, files and shared results."""

    def __init__(self) -> None:
        self.parent: dict[str, str] = {}

    def find(self, key: str) -> str:
        self.parent.setdefault(key, key)
        while self.parent[key] != key:
            self.parent[key] = self.parent[self.parent[key]]
            key = self.parent[key]
        return key

    def join(self, a: str, b: str) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def shared_keys(item: pytest.Item) -> list[str]:
    """The keys an item's test is joined by: its file (unless independent) and the shared
    results it reads."""
    path = item.nodeid.split("::")[0]
    keys = [] if path in INDEPENDENT_FILES else [f"file:{path}"]
    names = set(getattr(item, "fixturenames", ()))
    keys += [name for name in SHARED if name in names]
    if path.endswith("test_reproduce.py") or ("console" in names and REPRODUCE in item.nodeid):
        keys.append("console:reproduce")
    return keys


def assign_groups(items: Sequence[pytest.Item]) -> list[pytest.Item]:
    """Mark every item with its group (``xdist_group``) and return the items with the
    :data:`LONG_FIRST` groups first, each group's tests in their collected order. A group's
    name is a shared key (a file, a fixture) or, for a test alone, ``alone:<n>``: xdist reads
    the group from the test id after its last ``@``, so a name cannot hold a test id's
    brackets."""
    groups = _Groups()
    for item in items:
        for key in shared_keys(item):
            groups.join(item.nodeid, key)
    rank = {}
    alone: dict[str, str] = {}
    for item in items:
        root = groups.find(item.nodeid)
        label = next((n for n in LONG_FIRST if groups.find(n) == root), root)
        if "::" in label:  # a test id: the test shares nothing
            label = alone.setdefault(label, f"alone:{len(alone)}")
        item.add_marker(pytest.mark.xdist_group(label))
        rank[item.nodeid] = LONG_FIRST.index(label) if label in LONG_FIRST else len(LONG_FIRST)
    return sorted(items, key=lambda it: rank[it.nodeid])  # stable: collected order within
