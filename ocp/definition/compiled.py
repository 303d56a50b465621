"""One phase's expressions as CasADi Functions in the transcriptions' canonical form.

Every running expression is a function of ``(t, x, u, s)`` where the static
vector ``s = [p; v; t0; T]`` stacks the parameters, the decision variables and
the phase's initial and final times; every bound is a function of the
parameters ``p`` only (evaluated at solve time, so the NLP is built once).
"""

from __future__ import annotations

import casadi as ca

from .problem import OptimalControlProblem
from .symbols import constant


class CompiledPhase:
    """The Functions a transcription needs from one phase.

    Parameters
    ----------
    phase : OptimalControlProblem
        A validated phase.

    Attributes
    ----------
    ode : casadi.Function
        ``(t, x, u, s) -> (xdot, qdot)``; ``qdot = [L; integrands]`` (``nq`` rows).
    path : casadi.Function
        ``(t, x, u, s) -> h`` (the path constraints, ``npath`` rows).
    check : casadi.Function
        ``(t, x, u, s) -> [h; x_b]``: the path constraints and the bounded
        states, checked between nodes.
    bounds : casadi.Function
        ``p -> (path lo, path hi, x lo, x hi, u lo, u hi, check lo, check hi)``.
    check_names : list of str
        One name per row of ``check``.
    check_u_free : list of bool
        Whether each row of ``check`` is free of the controls.
    """

    def __init__(self, phase: OptimalControlProblem) -> None:
        pr = phase
        self.phase = pr
        self.s = ca.vertcat(pr.p, pr.v, pr.t0, pr.T)
        self.nx, self.nu, self.ns = pr.nx, pr.nu, self.s.numel()
        qdot = ca.vertcat(pr.lagrange, *[e for _, e in pr.integrals])
        self.nq = qdot.numel()
        args = [pr.t, pr.x, pr.u, self.s]
        names = ["t", "x", "u", "s"]
        self.ode = ca.Function("ode", args, [pr.rhs, qdot], names, ["xdot", "qdot"])
        h, hlo, hhi = pr.path_stack()
        self.npath = h.numel()
        self.path = ca.Function("path", args, [h], names, ["h"])
        self.path_u_free = [not ca.depends_on(h[i], pr.u) for i in range(self.npath)]
        xlo = ca.vertcat(*[pr.state_bounds[k][0] for k in pr.state_names])
        xhi = ca.vertcat(*[pr.state_bounds[k][1] for k in pr.state_names])
        ulo = ca.vertcat(*[pr.control_bounds[k][0] for k in pr.control_names]) \
            if pr.nu else ca.SX(0, 1)
        uhi = ca.vertcat(*[pr.control_bounds[k][1] for k in pr.control_names]) \
            if pr.nu else ca.SX(0, 1)
        self.bounded_states = [i for i in range(pr.nx)
                               if constant(xlo[i]) != -float("inf")
                               or constant(xhi[i]) != float("inf")]
        xb = ca.vertcat(*[pr.x[i] for i in self.bounded_states]) if self.bounded_states \
            else ca.SX(0, 1)
        self.check = ca.Function("check", args, [ca.vertcat(h, xb)], names, ["c"])
        self.check_u_free = self.path_u_free + [True] * len(self.bounded_states)
        self.check_names = [c.name if c.expr.numel() == 1 else f"{c.name}[{i}]"
                            for c in pr.path for i in range(c.expr.numel())]
        self.check_names += [f"bounds of state {pr.state_names[i]!r}"
                             for i in self.bounded_states]
        clo = ca.vertcat(hlo, *[xlo[i] for i in self.bounded_states])
        chi = ca.vertcat(hhi, *[xhi[i] for i in self.bounded_states])
        self.bounds = ca.Function("bounds", [pr.p], [hlo, hhi, xlo, xhi, ulo, uhi, clo, chi])

    @property
    def ncheck(self) -> int:
        """Number of rows of ``check``."""
        return self.check.size1_out(0)
