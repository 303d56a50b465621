"""The second test command's groups (tests/parallel.py): a shared result computed on one worker."""

from tests.parallel import assign_groups


class Item:
    """What assign_groups reads of a pytest item."""

    def __init__(self, nodeid: str, *fixtures: str) -> None:
        self.nodeid, self.fixturenames, self.marks = nodeid, list(fixtures), []

    def add_marker(self, mark) -> None:
        self.marks.append(mark)

    @property
    def group(self) -> str:
        (mark,) = [m for m in self.marks if m.name == "xdist_group"]
        return mark.args[0]


def test_shared_results_and_files_keep_their_tests_on_one_worker_longest_first():
    items = [Item("tests/a.py::t1"), Item("tests/a.py::t2", "study_robust"),
             Item("tests/b.py::t", "study_robust"), Item("tests/c.py::t"),
             Item("tests/test_docs_commands.py::t[hop]", "console"),
             Item("tests/test_docs_commands.py::t[reproduce --out paper --quick]", "console"),
             Item("tests/softlanding/report/test_reproduce.py::t1", "console"),
             Item("tests/softlanding/report/test_reproduce.py::t2"),
             Item("tests/test_notebooks.py::t", "docs_site"), Item("tests/test_docs.py::t",
                                                                  "docs_site")]
    ordered = assign_groups(items)
    group = {it.nodeid: it.group for it in items}
    # a file's tests share its module fixtures; a shared fixture joins files
    assert group["tests/a.py::t1"] == group["tests/a.py::t2"] == group["tests/b.py::t"]
    assert group["tests/a.py::t1"] == "study_robust"
    assert group["tests/c.py::t"] != group["tests/a.py::t1"]
    # the documented commands run alone, except the reproduction test_reproduce.py reads
    docs = "tests/test_docs_commands.py::t"
    assert group[f"{docs}[reproduce --out paper --quick]"] == "console:reproduce"
    assert group["tests/softlanding/report/test_reproduce.py::t2"] == "console:reproduce"
    assert group[f"{docs}[hop]"] not in ("console:reproduce", group["tests/c.py::t"])
    assert group[f"{docs}[hop]"] == "alone:0"  # xdist reads a group after the id's last "@"
    assert group["tests/test_notebooks.py::t"] == group["tests/test_docs.py::t"] == "docs_site"
    # the long groups first, in the order given; the others as collected
    firsts = [it.group for it in ordered[:8]]
    assert firsts == ["docs_site"] * 2 + ["console:reproduce"] * 3 + ["study_robust"] * 3
    assert [it.nodeid for it in ordered[8:]] == ["tests/c.py::t", f"{docs}[hop]"]


def test_a_run_on_several_workers_without_groups_is_refused():
    import pytest

    from tests.parallel import require_loadgroup

    require_loadgroup("loadgroup")
    for dist in ("load", "loadscope", "worksteal"):
        with pytest.raises(pytest.UsageError, match="--dist loadgroup"):
            require_loadgroup(dist)


def test_a_run_whose_tests_xdist_left_untagged_stops():
    import pytest

    from tests.parallel import require_group_tags

    require_group_tags(["tests/a.py::t@file:tests/a.py", "tests/b.py::t[x]@docs_site"])
    for untagged in ("tests/a.py::t", "tests/a.py::t[a@b]"):
        with pytest.raises(pytest.exit.Exception, match="did not tag"):
            require_group_tags(["tests/b.py::t@docs_site", untagged])
