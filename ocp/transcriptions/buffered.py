"""CasADi Functions called on numpy arrays without CasADi's argument conversions.

Calling a CasADi Function from Python converts every numpy argument to a ``DM`` and every
result back (measured: 20-70 us per array of ~100 entries, about 300 us of a 1-iteration
warm Ipopt re-solve of 2.7 ms). :class:`BufferedCall` evaluates through CasADi's
``FunctionBuffer`` instead: the arrays' memory is handed to the Function as it is, the
results written into fresh numpy arrays -- the same evaluation, the same numbers.

It falls back to the ordinary call where the buffer cannot serve: a Function with a
sparse input or output, a call from a second thread while the first is inside, an
evaluation that returns an error code or in which Python raised an exception (the
ordinary call then handles it as CasADi does; an exception the ordinary call does not raise
again, a signal handler's, is raised as it is). :meth:`BufferedCall.stats` is the calling
thread's last evaluation's, read as it ends (in the buffer's memory, under its lock; on the
ordinary call, CasADi's ``Function.stats``, which another thread's ordinary call of the same
Function may replace meanwhile: CasADi's own limit). CasADi's messages during an evaluation
are logged, not printed (:mod:`.solver_output`). One difference: an interruption (Ctrl-C,
SIGTERM as the CLI turns it into one) inside the evaluation is raised as it is, where
CasADi's call turns it into a failed evaluation (Ipopt's ``NonIpopt_Exception_Thrown``).
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from typing import Any

import casadi as ca
import numpy as np

from .solver_output import solver_output


class BufferedCall:
    """A CasADi Function evaluated on numpy arrays through its ``FunctionBuffer``.

    Parameters
    ----------
    f : casadi.Function
        The Function (dense inputs and outputs; otherwise every call is the ordinary one).

    Attributes
    ----------
    f : casadi.Function
        The Function.
    """

    def __init__(self, f: ca.Function) -> None:
        self.f = f
        self.names_in = [f.name_in(i) for i in range(f.n_in())]
        self.names_out = [f.name_out(i) for i in range(f.n_out())]
        self.shapes_in = [f.size_in(i) for i in range(f.n_in())]
        self.sizes_out = [f.nnz_out(i) for i in range(f.n_out())]
        dense = all(f.sparsity_in(i).is_dense() for i in range(f.n_in())) and \
            all(f.sparsity_out(i).is_dense() for i in range(f.n_out()))
        self.defaults = [np.full(f.nnz_in(i), f.default_in(i)) for i in range(f.n_in())]
        # the buffer holds the evaluation's memory; its arguments point into our arrays
        self.buffer: Any = None
        self.evaluate: Any = None
        if dense:
            self.buffer, self.evaluate = f.buffer()
        self.lock = threading.Lock()
        # each thread's last statistics, read as its evaluation ends (another thread may
        # take the buffer as soon as the lock is released)
        self.local = threading.local()

    def _flat(self, i: int, a: Any) -> np.ndarray:
        """Input ``i``'s nonzeros (column-major); a column vector given for an input of
        several columns is repeated across them, as CasADi's call repeats it."""
        r, c = self.shapes_in[i]
        if a is None:
            return self.defaults[i]
        v = np.asarray(a, dtype=float)
        if v.size == 1:  # a scalar fills the input, as CasADi's call spreads it
            return np.full(r * c, float(v.ravel()[0]))
        if v.ndim == 2 and v.shape == (r, c):
            return np.ascontiguousarray(v.ravel(order="F"))
        if v.size == r * c and (r == 1 or c == 1):  # a vector, as a row or a column
            return np.ascontiguousarray(v.ravel())
        if v.size == r and c > 1 and (v.ndim <= 1 or v.shape == (r, 1)):
            return np.tile(v.ravel(), c)
        raise ValueError(f"input {self.names_in[i]!r} of {self.f.name()}: shape {v.shape}, "
                         f"expected {(r, c)}")

    def __call__(self, *args: Any) -> list[np.ndarray]:
        """Evaluate at positional inputs (numpy arrays in the inputs' shapes, or None for
        an input's default); the outputs as flat arrays of their nonzeros (column-major).

        Parameters
        ----------
        *args : array_like or None
            One per input.
        """
        with solver_output():  # CasADi's messages (NaN in an evaluation, ...): logged
            return self._call(args)

    def _call(self, args: Sequence[Any]) -> list[np.ndarray]:
        if self.buffer is None or not self.lock.acquire(blocking=False):
            return self._ordinary(args)
        try:
            ins = [self._flat(i, a) for i, a in enumerate(args)]
            outs = [np.empty(n) for n in self.sizes_out]
            for i, v in enumerate(ins):
                self.buffer.set_arg(i, v.data)
            for i, o in enumerate(outs):
                self.buffer.set_res(i, o.data)
            try:
                self.evaluate()
            except SystemError as exc:  # Python raised inside the evaluation
                cause = exc.__cause__
                if isinstance(cause, BaseException) and not isinstance(cause, Exception):
                    raise cause from None  # an interruption (Ctrl-C): raised
                outs = self._ordinary(args)  # CasADi's own handling of the error
                if isinstance(cause, Exception):
                    # the ordinary call did not raise it again: it came from outside the
                    # evaluation (a signal handler's, e.g. a caller's SIGALRM timeout), and
                    # is the caller's, not an evaluation error to swallow
                    raise cause from None
                return outs
            if self.buffer.ret() != 0:  # the ordinary call raises CasADi's own error
                return self._ordinary(args)
            self.local.stats, self.local.buffered = dict(self.buffer.stats()), True
            return outs
        finally:
            self.lock.release()

    def named(self, args: Mapping[str, Any]) -> dict[str, np.ndarray]:
        """Evaluate at inputs by name (missing ones at their defaults), outputs by name.

        Parameters
        ----------
        args : mapping
            Input name -> array.
        """
        unknown = set(args) - set(self.names_in)
        if unknown:
            raise ValueError(f"{self.f.name()} has no input(s) {sorted(unknown)}")
        outs = self(*(args.get(n) for n in self.names_in))
        return dict(zip(self.names_out, outs, strict=True))

    @property
    def buffered(self) -> bool:
        """Whether this thread's last evaluation ran in the buffer's memory."""
        return bool(getattr(self.local, "buffered", False))

    def stats(self) -> dict[str, Any]:
        """The statistics of this thread's last evaluation (``Function.stats`` of the memory
        it ran in: an ``nlpsol``'s ``success``, ``return_status``, ``iter_count``, ...)."""
        return dict(getattr(self.local, "stats", None) or self.f.stats())

    def _ordinary(self, args: Sequence[Any]) -> list[np.ndarray]:
        kw = {n: a for n, a in zip(self.names_in, args, strict=True) if a is not None}
        res = self.f.call(kw)
        self.local.stats, self.local.buffered = dict(self.f.stats()), False
        return [np.array(res[n], dtype=float).ravel(order="F") for n in self.names_out]
