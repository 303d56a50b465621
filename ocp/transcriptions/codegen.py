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
leaves nothing a later run would load. Beside each library a small record
(``nlp-<key>.json``) holds its size and SHA-256; a library that does not match its record (a
disk error, a copy cut short, a file emptied by hand) or has none is compiled again before it
is loaded: loading a damaged library would kill the process (a truncated one with a bus
error).
"""

from __future__ import annotations

import hashlib
import json
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
        If there is none (``codegen=True`` cannot apply), or ``$CC`` cannot be read as a
        command (an unclosed quote).
    """
    env = os.environ.get("CC")
    if env and env.strip():
        try:
            return shlex.split(env)
        except ValueError as err:  # CC='"': shlex's bare "No closing quotation"
            raise ProblemDefinitionError(f"codegen=True: $CC={env!r} is not a command "
                                         f"({str(err).lower()})") from None
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


def file_record(path: Path) -> dict[str, object]:
    """What is recorded beside a cached library: its size and SHA-256.

    Parameters
    ----------
    path : Path
        The library.
    """
    data = path.read_bytes()
    return {"size": len(data), "sha256": hashlib.sha256(data).hexdigest()}


def record_path(lib: Path) -> Path:
    """The record of ``lib`` (``nlp-<key>.json`` beside ``nlp-<key>.so``).

    Parameters
    ----------
    lib : Path
        The library.
    """
    return lib.with_suffix(".json")


def intact(lib: Path) -> bool:
    """Whether the cached ``lib`` is the library its record describes (size, then hash).

    False when either file is missing or unreadable, or they disagree: the library must be
    compiled again before anything loads it.

    Parameters
    ----------
    lib : Path
        The library.
    """
    try:
        rec = json.loads(record_path(lib).read_text())
        if not isinstance(rec, dict) or lib.stat().st_size != rec.get("size"):
            return False  # the cheap test first: a truncated or emptied library
        return file_record(lib) == rec
    except (OSError, ValueError):
        return False


def _cache_folder() -> Path:
    """:func:`cache_dir`, created; a folder that cannot hold the cache is one clear error."""
    folder = cache_dir()
    where = "$OCP_CODEGEN_DIR" if os.environ.get("OCP_CODEGEN_DIR") else "the cache folder"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not os.access(folder, os.R_OK | os.W_OK | os.X_OK):
            raise PermissionError(13, "Permission denied (not readable and writable)")
    except OSError as err:  # a file, a read-only or unreadable folder, a bad path
        why = err.strerror or str(err)
        raise ProblemDefinitionError(f"codegen=True: {where} {str(folder)!r} cannot hold the "
                                     f"compiled libraries: {why}") from None
    return folder


def _compile(cc: list[str], source: Path, built: Path) -> None:
    """Compile ``source`` to the shared library ``built`` (one clear error on failure)."""
    try:
        run = subprocess.run([*cc, *OPT_FLAGS, "-fPIC", "-shared", str(source), "-o",
                              str(built), "-lm"], capture_output=True, text=True)
    except OSError as err:  # $CC names no program, or not an executable one
        raise ProblemDefinitionError(f"codegen=True: cannot run the C compiler "
                                     f"{cc[0]!r}: {err.strerror or err}") from None
    if run.returncode != 0:
        first = (run.stderr.strip().splitlines() or ["(no message)"])[0]
        raise ProblemDefinitionError(f"codegen=True: the C compiler failed: {first}")


def place(built: Path, lib: Path) -> None:
    """Move the compiled ``built`` to ``lib`` and write its record (:func:`record_path`),
    each in one step: a reader sees a whole file or none, and a library without its record
    is compiled again (:func:`intact`).

    Parameters
    ----------
    built : Path
        The library just compiled (on the same file system as ``lib``).
    lib : Path
        Where it is kept.
    """
    rec = lib.with_name(f".{lib.stem}.{os.getpid()}.json.partial")
    try:
        rec.write_text(json.dumps(file_record(built)))
        os.replace(built, lib)
        os.replace(rec, record_path(lib))
    finally:
        rec.unlink(missing_ok=True)


def compiled_library(solver: ca.Function) -> Path:
    """The shared library of the NLP functions of ``solver`` (an ``nlpsol``), compiled
    unless the cache has it intact.

    Parameters
    ----------
    solver : casadi.Function
        The NLP solver whose functions are compiled.

    Returns
    -------
    Path
        The library, for ``casadi.nlpsol(name, "ipopt", str(path), opts)``, checked
        against its record (:func:`intact`).

    Raises
    ------
    ProblemDefinitionError
        Without a C compiler, when the compiler fails (its first error line), or when the
        cache folder cannot be used.
    """
    cc = compiler()
    folder = _cache_folder()
    try:
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
            if not intact(lib):  # missing, or damaged: loading it could kill the process
                built = Path(tmp) / "ocp_nlp.so"
                _compile(cc, source, built)
                place(built, lib)
    except OSError as err:  # the folder changed under us (removed, made read-only, full)
        raise ProblemDefinitionError(f"codegen=True: cannot write the compiled library in "
                                     f"{str(folder)!r}: {err.strerror or err}") from None
    return lib
