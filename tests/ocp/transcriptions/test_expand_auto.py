"""``expand="auto"`` (multiple shooting's default, issue 31 item 2): a transcription's
first solve runs on the unexpanded graph (cheap to build), its re-solves on the
SX-expanded one (built once, faster per iteration); both land on the same optimum.
On the tree before, ``MultipleShooting`` re-solved on the unexpanded graph forever
(``sol.expanded`` did not exist) and ``expand="auto"`` was read as True.
"""

import numpy as np
import pytest

from ocp import Collocation, MultipleShooting, ProblemDefinitionError
from tests.oracles.ocp_suite.problems import bryson_denham


def test_auto_expands_from_the_second_solve_of_a_kind():
    tr = MultipleShooting(bryson_denham(), nodes=8, substeps=1, verify="off")
    first = tr.solve()
    again = tr.solve()
    warm = tr.solve(warm_start=again)
    warm_again = tr.solve(warm_start=warm)
    assert [s.expanded for s in (first, again, warm, warm_again)] == [False, True, False, True]
    assert again.objective == pytest.approx(first.objective, rel=1e-12)
    assert np.max(np.abs(again.x - first.x)) < 1e-9
    assert warm_again.objective == pytest.approx(first.objective, rel=1e-12)


def test_explicit_expand_is_kept_and_cvodes_never_expands():
    kept = [MultipleShooting(bryson_denham(), nodes=4, substeps=1, expand=e,
                             verify="off").solve().expanded for e in (True, False)]
    assert kept == [True, False]
    assert Collocation(bryson_denham(), intervals=4, verify="off").solve().expanded is True
    assert MultipleShooting(bryson_denham(), nodes=4, integrator="cvodes").expand is False


@pytest.mark.parametrize("bad", ["yes", 1, None, "Auto"])
def test_other_expand_values_are_refused(bad):
    with pytest.raises(ProblemDefinitionError, match="expand must be"):
        MultipleShooting(bryson_denham(), nodes=4, expand=bad)
    with pytest.raises(ProblemDefinitionError, match="expand must be"):
        Collocation(bryson_denham(), intervals=4, expand=bad)
