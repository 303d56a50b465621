"""The first run of a fresh install: the simulator says on stderr, once and before it starts,
that it is compiling, and only when numba's cache is cold (issue 24)."""

import json
import os
import subprocess
import sys

import pytest

NOTICE = "softlanding: compiling the simulator"
CHECK = ("from softlanding.simulation import kernel as K\n"
         "first, again = K.compile_notice(), K.compile_notice()\n"
         "K.compile_notice('non-affine')\n"
         "print(first is not None, again is None)")


def _run(args, cache_dir=None):
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          timeout=600, check=True)


def test_the_notice_is_printed_on_a_cold_cache_once_per_kind(tmp_path):
    p = _run(["-c", CHECK], cache_dir=tmp_path)  # an empty cache: nothing compiled yet
    lines = p.stderr.splitlines()
    assert lines == [f"{NOTICE} (once, about 10 s)...",
                     f"{NOTICE} for non-affine grounds (once, about 15 s)..."], p.stderr
    assert p.stdout.split() == ["True", "True"]  # returned when printed; once per process


def test_no_notice_once_compiled():
    from softlanding import Impact, Impedance, Robot, simulate

    simulate(Robot(5, 20), Impact(-1.0), Impedance(0.2, 0.18))  # compiled, cached on disk
    p = _run(["-c", "from softlanding.simulation import kernel as K\n"
                    "print(K.compile_notice())"])
    assert p.stderr == "" and p.stdout.strip() == "None"


@pytest.mark.slow
def test_a_cold_demo_says_so_on_stderr_first_and_a_warm_one_says_nothing(tmp_path):
    """End to end in a fresh cache (compiles the exact simulator: ~10 s)."""
    cold = _run(["-m", "softlanding", "demo", "--json", "--out", ""], cache_dir=tmp_path)
    assert cold.stderr.startswith(NOTICE) and cold.stderr.count("\n") == 1, cold.stderr
    warm = _run(["-m", "softlanding", "demo", "--json", "--out", ""], cache_dir=tmp_path)
    assert warm.stderr == ""
    assert json.loads(warm.stdout) == json.loads(cold.stdout)  # stdout is the JSON alone
