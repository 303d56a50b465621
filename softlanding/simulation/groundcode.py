"""A ground model as the compiled kernel takes it: parameter vector and C law.

Built-in models (:class:`~softlanding.model.ground.LinearGround`, :class:`DragGround`,
:class:`AddedMassGround`) are a few numbers evaluated in closed form inside the kernel
(:mod:`softlanding.simulation.kernel.groundlaw`). Any other ground model (a :class:`CustomGround`)
is turned into C by CasADi's code generator from its own ``yield_force`` and
``added_mass`` expressions, compiled once with the system's C compiler (``cc``, or
``$CC``), cached on disk by the hash of the generated code (``$SOFTLANDING_CACHE`` or
``~/.cache/softlanding``), loaded with ctypes and handed to the kernel as a function
pointer: the kernel is not recompiled per law.

The cache is bounded (:data:`LAW_CACHE_MAX_FILES` laws, :data:`LAW_CACHE_MAX_BYTES`): a new
law evicts the least recently used ones (``softlanding cache`` shows it, ``--clear`` empties
it). Each law's size and SHA-256 are recorded beside it and checked before it is loaded
(:func:`ocp.transcriptions.codegen.intact`): a damaged one is compiled again, where loading
it would kill the process. Without a C compiler the law is evaluated in Python instead (a
ctypes callback of the same CasADi function): the same numbers, 60 to 100 times slower
(``benchmarks/bench_law_fallback.py``: 400 drag landings at K = 2, 0.17 s CPU compiled with
the compiler's time, 10.2 s in Python).
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ocp.transcriptions.codegen import intact, place, record_path
from softlanding.errors import ParameterError
from softlanding.model.ground import AddedMassGround, DragGround, Ground, LinearGround

_LIBS: dict[str, Any] = {}  # keep the loaded laws (and Python callbacks) alive
LAW_CACHE_MAX_FILES = 256
"""Most compiled laws kept on disk (about 16 kB each); the least recently used go first."""
LAW_CACHE_MAX_BYTES = 32 * 2**20
"""Most bytes of compiled laws kept on disk."""
_LAW_FN = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double, ctypes.POINTER(ctypes.c_double))
_LAW_ERRORS: list[BaseException] = []  # raised by a Python law: re-raised after the kernel
_NOTICE: list[str] = []

_WRAPPER = """
void sl_law(double d, double v, double *out) {{
  const casadi_real *arg[{n_arg}];
  casadi_real *res[{n_res}];
  casadi_real w[{n_w}];
  casadi_int iw[{n_iw}];
  int i;
  arg[0] = &d; arg[1] = &v;
  for (i = 0; i < 5; ++i) res[i] = out + i;
  sl_law_core(arg, res, iw, w, 0);
}}
"""


def hold_stiffness(ground: Ground) -> float | None:
    """``K`` if the crater's static hold is ``f(d, 0) = K d`` with a constant ``K > 0`` (the
    exact kernel's rule: it holds support forces up to ``K d``), else None.

    Parameters
    ----------
    ground : Ground
        The ground model.
    """
    if isinstance(ground, LinearGround | DragGround):
        return ground.stiffness
    if isinstance(ground, AddedMassGround):
        return 1.0
    import casadi as ca

    d = ca.SX.sym("d")
    hold = ca.SX(ground.yield_force(d, 0.0))
    slope = ca.jacobian(hold, d)
    if ca.depends_on(slope, d) or not ca.simplify(hold - slope * d).is_zero():
        return None
    k = float(ca.evalf(slope))
    return k if k > 0.0 else None


def needs_integration(ground: Ground) -> bool:
    """True if the ground's landings are integrated (not on the exact matrix-exponential path):
    its law is not affine, or its crater's hold is not proportional to the depth.

    Parameters
    ----------
    ground : Ground
        The ground model.
    """
    return not ground.is_affine or hold_stiffness(ground) is None


def law_expressions(ground: Ground) -> Any:
    """The CasADi function ``(d, v) -> (f, m_a, m_a', f(d, 0), drag)`` of a ground model.

    ``drag = f - f(d, 0) - m_a'(d) v^2``: the bed's rate-dependent force (the grains'
    momentum flux taken out).

    Parameters
    ----------
    ground : Ground
        The ground model.
    """
    import casadi as ca

    d, v = ca.SX.sym("d"), ca.SX.sym("v")
    f = ca.SX(ground.yield_force(d, v))
    ma = ca.SX(ground.added_mass(d))
    dma = ca.jacobian(ma, d)
    hold = ca.SX(ground.yield_force(d, 0.0))
    return ca.Function("sl_law_core", [d, v], [f, ma, dma, hold, f - hold - dma * v**2])


def _compiler() -> str | None:
    """The C compiler (``$CC``, else ``cc`` or ``gcc`` on the path), or None if there is none."""
    cc = os.environ.get("CC")
    if cc:
        return shutil.which(cc.split()[0]) and cc
    return shutil.which("cc") or shutil.which("gcc")


def law_cache_dir(create: bool = True) -> Path:
    """The folder of the compiled laws (``$SOFTLANDING_CACHE/laws``, else
    ``~/.cache/softlanding/laws``).

    Parameters
    ----------
    create : bool
        Create it if missing.
    """
    root = os.environ.get("SOFTLANDING_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "softlanding")
    path = Path(root) / "laws"
    if create:
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as err:  # a file, a read-only or unreadable place
            where = "$SOFTLANDING_CACHE" if os.environ.get("SOFTLANDING_CACHE") else "cache"
            raise ParameterError(where, f"{path} cannot hold the compiled ground laws: "
                                        f"{err.strerror or err}") from None
    return path


def _cached_laws(folder: Path) -> list[tuple[float, int, Path]]:
    out = []
    for p in folder.glob("law_*"):
        try:
            st = p.stat()
        except OSError:  # removed meanwhile (another process pruning)
            continue
        out.append((st.st_mtime, st.st_size, p))
    return sorted(out)


def law_cache_info() -> dict[str, Any]:
    """What the compiled-law cache holds.

    Returns
    -------
    dict
        ``path``, ``laws`` (how many), ``bytes``, and the bounds ``max_laws``, ``max_bytes``.
    """
    folder = law_cache_dir(create=False)
    laws = _cached_laws(folder) if folder.is_dir() else []
    return {"path": str(folder), "laws": sum(p.suffix == ".so" for _, _, p in laws),
            "bytes": sum(size for _, size, _ in laws), "max_laws": LAW_CACHE_MAX_FILES,
            "max_bytes": LAW_CACHE_MAX_BYTES}


def clear_law_cache() -> int:
    """Remove every compiled law from the disk cache (laws loaded by this process stay loaded).

    Returns
    -------
    int
        How many laws were removed.
    """
    folder = law_cache_dir(create=False)
    n = 0
    for _, _, p in _cached_laws(folder) if folder.is_dir() else []:
        try:
            p.unlink()
        except FileNotFoundError:
            continue
        n += p.suffix == ".so"
    return n


def prune_law_cache(keep: Path | None = None) -> int:
    """Evict the least recently used laws until the cache is within its bounds.

    Parameters
    ----------
    keep : Path, optional
        A law never evicted (the one just compiled).

    Returns
    -------
    int
        How many files were removed.
    """
    laws = [x for x in _cached_laws(law_cache_dir()) if x[2] != keep]
    count = sum(p.suffix == ".so" for _, _, p in laws) + (keep is not None)
    size = sum(s for _, s, _ in laws) + (keep.stat().st_size if keep is not None else 0)
    removed = 0
    for _, s, p in laws:  # oldest first
        if count <= LAW_CACHE_MAX_FILES and size <= LAW_CACHE_MAX_BYTES:
            break
        try:
            p.unlink()
        except FileNotFoundError:
            pass
        count, size, removed = count - (p.suffix == ".so"), size - s, removed + 1
    return removed


def _python_law(ground: Ground) -> tuple[Any, int]:
    """The law as a ctypes callback of its CasADi function: no C compiler needed, slower."""
    if not _NOTICE:
        _NOTICE.append("shown")
        print("softlanding: no C compiler (cc, gcc or $CC): this ground's law runs in Python, "
              "60 to 100 times slower", file=sys.stderr)
    fun = law_expressions(ground).expand()

    def law(d: float, v: float, out: Any) -> None:
        try:
            for i, x in enumerate(fun(d, v)):
                out[i] = float(x)
        except BaseException as exc:  # noqa: BLE001 - a callback cannot raise: kept for later
            _LAW_ERRORS.append(exc)
            for i in range(5):
                out[i] = float("nan")

    cb = _LAW_FN(law)
    _LIBS[f"python:{id(cb)}"] = cb
    return cb, ctypes.cast(cb, ctypes.c_void_p).value or 0


def raise_law_errors() -> None:
    """Raise the first error a Python-evaluated law met (a Ctrl-C, say) during the last run.

    Raises
    ------
    BaseException
        That error (the kernel could not be stopped by it: the law returned NaN instead).
    """
    if _LAW_ERRORS:
        exc = _LAW_ERRORS[0]
        _LAW_ERRORS.clear()
        raise exc


def law_source(ground: Ground) -> str:
    """The C source of a ground model's law (CasADi's code and the kernel's wrapper); its
    hash names the compiled library.

    Parameters
    ----------
    ground : Ground
        The ground model.
    """
    fun = law_expressions(ground)
    with tempfile.TemporaryDirectory() as tmp:
        cg_name = "sl_law_gen.c"
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            fun.generate(cg_name, {"with_header": False, "casadi_real": "double"})
        finally:
            os.chdir(cwd)
        return (Path(tmp) / cg_name).read_text() + _WRAPPER.format(
            n_arg=max(2, fun.sz_arg()), n_res=max(5, fun.sz_res()), n_w=max(1, fun.sz_w()),
            n_iw=max(1, fun.sz_iw()))


def compile_law(ground: Ground) -> tuple[ctypes.CDLL, int]:
    """Generate, compile (once: cached on disk) and load the C law of a ground model.

    Parameters
    ----------
    ground : Ground
        The ground model (its ``yield_force`` and ``added_mass`` must accept CasADi
        symbols).

    Returns
    -------
    lib : ctypes.CDLL or ctypes callback
        The loaded library, or without a C compiler the Python callback (kept alive by this
        module).
    address : int
        Address of ``void sl_law(double d, double v, double *out)``.
    """
    src = law_source(ground)
    key = hashlib.sha256(src.encode()).hexdigest()[:20]
    so = law_cache_dir() / f"law_{key}.so"
    if str(so) in _LIBS:
        return _LIBS[str(so)], ctypes.cast(_LIBS[str(so)].sl_law, ctypes.c_void_p).value or 0
    if intact(so):  # size and hash as recorded: a damaged library would kill the process
        with contextlib.suppress(FileNotFoundError):  # (evicted meanwhile: loaded below)
            os.utime(so)  # used now: the last to be evicted
            os.utime(record_path(so))
    else:
        cc = _compiler()
        if cc is None:
            return _python_law(ground)
        with tempfile.TemporaryDirectory() as tmp:
            c_file = Path(tmp) / f"law_{key}.c"
            c_file.write_text(src)
            tmp_so = so.with_name(f".law_{key}.{os.getpid()}.so.partial")
            try:
                p = subprocess.run([*cc.split(), "-O2", "-shared", "-fPIC", "-o", str(tmp_so),
                                    str(c_file), "-lm"], capture_output=True, text=True)
                if p.returncode != 0:
                    raise ParameterError("ground", f"the C code of the ground law "
                                                   f"{ground.name!r} did not compile: "
                                                   f"{p.stderr.strip()[:300]}")
                place(tmp_so, so)
            finally:
                tmp_so.unlink(missing_ok=True)
        prune_law_cache(keep=so)
    lib = ctypes.CDLL(str(so))
    _LIBS[str(so)] = lib
    return lib, ctypes.cast(lib.sl_law, ctypes.c_void_p).value or 0


class _LawPointer:
    """A C law for the kernel (numba's wrapper-address protocol)."""

    def __init__(self, address: int) -> None:
        self.address = address

    def __wrapper_address__(self) -> int:
        return self.address

    def signature(self) -> Any:
        from softlanding.simulation.kernel.groundlaw import LAW_SIG

        return LAW_SIG


def _law_pointer(ground: Ground) -> Any:
    from numba import types

    class Wap(_LawPointer, types.WrapperAddressProtocol):
        pass

    return Wap(compile_law(ground)[1])


@lru_cache(maxsize=64)
def _custom_pointer(ground: Ground) -> Any:
    return _law_pointer(ground)


def kernel_law(ground: Ground, r_m: float, *, lock: bool = False,
               u_max: float = np.inf) -> tuple[np.ndarray, Any]:
    """``(G, fp)``: the kernel's parameter vector and law pointer of a ground model.

    Parameters
    ----------
    ground : Ground
        The ground model.
    r_m : float
        Mass ratio.
    lock : bool
        A rigid leg (see :func:`softlanding.simulation.kernel.groundlaw.pack_ground`).
    u_max : float
        The lock's force limit.
    """
    from softlanding.simulation.kernel.groundlaw import no_custom_law, pack_ground

    if isinstance(ground, LinearGround | DragGround) and ground.stiffness != 1.0:
        # the integrator's built-in laws are the paper's spring: another stiffness is
        # compiled from the ground's own law, like a user's (the exact path reads K off
        # the mode matrices)
        G = pack_ground(0.0, 0.0, 0.0, 1.0, r_m, custom=True, lock=lock, u_max=u_max)
        return G, _custom_pointer(ground)
    if isinstance(ground, LinearGround):
        return pack_ground(0.0, 0.0, 0.0, 1.0, r_m, lock=lock, u_max=u_max), no_custom_law
    if isinstance(ground, DragGround):
        return pack_ground(ground.c_d, 0.0, 0.0, 1.0, r_m, lock=lock,
                           u_max=u_max), no_custom_law
    if isinstance(ground, AddedMassGround):
        return pack_ground(ground.c_d, ground.pi_a, ground.radius, ground.kappa, r_m,
                           lock=lock, u_max=u_max), no_custom_law
    G = pack_ground(0.0, 0.0, 0.0, 1.0, r_m, custom=True, lock=lock, u_max=u_max)
    return G, _custom_pointer(ground)


__all__ = ["LAW_CACHE_MAX_BYTES", "LAW_CACHE_MAX_FILES", "clear_law_cache", "compile_law",
           "hold_stiffness", "kernel_law", "law_cache_dir", "law_cache_info", "law_expressions",
           "law_source", "needs_integration", "prune_law_cache", "raise_law_errors"]
