"""CasADi's bundled OpenBLAS (under Ipopt's MUMPS) on one thread unless the user says."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import ocp
from ocp.transcriptions.blas import library_files

BUNDLED = pytest.mark.skipif(not library_files(), reason="this CasADi has no bundled OpenBLAS")
CPUS = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()

ROOT = Path(__file__).resolve().parents[3]
SOLVE_AND_REPORT = f"""
import sys
sys.path.insert(0, {str(ROOT)!r})
import ocp
from tests.oracles.problems import min_time_double_integrator
if len(sys.argv) > 1:
    ocp.set_blas_threads(int(sys.argv[1]))
p = min_time_double_integrator(name="double integrator")
sol = ocp.MultipleShooting(p, nodes=20).solve({{"d": 1.0}})
print(ocp.blas_threads(), round(sol.T, 6))
"""


def run(env_extra: dict[str, str], *args: str) -> list[str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", SOLVE_AND_REPORT, *args], capture_output=True,
                         text=True, check=True, timeout=120, env={**env, **env_extra})
    return out.stdout.split()


@BUNDLED
def test_solves_use_one_blas_thread_unless_the_environment_or_the_user_says():
    # the minimum time of a unit move at |u| <= 1 is 2 (bang-bang)
    assert run({}) == ["1", "2.0"]
    # OpenBLAS caps a count from the environment at the CPUs this process may use
    assert run({"OPENBLAS_NUM_THREADS": "2"}) == [str(min(2, CPUS)), "2.0"]
    assert run({}, "2") == ["2", "2.0"]  # set before the first solve: kept


@BUNDLED
def test_set_blas_threads_changes_the_count():
    before = ocp.blas_threads()
    try:
        assert ocp.set_blas_threads(2) is True and ocp.blas_threads() == 2
    finally:
        ocp.set_blas_threads(before)
    assert ocp.blas_threads() == before


@pytest.mark.parametrize("n", [0, -1, 1.5, True, "2"])
def test_set_blas_threads_refuses_a_bad_count(n):
    with pytest.raises(ValueError, match="positive integer"):
        ocp.set_blas_threads(n)


@BUNDLED
def test_a_count_above_the_cpus_is_capped_at_them():
    """Issue 47, defect 10: 2**32 + 1 gave one thread (a C int overflow) and 10**9 gave
    OpenBLAS's build limit, 16, on 2 CPUs. The rule: at most the CPUs this process may use
    (as OpenBLAS does for OPENBLAS_NUM_THREADS)."""
    before = ocp.blas_threads()
    try:
        for n in (2**32 + 1, 10**9, CPUS + 1):
            assert ocp.set_blas_threads(n) is True and ocp.blas_threads() == CPUS, n
    finally:
        ocp.set_blas_threads(before)
