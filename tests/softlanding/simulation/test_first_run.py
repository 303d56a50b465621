"""The first run of a fresh install: the simulator says on stderr, once and before it starts,
that it is compiling, only when numba compiles (issue 24), with a bar on a terminal; a demo
compiles the lite kernel only, not the creep and hop proofs it never needs, and the demo
command on an empty cache compiles nothing (issue 47)."""

import json
import os
import subprocess
import sys

import numba
import pytest

from softlanding.simulation import kernel as K

NOTICE = "softlanding: compiling the simulator"


def _run(args, cache_dir=None):
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = str(cache_dir)
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          timeout=600, check=True)


def test_the_notice_is_printed_when_numba_compiles_once_per_kind(monkeypatch, capsys):
    monkeypatch.setattr(K, "_CHECKED", set())
    fresh = numba.njit(lambda x: x + 1)  # not compiled yet
    with K.first_compile("affine") as first:
        fresh(1)  # a compile: the notice, at its start
    with K.first_compile("affine") as again:
        fresh(2.0)  # watched once per kind and process
    with K.first_compile("proofs") as nothing:
        fresh(3)  # compiled already: no notice
    err = capsys.readouterr().err
    assert err.splitlines() == [f"{NOTICE} (once, about 10 s)..."], err
    assert first.notice == err.strip() and again is None and nothing.notice is None


def test_the_bar_counts_the_functions_compiled_on_a_terminal(monkeypatch, capsys):
    from softlanding.util import progress

    monkeypatch.setattr(K, "_CHECKED", set())
    monkeypatch.setattr(progress, "FORCE", True)  # as --progress: a bar without a terminal
    fresh = numba.njit(lambda x: 2 * x)
    with K.first_compile("proofs") as watch:
        fresh(1)
    err = capsys.readouterr().err
    assert err.startswith(f"{NOTICE}'s creep and hop proofs (once, about 5 s)...\n")
    assert "compiling" in err.split("\n", 1)[1] and "function" in err
    assert watch.bar.n >= 1


def test_no_notice_once_compiled():
    from softlanding import Impact, Impedance, Robot, simulate

    simulate(Robot(5, 20), Impact(-1.0), Impedance(0.2, 0.18))  # compiled, cached on disk
    p = _run(["-c", "from softlanding import Impact, Impedance, Robot, simulate\n"
                    "print(simulate(Robot(5, 20), Impact(-1.0), Impedance(0.2, 0.18)).steps)"])
    assert p.stderr == "" and p.stdout.strip() == "2"


COMPILED = """
import json
from numba.core import event
from softlanding.report.demo import demo_table, stepped_intrusions
with event.install_recorder("numba:compile") as rec:
    demo_table(), stepped_intrusions()
print(json.dumps(sorted({e.data["dispatcher"].py_func.__qualname__ for _, e in rec.buffer})))
"""


@pytest.mark.slow
def test_a_cold_demo_runs_python_then_compiles_only_what_it_needs(tmp_path):
    """On an empty cache the demo command runs the kernel as Python: nothing compiled, nothing
    said. A first compile of the demo's landings never compiles the proofs (they were a third
    of the first demo's compile); the demo command then runs compiled, with the same numbers
    to the last bit."""
    demo = ["-m", "softlanding", "demo", "--json", "--out", ""]
    cold = _run(demo, cache_dir=tmp_path)
    assert cold.stderr == "" and not list(tmp_path.rglob("*.nbi")), cold.stderr
    p = _run(["-c", COMPILED], cache_dir=tmp_path)
    compiled = set(json.loads(p.stdout))
    assert "simulate_one" in compiled and "creep_candidate" in compiled
    assert not compiled & {"creep_proof", "creep_setup", "det_inv3", "hops_settled",
                           "first_symmetric_hop", "threshold_energy", "limit_depth"}, compiled
    assert p.stderr.splitlines() == [f"{NOTICE} (once, about 10 s)..."]
    warm = _run(demo, cache_dir=tmp_path)
    assert warm.stderr == ""  # compiled (cached): no compile notice
    cold, warm = json.loads(cold.stdout), json.loads(warm.stdout)  # stdout is the JSON alone
    assert (cold.pop("simulator"), warm.pop("simulator")) == ("python", "compiled")
    assert warm == cold
