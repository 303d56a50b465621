"""Codes, output layout, tolerances and compile options shared by the kernel's modules."""

from __future__ import annotations

from typing import Any

# ground modes
YIELDING, STATIC, FLIGHT = 0, 1, 2
# control regimes
LINEAR, SAT_HIGH, SAT_LOW, OPEN_LOOP = 0, 1, 2, 3
# event codes
EV_STOP, EV_YIELD, EV_LIFT, EV_LAND, EV_SAT_HIGH, EV_SAT_LOW, EV_UNSAT = range(7)
# status codes
REST_PROVEN, HORIZON, TOO_MANY_SEGMENTS, NEVER_RESTS_CREEP = 0, 1, 2, 3
STEP_BUDGET, BODY_THROUGH_FOOT, BODY_FLIES_OFF, OUT_OF_RANGE = 4, 5, 6, 7
HOPS_TO_LIMIT = 8
# not a landing's status: the lite kernel (no creep or hop proof compiled) stopped where the
# landing needs one, and the landing is run again by the whole kernel (see .landing)
NEEDS_PROOFS = 9

# output layout
O_DEPTH, O_STEPS, O_TSTOP, O_T, O_UPEAK, O_SMIN, O_SMAX, O_FEAS, O_STATUS = range(9)
O_E0, O_ET, O_EGND, O_EACT, O_NSEG, O_UMIN, O_UMAX = range(9, 16)
O_DLIM = 16  # the depth's limit as t -> inf: the rest depth, a creep's or hops' limit, else NaN
O_FOOT_REST = 17  # 1 if the foot's rest is proven (also when the body does not rest)
N_OUT = 18

DEFAULT_MAX_STEPS = 1_000_000  # marching steps (and segments) per landing before giving up
SCALE_MAX = 1e8  # largest |initial state| or stroke resolved (absolute rounding ~1e-8 there)
MAX_SUBSTEPS = 1_000_000  # substeps of one exact propagation; beyond: NaN (hostile scales)

THETA = 1.0  # ||A|| h (or omega h in the static mode) bound for the marching grid
TIE = 1e-12  # relative tolerance on the ground's yield threshold
FEAS_TOL = 1e-9  # tolerance on the stroke limits (rounding at an exact boundary)
SMALL = 1e-12  # what counts as zero drift in the rest proof

# compile options of every compiled function: cached on disk, no C-callable wrapper (nothing
# takes a kernel function's C address; the wrappers were a tenth of the first compile) and no
# Python entry: these are called from compiled code only (each one's Python wrapper, which
# unboxes its arguments, was compiled for nothing: ~10 % of the first compile). A call from
# Python to a JIT function would crash: the functions Python calls take ENTRY instead.
# (A constant argument in a call between compiled functions is passed as np.int64(..) or
# np.bool_(..): numba compiles the callee again for every literal value it is given.)
JIT: dict[str, Any] = {"cache": True, "no_cfunc_wrapper": True, "no_cpython_wrapper": True}
ENTRY: dict[str, Any] = {"cache": True, "no_cfunc_wrapper": True}
