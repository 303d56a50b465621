"""The unknown-ground section of the reproduction: its Markdown and figure from a small fake
row set (fast: no study is run)."""

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

from softlanding.report.registry import Settings  # noqa: E402
from softlanding.report.reproduction import SECTIONS  # noqa: E402
from softlanding.report.unknown_ground import (  # noqa: E402
    UNKNOWN_GROUND_SECTION,
    unknown_ground_entry,
    unknown_ground_markdown,
)

ROBOT = {"r_m": 5.0, "s": 20.0, "u_max": 8.2, "l0": 10.0}


def _c(depth, clair, feasible=True):
    return {"depth": depth, "ratio": depth / clair, "feasible": feasible}


def _row(v0, k, c_d, clair, *, mpc=1.0, open_loop=1.5, ok=True, verified=True, worst=1.2):
    ground = {"model": "linear", "stiffness": k} if c_d == 0 else \
        {"model": "drag", "c_d": c_d, "stiffness": k}
    return {"v0": v0, "ground": ground, "clairvoyant_depth": clair,
            "clairvoyant_verified": verified,
            "open_loop": _c(open_loop * clair, clair, ok),
            "robust": _c(1.3 * clair, clair), "tree": _c(1.1 * clair, clair),
            "impedance_nominal": _c(1.4 * clair, clair),
            "impedance_worst": _c(worst * clair, clair),
            "mpc": {**_c(mpc * clair, clair, verified), "step_time_median_ms": 2.0,
                    "step_time_p99_ms": 10.0, "replans": 3, "robot": ROBOT}}


ROWS = [_row(-3.0, 0.5, 0.0, 3.0), _row(-3.0, 2.0, 1.0, 0.5, ok=False, mpc=1.03),
        _row(-10.0, 0.5, 0.0, 9.0, verified=False, worst=2.0),
        _row(-10.0, 2.0, 1.0, 1.5, mpc=1 - 1e-6)]


@pytest.fixture(scope="module")
def md():
    entry = unknown_ground_entry(ROWS, period=0.01, tau_s=0.025)
    return entry, "\n".join(unknown_ground_markdown(entry))


def test_entry_counts_the_goals(md):
    entry, _ = md
    assert entry["controllers"] == ["open_loop", "robust", "tree", "impedance_nominal",
                                    "impedance_worst", "mpc"]  # an extra key is picked up
    assert entry["rig_period_ms"] == pytest.approx(0.25)
    a = entry["all"]
    assert a["mpc"]["within_2_percent"] == 3 and a["mpc"]["never_below"] == 3
    assert a["feasible"]["open_loop"] == 3 and a["feasible"]["mpc"] == 3
    assert entry["by_v0"]["-10"]["worst"]["impedance_worst"] == pytest.approx(18.0)
    assert entry["by_v0"]["-3"]["clairvoyant_worst"] == 3.0


def test_markdown_tables(md):
    _, text = md
    assert text.startswith("## Landing on an unknown ground (fig_unknown_ground)")
    assert "r_m = 5, s = 20, u_max = 8.2" in text
    assert "impedance tuned for the worst case" in text
    lines = text.splitlines()
    worst = [ln for ln in lines if ln.startswith("| -3 | 3.0000 |")]
    # v0 = -3: nominal plan broke a limit on one ground (flagged), the tree did not
    assert worst == ["| -3 | 3.0000 | 4.5000 ! | 3.9000 | 3.3000 | 4.2000 | 3.6000 | "
                     "3.0000 |"]
    assert "| -10 | 9.0000 | 13.5000 | 11.7000 | 9.9000 | 12.6000 | 18.0000 | 9.0000 ! |" \
        in lines
    assert "| all | 4 | 3 | 3 | 4 | 4 | 4 | 4 | 3 |" in lines  # feasible counts
    # MPC goals and step times: 2 ms median, 10 ms p99, a rig period of 0.25 ms
    assert "| -3 | 2 | 1 | 2 | 1.0300 | 2.00 | 10.0 | 8.0 | 40 |" in lines
    assert "| all | 4 | 3 | 3 | 1.0300 | 2.00 | 10.0 | 8.0 | 40 |" in lines
    assert "not proven: 1; on a ground whose clairvoyant optimum is not verified either: 1" \
        in text.replace("\n", " ")
    tables = "\n".join(ln if ln.startswith("|") else "" for ln in lines).split("\n\n")
    for t in filter(None, (t.strip() for t in tables)):  # as many cells as the header
        assert len({ln.count("|") for ln in t.splitlines()}) == 1, t


def test_section_is_registered_last_with_its_grids():
    assert SECTIONS[-1] is UNKNOWN_GROUND_SECTION and UNKNOWN_GROUND_SECTION.key == \
        "unknown_ground"
    quick = Settings.make(True)
    assert (quick.unknown_v0, quick.unknown_stiffness, quick.unknown_drag) == \
        ((-3.0,), (0.5, 2.0), (0.0, 1.0))
    from softlanding.studies.unknown_ground import STUDY_DRAG, STUDY_STIFFNESS, STUDY_V0

    full = Settings.make(False)
    assert (full.unknown_v0, full.unknown_stiffness, full.unknown_drag) == \
        (STUDY_V0, STUDY_STIFFNESS, STUDY_DRAG)


def test_study_figure_marks_infeasible_results():
    import matplotlib.pyplot as plt

    from softlanding.plots import plot_unknown_ground_study

    fig = plot_unknown_ground_study(ROWS)
    axes = fig.get_axes()
    assert [a.get_title(loc="left") for a in axes] == ["impact velocity $v_0$ = -3",
                                                       "impact velocity $v_0$ = -10"]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "impedance tuned for the worst case" in labels
    assert any("hollow" in t and "limit broken" in t for t in labels)
    assert "r_m" in fig._suptitle.get_text()
    plt.close(fig)
