"""The ground-model options of the ``softlanding`` command, and the model they name.

``--ground linear|drag|added-mass|power`` with its numbers: ``--stiffness`` (the factor ``K``
of ``f = K d`` on the linear and drag grounds), ``--cd`` (the drag number
``c_d = b x_s / m_t``; an extra drag on the added-mass ground), ``--pi-a``, ``--radius``,
``--kappa`` (the accreted cone; default: the poppy-seed preset of the paper's rig), and
``--exponent`` (the power law ``f = d^n``, a user law compiled from its CasADi
expression). Bad numbers are one-line errors (exit 2) from the model's own validation.

A command that tunes for an unknown ground (``impedance``) takes comma lists instead:
``--stiffness 0.5,1,2 --cd 0,0.2,1`` names every ``K`` with every ``c_d``
(:func:`grounds_of`).
"""

from __future__ import annotations

import argparse
import itertools
import math
from typing import Any

from softlanding.errors import ParameterError, check

GROUNDS = ("linear", "drag", "added-mass", "power")


def numbers(text: str) -> list[float]:
    """``--stiffness`` and ``--cd`` of a worst-case command: one number or a comma list
    (an argparse type).

    Parameters
    ----------
    text : str
        What the user typed, e.g. ``0.5,1,2``.

    Raises
    ------
    argparse.ArgumentTypeError
        Not finite numbers separated by commas (a one-line usage error, exit 2).
    """
    try:
        values = [float(t) for t in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"a number or comma-separated numbers (e.g. 0.5,1,2), "
                                         f"not {text!r}")
    return values


def ground_args(p: argparse.ArgumentParser, several: bool = False) -> None:
    """Add ``--ground`` and its parameters to a sub-command's parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser.
    several : bool
        ``--stiffness`` and ``--cd`` take comma lists: the command tunes for the worst case
        over every ground they name (read them with :func:`grounds_of`).
    """
    g = p.add_argument_group("ground model")
    g.add_argument("--ground", choices=GROUNDS, default="linear",
                   help="yielding ground law: the paper's spring (default), inertial drag "
                        "f = d + c_d v^2, added mass (accreted cone of grains), or the power "
                        "law f = d^n")
    worst = (": a comma list (e.g. 0.5,1,2) tunes for the worst case over every value, with "
             "every value of the other" if several else "")
    g.add_argument("--stiffness", type=numbers if several else float, default=None,
                   metavar="K[,K...]" if several else "K",
                   help="ground stiffness factor K > 0: f = K d on --ground linear or drag "
                        f"(default 1, the paper's measured ground){worst}")
    g.add_argument("--cd", type=numbers if several else float, default=None,
                   metavar="CD[,CD...]" if several else "CD",
                   help="drag number c_d = b x_s / m_t (>= 0; --ground drag, or extra drag "
                        f"with added-mass){worst}")
    g.add_argument("--pi-a", type=float, default=None,
                   help="added-mass number Pi_a = pi c_g phi rho_p mu x_s^3 / m_t (default: "
                        "poppy seeds, the paper's rig)")
    g.add_argument("--radius", type=float, default=None, help="foot radius R / x_s (added mass)")
    g.add_argument("--kappa", type=float, default=None,
                   help="cone shape mu / tan(theta) (added mass)")
    g.add_argument("--exponent", type=float, default=None,
                   help="n of the power law f = d^n (> 0)")


def _unused(a: argparse.Namespace, names: tuple[str, ...], ground: str) -> None:
    for n in names:
        if getattr(a, n, None) is not None:
            flag = "--" + n.replace("_", "-")
            raise ParameterError(n, f"{flag} does not apply to --ground {ground}")


def ground_of(a: argparse.Namespace) -> Any:
    """The ground model named by the parsed options.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments with the options of :func:`ground_args`.

    Raises
    ------
    ParameterError
        A number out of range, or an option of another ground model.
    """
    from softlanding.model.ground import LINEAR_GROUND, AddedMassGround, DragGround, LinearGround

    kind = getattr(a, "ground", "linear")
    k = 1.0 if getattr(a, "stiffness", None) is None else a.stiffness
    if kind == "linear":
        _unused(a, ("cd", "pi_a", "radius", "kappa", "exponent"), kind)
        return LINEAR_GROUND if k == 1.0 else LinearGround(k)
    if kind == "drag":
        _unused(a, ("pi_a", "radius", "kappa", "exponent"), kind)
        if a.cd is None:
            raise ParameterError("--cd", "--ground drag needs the drag number --cd VALUE")
        return DragGround(a.cd, k)
    if kind == "added-mass":
        _unused(a, ("exponent", "stiffness"), kind)
        from softlanding.model.terrain import paper_rig_units, poppy_seed_added_mass

        base = poppy_seed_added_mass(paper_rig_units())
        return AddedMassGround(
            pi_a=base.pi_a if a.pi_a is None else a.pi_a,
            radius=base.radius if a.radius is None else a.radius,
            kappa=base.kappa if a.kappa is None else a.kappa,
            c_d=0.0 if a.cd is None else a.cd)
    _unused(a, ("cd", "pi_a", "radius", "kappa", "stiffness"), kind)
    if a.exponent is None:
        raise ParameterError("--exponent", "--ground power needs --exponent N")
    from softlanding.model.terrain import power_law_ground

    return power_law_ground(check("exponent", a.exponent))




def grounds_of(a: argparse.Namespace) -> Any:
    """The ground, or the grounds, named by options parsed with ``ground_args(several=True)``.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments; ``stiffness`` and ``cd`` are lists of numbers or None.

    Returns
    -------
    Ground or list of Ground
        One ground when every list has one value (the same model :func:`ground_of` gives),
        else every ``--stiffness`` value with every ``--cd`` value.

    Raises
    ------
    ParameterError
        As :func:`ground_of`, for any of the grounds.
    """
    ks = a.stiffness if a.stiffness is not None else [None]
    cds = a.cd if a.cd is not None else [None]
    for name, values in (("stiffness", ks), ("cd", cds)):
        if len(set(values)) < len(values):  # a ground named twice would count twice
            raise ParameterError(name, "lists a value twice")
    grounds = [ground_of(argparse.Namespace(**{**vars(a), "stiffness": k, "cd": cd}))
               for k, cd in itertools.product(ks, cds)]
    return grounds[0] if len(grounds) == 1 else grounds


def model_ground(a: argparse.Namespace) -> Any:
    """The ground the controller assumes before measuring (``--model-ground``,
    ``--model-stiffness``, ``--model-cd``), checked.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    from softlanding.model.ground import DragGround, LinearGround

    if a.model_ground == "linear" and a.model_cd is not None:
        raise ParameterError("--model-cd", "applies to --model-ground drag")
    if a.model_ground == "drag" and a.model_cd is None:
        raise ParameterError("--model-cd", "is required with --model-ground drag (the drag "
                                           "number the controller assumes)")
    k = 1.0 if a.model_stiffness is None else a.model_stiffness
    try:
        return LinearGround(k) if a.model_ground == "linear" else DragGround(a.model_cd, k)
    except ParameterError as err:  # the model's numbers are --model-*, not --cd, --stiffness
        flag = {"c_d": "--model-cd", "stiffness": "--model-stiffness"}.get(err.parameter,
                                                                          err.parameter)
        raise ParameterError(flag, str(err).partition(": ")[2]) from None


def rft_stiffness_of(a: argparse.Namespace) -> float:
    """``k_g`` [N/m] of ``--medium`` and ``--foot-diameter`` (resistive force theory).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed ``scale`` arguments.

    Raises
    ------
    ParameterError
        ``--kg`` given too, or ``--foot-diameter`` without ``--medium``.
    """
    from softlanding.model.terrain import PAPER_FOOT_DIAMETER, medium, rft_stiffness

    if a.medium is None:
        raise ParameterError("foot_diameter", "--foot-diameter needs --medium (the granular "
                                              "medium whose RFT fit gives k_g)")
    if a.kg is not None:
        raise ParameterError("kg", "give either --kg or --medium (RFT stiffness), not both")
    d = PAPER_FOOT_DIAMETER if a.foot_diameter is None else a.foot_diameter
    return rft_stiffness(medium(a.medium), d)


def ground_text(g: Any) -> str:
    """A ground in words: its name and parameters (``drag, c_d = 0.2, stiffness = 2``).

    Parameters
    ----------
    g : Ground
        The ground.
    """
    d = g.to_dict()
    if "stiffness" not in d and hasattr(g, "stiffness"):  # (to_dict leaves out K = 1)
        d["stiffness"] = g.stiffness
    rest = [f"{k} = {v:g}" if isinstance(v, float | int) else f"{k} = {v}"
            for k, v in d.items() if k != "model"]
    return ", ".join([str(d.get("model", g.name)), *rest])


__all__ = ["GROUNDS", "ground_args", "ground_of", "ground_text", "grounds_of", "model_ground",
           "numbers", "rft_stiffness_of"]
