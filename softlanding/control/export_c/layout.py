"""The numbers the exported C takes from the Python controller: the layout of ``P`` and
``M``, the phases, statuses and tolerances of :mod:`softlanding.control.bangbang`, the
creep law's constants and Gauss-Legendre nodes (:mod:`softlanding.control.creep`), the
layout of the foot filter's memory ``F`` and its constants
(:mod:`softlanding.control.foot_filter`), the filtered estimate's weight and recovery
constants (:mod:`softlanding.control.estimation`, :mod:`softlanding.control.recovery`), and
the Dormand-Prince coefficients of
:mod:`softlanding.simulation.kernel.dop853`, as C text.

Every index is read from :mod:`~softlanding.control.bangbang` (its ``P_*`` and ``M_*``
constants) or :mod:`~softlanding.control.foot_filter` (its ``F_*``), never written here: a
new entry there without a description here fails the export (:func:`layout_lines`), so the
C cannot drift from the Python.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from softlanding.control import bangbang as bb
from softlanding.control import bangbang_layout as bbl
from softlanding.control import creep, estimation, recovery
from softlanding.control import foot_filter as ff
from softlanding.simulation.kernel import dop853

#: What each entry of ``P`` holds (the header's comments).
P_DOC = {
    "P_AB0": "body's acceleration at u = 0: a_b = AB0 + BB u",
    "P_BB": "body's acceleration per unit force",
    "P_AF0": "foot's acceleration at u = 0, f = 0: a_f = AF0 + BF u + GF f",
    "P_BF": "foot's acceleration per unit force",
    "P_GF": "foot's acceleration per unit ground force",
    "P_K": "ground stiffness factor K planned for (overwritten by the estimate)",
    "P_CD": "ground drag number c_d planned for (overwritten by the estimate)",
    "P_RM": "mass ratio r_m = m_b / m_f",
    "P_S": "stroke s (0 <= x_b - x_f <= s)",
    "P_UMAX": "force limit u_max (the push +u_max, the pull -u_max)",
    "P_HOLD0": "1 / (1 + r_m): the foot's share of the weight in the arrest condition",
    "P_NOISE": "standard deviation of one measured ground force (the estimator's)",
    "P_MARGIN": "plan for the estimate less MARGIN standard deviations of K and c_d",
    "P_BUDGET": "Newton iterations per sample while the switch is > 3 samples away",
    "P_PERIOD": "the sample period (the plan-holds check predicts the next sample)",
    "P_WORK": "integrator steps one call may take (its bound; then SL_DEFERRED)",
    "P_CREEP": "the creep law takes over creeping landings (1; 0: SL_CREEP, not covered)",
}

#: What each entry of ``M`` holds.
M_DOC = {
    "M_PHASE": "SL_PUSH (both arcs left), SL_PULL (the foot's stop left), SL_CREEPING or "
               "SL_BRAKING",
    "M_TAU1": "push left from the last step (while SL_PUSH)",
    "M_TAU2": "pull from the switch (SL_PUSH) or from the last step (SL_PULL) to the stop",
    "M_TH0": "estimate of K",
    "M_TH1": "estimate of c_d",
    "M_P00": "estimator's covariance [K, K] / NOISE^2",
    "M_P01": "estimator's covariance [K, c_d] / NOISE^2",
    "M_P11": "estimator's covariance [c_d, c_d] / NOISE^2",
    "M_SAMPLES": "measurements the estimate holds",
    "M_ITER": "Newton iterations of the last call",
    "M_STATUS": "status of the last step",
    "M_XBT": "planned body height at the foot's stop",
    "M_VBT": "planned body velocity at the foot's stop",
    "M_XFT": "planned foot height at the foot's stop",
    "M_UNCONVERGED": "samples in a row with a large unconverged Newton step",
    "M_PRED": "predicted state after the next sample, 4 entries [x_b, v_b, x_f, v_f]",
    "M_PRED_OK": "1 if M_PRED holds a prediction",
    "M_KPLAN": "K the prediction was made for",
    "M_CPLAN": "c_d the prediction was made for",
    "M_LAST_STEP": "size |dtau1| + |dtau2| of the last Newton step",
    "M_WORK": "integrator steps of the last sl_control_step (at most P[SL_P_WORK])",
    "M_DEFERRED": "calls whose integrator steps ran out (SL_DEFERRED)",
    "M_UCREEP": "the creep law's or the brake's force of the last step (while SL_CREEPING, "
                "SL_BRAKING): sl_force",
    "M_FALLBACKS": "samples the fallback acted on (the structure did not cover the state)",
    "M_WHY": "the status the fallback last took over from",
}

#: What each entry of the foot filter's memory ``F`` holds.
F_DOC = {
    "F_X": "filtered foot position x_f (the last step's output)",
    "F_V": "filtered foot velocity v_f (the last step's output)",
    "F_P00": "covariance [x_f, x_f] / noise^2",
    "F_P01": "covariance [x_f, v_f] / noise^2",
    "F_P11": "covariance [v_f, v_f] / noise^2",
    "F_G1": "the last sample's g (the foot's acceleration less BF u)",
    "F_G0": "the sample before's g",
    "F_N": "samples filtered",
    "F_H": "the last sample's length",
    "F_X0": "the impact's foot position (the first samples are redone from it)",
    "F_V0": "the impact's foot velocity",
    "F_U1": "the first sample's int u dt (F_U1 + 2: the second sample's)",
    "F_U2": "the first sample's int (h - t) u dt (F_U2 + 2: the second sample's)",
    "F_H0": "the first sample's length (-1: unequal first samples, no redo)",
}

#: The foot filter's constants (names of :mod:`~softlanding.control.foot_filter`).
FILTER_CONSTANTS = ("PROVISIONAL", "PROCESS", "INNOVATION", "START_STD")

#: The phases and statuses, and the tolerances the C uses (names of
#: :mod:`~softlanding.control.bangbang`).
STATUSES = ("OK", "NEWTON_FAILED", "ARREST_FAILS", "PATH_LIMIT", "CONVERGING", "HOLDS",
            "CREEP", "DEFERRED", "CREEP_LAW", "KEPT", "BRAKE")
CONSTANTS = ("PUSH", "PULL", "CREEPING", "BRAKING", *STATUSES, "RTOL", "MAX_NEWTON", "NEWTON_TOL",
             "PLAN_HOLDS_TOL", "MAX_UNCONVERGED", "LOOSE_RTOL", "TIGHTEN", "MARCH_FAILED",
             "MARCHED", "SPENT", "CREEP_SIGMAS", "STROKE_MARGIN", "BODY_DECEL")

#: The creep law's constants (names of :mod:`~softlanding.control.creep`), written
#: ``SL_CREEP_<name>``; its Gauss-Legendre nodes and weights are :func:`creep_gl_text`'s.
CREEP_CONSTANTS = ("BRAKE", "GAIN", "REACH", "BISECT", "NEWTON")

#: The filtered estimate's constants: ``(module, name)``, written ``SL_<name>``
#: (``sl_filtered_weight``'s allowance and least weight, ``sl_filtered_step``'s bound on the
#: samples in a row its recovery goes on over).
FILTERED_CONSTANTS = ((bb, "FILTERED_REGRESSOR"), (estimation, "MIN_WEIGHT"),
                      (recovery, "RECOVERY_SAMPLES"))


def c_double(v: float) -> str:
    """A C literal of the double ``v``, exact (Python's shortest round-trip repr).

    Parameters
    ----------
    v : float
        A finite number.

    Raises
    ------
    ValueError
        ``v`` is not finite (C has no literal for it).
    """
    v = float(v)
    if not np.isfinite(v):
        raise ValueError(f"no C literal for {v}")
    text = repr(v)
    return text if any(c in text for c in ".en") else text + ".0"


def indices(prefix: str) -> dict[str, int]:
    """The ``P_*`` (``prefix = "P_"``) or ``M_*`` constants of the controller, or the
    ``F_*`` of the foot filter, by index.

    Parameters
    ----------
    prefix : str
        ``"P_"``, ``"M_"`` or ``"F_"``.
    """
    module = ff if prefix == "F_" else bbl
    found = {k: v for k, v in vars(module).items() if k.startswith(prefix) and type(v) is int}
    return dict(sorted(found.items(), key=lambda kv: kv[1]))


def layout_lines(prefix: str) -> list[str]:
    """``#define SL_P_K 5  /* ... */`` lines of every ``P_*``, ``M_*`` or ``F_*`` index,
    then the size.

    Parameters
    ----------
    prefix : str
        ``"P_"``, ``"M_"`` or ``"F_"``.

    Raises
    ------
    KeyError
        The controller (or the filter) has an entry this module does not describe.
    """
    doc, module, size = {"P_": (P_DOC, bbl, "NP"), "M_": (M_DOC, bbl, "NM"),
                         "F_": (F_DOC, ff, "NF")}[prefix]
    found = indices(prefix)
    missing = sorted(set(found) - set(doc))
    if missing:
        raise KeyError(f"{module.__name__} has {', '.join(missing)}, which the C "
                       "export does not describe: add it to export_c.layout")
    lines = [f"#define SL_{k:<14} {v:2d}  /* {doc[k]} */" for k, v in found.items()]
    lines.append(f"#define SL_{size:<14} {getattr(module, size):2d}  /* entries */")
    return lines


def define_line(name: str, v: int | float) -> str:
    """``#define name value``: an int as it is, a float to the last bit (:func:`c_double`).

    Parameters
    ----------
    name : str
        The macro's name (padded by the caller, so that the values line up).
    v : int or float
        The value.
    """
    return f"#define {name} {str(v) if type(v) is int else c_double(v)}"


def constant_lines() -> list[str]:
    """``#define`` lines of :data:`CONSTANTS` (the status's meaning in its comment)."""
    lines = []
    for name in CONSTANTS:
        v = getattr(bb, name)
        note = bb.STATUS_NAMES[v] if name in STATUSES else None
        lines.append(define_line(f"SL_{name:<16}", v) + (f"  /* {note} */" if note else ""))
    return lines


def filter_constant_lines() -> list[str]:
    """``#define SL_FILTER_*`` lines of :data:`FILTER_CONSTANTS`, and the impact state's
    variance ``START_STD ** 2`` (as Python squares it)."""
    lines = [define_line(f"SL_FILTER_{name:<12}", getattr(ff, name))
             for name in FILTER_CONSTANTS]
    lines.append(f"#define SL_FILTER_{'START_VAR':<12} {c_double(ff.START_STD ** 2)}")
    return lines


def filtered_constant_lines() -> list[str]:
    """``#define`` lines of :data:`FILTERED_CONSTANTS`."""
    return [define_line(f"SL_{name:<18}", getattr(module, name))
            for module, name in FILTERED_CONSTANTS]


def creep_constant_lines() -> list[str]:
    """``#define SL_CREEP_*`` lines of :data:`CREEP_CONSTANTS`, and ``SL_CREEP_GL_N``, the
    number of Gauss-Legendre nodes."""
    lines = [define_line(f"SL_CREEP_{name:<10}", getattr(creep, name))
             for name in CREEP_CONSTANTS]
    lines.append(f"#define SL_CREEP_{'GL_N':<10} {creep.GL_X.size}")
    return lines


def creep_gl_text() -> str:
    """The C arrays ``SL_GL_X``, ``SL_GL_W``: the creep law's Gauss-Legendre nodes and
    weights on ``[0, 1]`` (:data:`~softlanding.control.creep.GL_X`, ``GL_W``), exact."""
    return "\n".join([
        f"static const double SL_GL_X[SL_CREEP_GL_N] = {_array(creep.GL_X)};",
        f"static const double SL_GL_W[SL_CREEP_GL_N] = {_array(creep.GL_W)};"])


def _array(values: Iterable[float]) -> str:
    return "{" + ", ".join(c_double(v) for v in values) + "}"


def dop853_text() -> str:
    """The C arrays ``SL_DA`` (12 x 12), ``SL_DB`` (12), ``SL_DE5``, ``SL_DE3`` (13)."""
    rows = ",\n    ".join(_array(r) for r in dop853.A)
    return "\n".join([
        f"static const double SL_DA[{dop853.A.shape[0]}][{dop853.A.shape[1]}] = {{\n    "
        f"{rows}}};",
        f"static const double SL_DB[{dop853.B.size}] = {_array(dop853.B)};",
        f"static const double SL_DE5[{dop853.E5.size}] = {_array(dop853.E5)};",
        f"static const double SL_DE3[{dop853.E3.size}] = {_array(dop853.E3)};"])


def robot_lines(P: np.ndarray) -> list[str]:
    """The initializer lines of ``SL_ROBOT_NUMBERS``: each value with its entry's name.

    Parameters
    ----------
    P : array
        :func:`~softlanding.control.bangbang.robot_numbers`.
    """
    names = {v: k for k, v in indices("P_").items()}
    return [f"    {c_double(v)},  /* {names[i]} */" for i, v in enumerate(P)]


__all__ = ["CONSTANTS", "CREEP_CONSTANTS", "FILTERED_CONSTANTS", "FILTER_CONSTANTS", "F_DOC",
           "M_DOC", "P_DOC", "STATUSES", "c_double", "constant_lines", "creep_constant_lines",
           "creep_gl_text", "define_line", "dop853_text", "filter_constant_lines",
           "filtered_constant_lines", "indices", "layout_lines", "robot_lines"]
