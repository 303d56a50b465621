"""Issue 45 item 4: what a multistart's starts cost, and where they go.

* A failed start costs its solve alone: the analysis of its last iterate runs when its
  ``diagnosis`` is read, and only start 0 (what a solve from the guess gives) retries a
  failed scaled solve on the NLP as posed. On the tree before, every failed start ran
  the diagnosis (its message was read) and the retry, doubling its time.
* After a first round shared between the kinds of starts (bang sequences, waypoint
  paths), the starts go to the kind whose starts reach the best objective (Thompson
  sampling), never all of them.

The case: Dubins' car to a point behind it at 16 intervals (tests/oracles), whose
default guess and waypoint starts fail in Ipopt (local infeasibility). About 3 s CPU.
"""

import numpy as np
import pytest

import ocp.transcriptions.failure as failure
import ocp.transcriptions.nlp as nlp
from ocp import multistart
from ocp.search.allocation import BANG, FIRST, WAYPOINT, Allocation
from ocp.transcriptions.diagnosis import Diagnosis
from tests.oracles.several_optima import dubins_transcription


def test_failed_starts_pay_neither_diagnosis_nor_retry(monkeypatch):
    calls: dict[str, list] = {"diagnose": [], "retry": []}
    diagnose, after = failure.diagnose, nlp.after_failure

    def counted_diagnose(*args, **kwargs):
        calls["diagnose"].append(1)
        return diagnose(*args, **kwargs)

    def counted_after(tr, sol, args, unscaled):  # a failed scaled solve: retried as posed?
        calls["retry"].append(tr.scaling_options.get("fallback", True))
        return after(tr, sol, args, unscaled)

    monkeypatch.setattr(failure, "diagnose", counted_diagnose)
    monkeypatch.setattr(nlp, "after_failure", counted_after)
    res = multistart(dubins_transcription(), n=4, seed=0, stop=None)
    failed = [s for s in res.starts if not s.success]
    assert failed[0].index == 0 and len(failed) >= 2  # the default guess and others fail
    assert len(calls["retry"]) == len(failed)  # every failure was a scaled solve
    assert calls["retry"][0] is True and not any(calls["retry"][1:])
    assert calls["diagnose"] == []  # nothing analysed while the starts ran
    assert all(s.message.startswith("Ipopt failed") for s in failed)
    d = failed[1].diagnosis  # read: analysed once, then kept
    assert isinstance(d, Diagnosis) and failed[1].diagnosis is d
    assert len(calls["diagnose"]) == 1


def same(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-6 * max(1.0, abs(b))


def test_later_rounds_go_to_the_kind_that_reaches_the_best():
    deal = Allocation(0.5, True, np.random.default_rng(0), same)
    first = deal.next_round(FIRST, [("", 2.0)])
    assert sorted(first) == [BANG, BANG, WAYPOINT, WAYPOINT]
    # the waypoint starts reach 1.0, the bang starts the default's 2.0
    results = [("", 2.0)] + [(k, 1.0 if k == WAYPOINT else 2.0) for k in first]
    assert deal.yields(results) == {BANG: (0, 2), WAYPOINT: (2, 2)}
    later = [k for _ in range(50) for k in deal.next_round(4, results)]
    assert later.count(WAYPOINT) > 0.8 * len(later) and later.count(BANG) > 0
    # a start that fails counts as a miss; a new best re-scores every kind
    results += [(BANG, 0.5), (WAYPOINT, np.nan)]
    assert deal.yields(results) == {BANG: (1, 3), WAYPOINT: (0, 3)}


@pytest.mark.parametrize("share", [0.0, 0.25, 1.0])
def test_a_fixed_share_is_kept(share):
    deal = Allocation(share, False, np.random.default_rng(0), same)
    results = [("", 1.0)] + [(WAYPOINT, 1.0)] * 8
    kinds = deal.next_round(8, results)
    assert kinds.count(BANG) == round(8 * share)
