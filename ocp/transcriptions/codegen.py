"""Compiled NLP functions: CasADi's generated C, built by the system C compiler, cached on disk.

A transcription built with ``codegen=True`` hands Ipopt the NLP's functions (objective,
constraints, their derivatives and the Lagrangian's Hessian) as machine code instead of
CasADi's virtual machines. The C is generated from the transcription's own solver, so the
functions are the same expressions; only their evaluation differs (rounding: results agree
to the last digits, not bit for bit). Compiling costs seconds to a minute (the soft landing
at N = 100: 9 MB of C, about a minute at ``-O1``), so it pays for problems that are solved
many times (sweeps, re-solves, MPC), not for one solve.

The shared library is cached under :func:`cache_dir`, named by the SHA-256 of the generated
source, the compiler command and CasADi's version: the same NLP in a later process (or
another transcription of it) loads it without compiling. Each library is compiled in a
temporary file beside its final name and moved there in one step, so an interrupted compile
leaves nothing a later run would load.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
import tempfile
from importlib.metadata import version
from pathlib import Path

import casadi as ca

from ..definition.errors import ProblemDefinitionError

#: The functions Ipopt's CasADi interface takes from a compiled library (besides the NLP
#: itself, the solver's oracle).
NLP_FUNCTIONS = ("nlp_f", "nlp_g", "nlp_grad", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l")

#: Optimisation flag: ``-O1`` compiles CasADi's long straight-line code several times
#: faster than ``-O2`` for about the same speed; ``-O0`` code is no faster than CasADi's
#: virtual machine (measured on the soft landing, N = 100).
OPT_FLAGS = ("-O1",)


def cache_dir() -> Path:
    """Where compiled NLP libraries are kept: ``$OCP_CODEGEN_DIR``, else
    ``$XDG_CACHE_HOME/ocp/codegen`` (``~/.cache/ocp/codegen``).

    Returns
    -------
    Path
    """
    env = os.environ.get("OCP_CODEGEN_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ocp" / "codegen"


def compiler() -> list[str]:
    """The C compiler command: ``$CC`` if set, else the first of ``cc``, ``gcc``, ``clang``
    on the path.

    Raises
    ------
    ProblemDefinitionError
        If there is none (``codegen=True`` cannot apply).
    """
    env = os.environ.get("CC")
    if env:
        return shlex.split(env)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return [found]
    raise ProblemDefinitionError("codegen=True needs a C compiler (cc, gcc or clang on the "
                                 "path, or $CC); none found")


def has_compiler() -> bool:
    """Whether :func:`compiler` finds a C compiler."""
    try:
        compiler()
    except ProblemDefinitionError:
        return False
    return True


def compiled_library(solver: ca.Function) -> Path:
    """The shared library of the NLP functions of ``solver`` (an ``nlpsol``), compiled
    unless the cache has it.

    Parameters
    ----------
    solver : casadi.Function
        The NLP solver whose functions are compiled.

    Returns
    -------
    Path
        The library, for ``casadi.nlpsol(name, "ipopt", str(path), opts)``.

    Raises
    ------
    ProblemDefinitionError
        Without a C compiler, or when the compiler fails (its first error line).
    """
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    cc = compiler()
    with tempfile.TemporaryDirectory(dir=folder, prefix=".gen-") as tmp:
        gen = ca.CodeGenerator("ocp_nlp.c", {"with_header": False})
        gen.add(solver.oracle())  # "nlp": (x, p) -> (f, g), which the library is named by
        for fname in NLP_FUNCTIONS:
            gen.add(solver.get_function(fname))
        gen.generate(tmp + os.sep)
        source = Path(tmp) / "ocp_nlp.c"
        key = hashlib.sha256(source.read_bytes())
        key.update(repr((cc, OPT_FLAGS, version("casadi"))).encode())
        lib = folder / f"nlp-{key.hexdigest()[:32]}.so"
        if not lib.exists():
            built = Path(tmp) / "ocp_nlp.so"
            try:
                run = subprocess.run([*cc, *OPT_FLAGS, "-fPIC", "-shared", str(source), "-o",
                                      str(built), "-lm"], capture_output=True, text=True)
            except OSError as err:  # $CC names no program
                raise ProblemDefinitionError(f"codegen=True: cannot run the C compiler "
                                             f"{cc[0]!r}: {err.strerror}") from None
            if run.returncode != 0:
                first = (run.stderr.strip().splitlines() or ["(no message)"])[0]
                raise ProblemDefinitionError(f"codegen=True: the C compiler failed: {first}")
            os.replace(built, lib)  # one step: a reader sees the whole library or none
    return lib
