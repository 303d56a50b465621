"""The exported C controller compiled with the system's C compiler and called through
:mod:`ctypes` (for its check against the Python controller and its benchmark)."""

from __future__ import annotations

import ctypes
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control import foot_filter as ff
from softlanding.control.export_c.writer import SOURCE
from softlanding.errors import ExportError

#: The flags the README gives (C99, no fused multiply-adds: it rounds as numba does).
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off")


def find_compiler() -> list[str] | None:
    """The C compiler's command (``$CC``, else ``cc`` or ``gcc`` on the path), or None."""
    cc = os.environ.get("CC")
    if cc:
        return cc.split() if shutil.which(cc.split()[0]) else None
    found = shutil.which("cc") or shutil.which("gcc")
    return [found] if found else None


def compile_shared(folder: Path, library: Path, extra: tuple[str, ...] = ()) -> Path:
    """Compile the exported files of ``folder`` (and the C files ``extra``) into the shared
    library ``library``.

    Parameters
    ----------
    folder : Path
        Holds the exported files (:func:`~softlanding.control.export_c.writer.write_controller`).
    library : Path
        The library to write.
    extra : tuple of str
        More C files to link in (a benchmark's timing wrapper).

    Returns
    -------
    Path
        ``library``.

    Raises
    ------
    ExportError
        No C compiler, or the code did not compile without a warning (the compiler's
        message).
    """
    cc = find_compiler()
    if cc is None:
        raise ExportError("no C compiler (cc, gcc or $CC) on this system")
    p = subprocess.run([*cc, *CFLAGS, "-Wall", "-Wextra", "-shared", "-fPIC", "-I", str(folder),
                        "-o", str(library), str(Path(folder) / SOURCE), *extra, "-lm"],
                       capture_output=True, text=True)
    if p.returncode != 0 or p.stderr.strip():  # a warning is a defect of the template too
        raise ExportError(f"the exported controller did not compile cleanly with "
                          f"{' '.join(cc)}: {' '.join(p.stderr.split())[:400]}")
    return Path(library)


def _ptr(a: np.ndarray) -> int:
    """The address of ``a``'s data (for a ``double *`` argument)."""
    if a.dtype != np.float64 or not a.flags.c_contiguous:
        raise TypeError("arrays passed to C must be contiguous float64")
    return int(a.ctypes.data)


class CController:
    """The exported controller's functions, called through :mod:`ctypes`.

    Parameters
    ----------
    library : Path
        :func:`compile_shared`'s library.
    """

    def __init__(self, library: Path) -> None:
        self.lib = lib = ctypes.CDLL(str(library))
        d, p, i = ctypes.c_double, ctypes.c_void_p, ctypes.c_int
        lib.sl_control_step.argtypes = [p, p, p, d, d, d, i]
        lib.sl_control_step.restype = i
        lib.sl_solve_plan.argtypes = [p, p, p]
        lib.sl_solve_plan.restype = i
        lib.sl_new_memory.argtypes = [p, d, d, d, d, d, d, d]
        lib.sl_new_memory.restype = None
        lib.sl_force.argtypes = [p, p, d]
        lib.sl_force.restype = d
        lib.sl_force_integrals.argtypes = [p, p, d, p]
        lib.sl_force_integrals.restype = None
        lib.sl_ground_estimate.argtypes = [p, p, p]
        lib.sl_ground_estimate.restype = None
        lib.sl_filter_init.argtypes = [p, p]
        lib.sl_filter_init.restype = None
        lib.sl_filter_step.argtypes = [p, p, d, d, d, d, d, d]
        lib.sl_filter_step.restype = i
        lib.sl_filtered_weight.argtypes = [p, p, p, p, d, d]
        lib.sl_filtered_weight.restype = d
        lib.sl_filtered_step.argtypes = [p, p, p, d, d, d, i, d, ctypes.POINTER(i)]
        lib.sl_filtered_step.restype = i
        self.sensor_noise = float(d.in_dll(lib, "SL_SENSOR_NOISE").value)
        self.robot_numbers = np.ctypeslib.as_array(
            (ctypes.c_double * bb.NP).in_dll(lib, "SL_ROBOT_NUMBERS")).copy()

    def control_step(self, P: np.ndarray, M: np.ndarray, x: np.ndarray, a_f: float, u: float,
                     h: float, estimate: bool) -> int:
        """``sl_control_step`` (as :func:`~softlanding.control.bangbang.control_step`).

        Parameters
        ----------
        P, M : array
            The numbers and the memory, updated in place.
        x : array of 4
            The measured state.
        a_f, u, h : float
            The measured foot acceleration, the force the sample ended under, its length.
        estimate : bool
            Update the estimate.
        """
        return int(self.lib.sl_control_step(_ptr(P), _ptr(M), _ptr(x), a_f, u, h,
                                            int(estimate)))

    def solve_plan(self, P: np.ndarray, M: np.ndarray, x: np.ndarray) -> int:
        """``sl_solve_plan`` (as :func:`~softlanding.control.bangbang.solve_plan`).

        Parameters
        ----------
        P, M : array
            The numbers, the memory (its durations the guess; updated in place).
        x : array of 4
            The state.
        """
        return int(self.lib.sl_solve_plan(_ptr(P), _ptr(M), _ptr(x)))

    def new_memory(self, tau1: float, tau2: float, prior: tuple[float, float],
                   prior_std: tuple[float, float], noise_std: float) -> np.ndarray:
        """``sl_new_memory`` (as :func:`~softlanding.control.bangbang.new_memory`).

        Parameters
        ----------
        tau1, tau2 : float
            The first plan's push and pull durations.
        prior, prior_std : (float, float)
            The estimator's prior ``(K, c_d)`` and its standard deviations.
        noise_std : float
            Standard deviation of one measured ground force.
        """
        M = np.zeros(bb.NM)
        self.lib.sl_new_memory(_ptr(M), tau1, tau2, *prior, *prior_std, noise_std)
        return M

    def force(self, P: np.ndarray, M: np.ndarray, t: float) -> float:
        """``sl_force``: the plan's force ``t`` after the last step.

        Parameters
        ----------
        P, M : array
            The numbers and the memory.
        t : float
            Time after the step.
        """
        return float(self.lib.sl_force(_ptr(P), _ptr(M), t))

    def force_integrals(self, P: np.ndarray, M: np.ndarray, h: float) -> np.ndarray:
        """``sl_force_integrals``: ``int_0^h u dt`` and ``int_0^h (h - t) u dt`` of the
        plan's force after the last step.

        Parameters
        ----------
        P, M : array
            The numbers and the memory.
        h : float
            The sample.
        """
        U = np.zeros(2)
        self.lib.sl_force_integrals(_ptr(P), _ptr(M), h, _ptr(U))
        return U

    def ground_estimate(self, P: np.ndarray, M: np.ndarray) -> np.ndarray:
        """``sl_ground_estimate``: ``[K, c_d, std K, std c_d]`` of the estimate in ``M``.

        Parameters
        ----------
        P, M : array
            The numbers and the memory.
        """
        E = np.zeros(4)
        self.lib.sl_ground_estimate(_ptr(P), _ptr(M), _ptr(E))
        return E

    def filter_init(self, x0: np.ndarray) -> np.ndarray:
        """``sl_filter_init`` (as :func:`~softlanding.control.foot_filter.new_filter`).

        Parameters
        ----------
        x0 : array of 4
            The impact state.
        """
        F = np.zeros(ff.NF)
        self.lib.sl_filter_init(_ptr(F), _ptr(np.ascontiguousarray(x0, float)))
        return F

    def filter_step(self, F: np.ndarray, x: np.ndarray, g: float, U1: float, U2: float,
                    h: float, beta: float, noise: float) -> int:
        """``sl_filter_step`` (as :func:`~softlanding.control.foot_filter.filter_step`): ``F``
        and ``x`` updated in place; 1 if the innovation check widened the prediction, else
        0; ``SL_REFUSED`` (-1), nothing changed, for a non-finite input.

        Parameters
        ----------
        F : array
            The filter's memory.
        x : array of 4
            The measured state (its foot's entries replaced by the filter's).
        g, U1, U2, h, beta, noise : float
            As :func:`~softlanding.control.foot_filter.filter_step`.
        """
        return int(self.lib.sl_filter_step(_ptr(F), _ptr(x), g, U1, U2, h, beta, noise))

    def filtered_weight(self, P: np.ndarray, M: np.ndarray, F: np.ndarray, x: np.ndarray,
                        a_f: float, u: float) -> float:
        """``sl_filtered_weight`` (as :func:`~softlanding.control.recovery.sample_weight`).

        Parameters
        ----------
        P, M : array
            The numbers and the memory before the step.
        F : array
            The filter's memory after the sample's filter step.
        x : array of 4
            The filtered state.
        a_f, u : float
            The measured foot acceleration, the force the sample ended under.
        """
        return float(self.lib.sl_filtered_weight(_ptr(P), _ptr(M), _ptr(F), _ptr(x), a_f, u))

    def filtered_step(self, P: np.ndarray, M: np.ndarray, x: np.ndarray, a_f: float,
                      u: float, h: float, estimate: bool, weight: float, recovering: int
                      ) -> tuple[int, int]:
        """``sl_filtered_step`` (as :func:`~softlanding.control.recovery.filtered_step`): the
        status and the new count of samples the recovery has gone on over.

        Parameters
        ----------
        P, M, a_f, u, h, estimate
            As for :meth:`control_step`.
        x : array of 4
            The filtered state.
        weight : float
            The sample's weight.
        recovering : int
            Samples the recovery has gone on over so far.
        """
        n = ctypes.c_int(recovering)
        st = self.lib.sl_filtered_step(_ptr(P), _ptr(M), _ptr(x), a_f, u, h, int(estimate),
                                       weight, ctypes.byref(n))
        return int(st), int(n.value)


__all__ = ["CFLAGS", "CController", "compile_shared", "find_compiler"]
