"""Fixtures shared by the files of tests/ocp: expensive solves done once per test run.

Each is an exact computation that several files did on their own (the same problem built
afresh, the same transcription, the same options): one copy now, read by all. Readers only
read (the one exception: test_ocp_suite.py re-solves the brachistochrone's transcription, an
entry no other file reads), and every shared result is computed from a problem object of its
own, refined by :func:`suite_switching` alone, so no earlier in-process solve (a warm start,
the refinement's NLP cache and its Newton fast path) changes what a reader gets.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import pytest

from ocp import Collocation, MultipleShooting, PathViolationWarning, certify
from ocp.structure.switching import refine_switching
from tests.oracles.ocp_suite import PROBLEMS
from tests.oracles.ocp_suite import problems as P


@pytest.fixture(scope="session")
def suite_refined() -> Callable[[str], Any]:
    """``refined(name)``: the suite problem ``name`` solved by Radau collocation with mesh
    refinement on its own settings (intervals, degree, tolerance, rounds, guess), a path
    violation between the points an error; each problem once per test run (read by
    tests/ocp/test_ocp_suite.py and, for the cannonball, definition/test_scaling_ocp.py)."""
    by_name = {p.name: p for p in PROBLEMS}
    done: dict[str, Any] = {}

    def refined(name: str) -> Any:
        if name not in done:
            sp = by_name[name]
            tr = Collocation(sp.build(), intervals=sp.intervals, degree=sp.degree)
            with warnings.catch_warnings():
                warnings.simplefilter("error", PathViolationWarning)
                done[name] = tr.refine(tol=sp.tol, max_rounds=sp.max_rounds,
                                       guess=sp.guess() if sp.guess else None)
        return done[name]

    return refined


@pytest.fixture(scope="session")
def suite_switching(suite_refined: Callable[[str], Any]) -> Callable[[str], tuple[Any, Any]]:
    """``switching(name)``: the switching-time refinement of a bang-bang suite problem's
    refined solve (default settings) and its certificate, ``(r, certify(sol, r))``, once
    per test run (read by tests/ocp/test_ocp_suite.py and, for the moon lander and the
    oscillator, structure/test_collocation_structure.py). Only this fixture refines the
    suite's solves: each refinement is built on an empty cache and solved by Ipopt."""
    done: dict[str, tuple[Any, Any]] = {}

    def switching(name: str) -> tuple[Any, Any]:
        if name not in done:
            sol = suite_refined(name)
            r = refine_switching(sol)
            done[name] = (r, certify(sol, r))
        return done[name]

    return switching


@pytest.fixture(scope="session")
def moon_lander_shooting() -> tuple[Any, Any, Any]:
    """Meditch's moon lander by multiple shooting on 60 nodes, its switching-time
    refinement with default settings and the certificate of the two (read by
    structure/test_collocation_structure.py and test_ocp_suite_structure.py)."""
    sol = MultipleShooting(P.moon_lander(), nodes=60).solve({})
    r = refine_switching(sol)
    return sol, r, certify(sol, r)
