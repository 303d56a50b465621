"""``softlanding robust``: one landing plan for a set of grounds (open-loop, and the tree)."""

from __future__ import annotations

import argparse
import itertools
from typing import Any

from softlanding.cli.output import (
    EXIT_FAILURE,
    EXIT_OK,
    print_json,
    print_table,
    robot_of,
    savefig,
    target,
)
from softlanding.errors import ParameterError, check, check_count
from softlanding.model.ground import MAX_GROUNDS, Ground, linear_or_drag
from softlanding.model.robot import Impact


def ground_set(stiffness: list[float], drag: list[float]) -> list[Ground]:
    """The grounds ``f = K d + c_d v^2`` of every ``K`` and ``c_d`` (linear when ``c_d = 0``).

    Parameters
    ----------
    stiffness, drag : list of float
        The factors ``K`` (> 0) and drag numbers (>= 0).

    Raises
    ------
    ParameterError
        A bad value, a repeated ground, or more than
        :data:`~softlanding.model.ground.MAX_GROUNDS` grounds.
    """
    n = len(stiffness) * len(drag)
    if n > MAX_GROUNDS:  # refused before anything is built or compiled
        raise ParameterError("--cd" if len(drag) > len(stiffness) else "--stiffness",
                             f"{len(stiffness)} x {len(drag)} = {n} grounds (every --stiffness "
                             f"with every --cd); at most {MAX_GROUNDS}")
    for k in stiffness:
        check("--stiffness", k, (lambda v: v > 0, "must be > 0"))
    for c in drag:
        check("--cd", c, (lambda v: v >= 0, "must be >= 0"))
    if len(set(stiffness)) < len(stiffness) or len(set(drag)) < len(drag):
        raise ParameterError("--stiffness" if len(set(stiffness)) < len(stiffness) else "--cd",
                             "lists a value twice")
    return [linear_or_drag(k, c) for k, c in itertools.product(stiffness, drag)]


def _stiffness_shown(plan: dict) -> dict:
    """Every ground of the set with its ``stiffness`` (a ground's JSON omits the paper's 1)."""
    for row in plan["grounds"]:
        row["ground"].setdefault("stiffness", 1.0)
    return plan


def _table(robust: Any, tree: Any, clair: list[Any], names: list[str],
           branch: float) -> list[tuple[str, object]]:
    """The table's rows: each ground's depths, then the worst cases and the search."""
    rows: list[tuple[str, object]] = []
    for i, name in enumerate(names):
        nom, rob = robust.nominal[i], robust.landings[i]
        cells = [f"nominal {nom.depth:.5g}{'' if nom.feasible else ' (limit broken)'}",
                 f"robust {rob.depth:.5g}{'' if rob.feasible else ' (limit broken)'}"]
        if tree is not None:
            t = tree.landings[i]
            cells.append(f"tree {t.depth:.5g}{'' if t.feasible else ' (limit broken)'}")
        cells.append(f"clairvoyant {clair[i].depth:.5g}")
        rows.append((name, ", ".join(cells)))
    rows += [("worst: nominal / robust", f"{robust.nominal_worst:.6g} / {robust.worst:.6g}"),
             ("worst: clairvoyant (a bound)", f"{max(c.depth for c in clair):.6g}"),
             ("robust feasible on every ground", robust.feasible),
             ("robust search converged (KKT)", "yes" if robust.converged else
              f"NO (KKT residual {robust.kkt_residual:.2g})"),
             ("robust plan", _plan_line(robust, names, clair)),
             ("binding (KKT multipliers)", _binding_line(robust, names)),
             ("nominal feasible on every ground", robust.nominal_feasible),
             ("search", f"{robust.message} ({robust.iterations} iterations, "
                        f"{robust.evaluations} points, {robust.solve_time_s:.3g} s wall, "
                        f"{robust.cpu_time_s:.3g} s CPU)")]
    if tree is not None:
        rows += [(f"worst: tree (branch at {branch:g})", f"{tree.worst:.6g}"),
                 ("tree feasible on every ground", tree.feasible)]
    return rows


def robust_command(a: argparse.Namespace) -> int:
    """Run ``softlanding robust`` (the parsed arguments; the exit code).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    robot, impact, plot = robot_of(a), Impact(a.v0), target(a)
    grounds = ground_set(a.stiffness, a.cd)
    if a.branch_time is not None and not a.tree:
        raise ParameterError("--branch-time", "applies to --tree")
    if a.branch_time is not None:
        check("branch_time", a.branch_time, (lambda v: v > 0, "must be > 0"))
    extra = check_count("extra_pieces", a.extra_pieces, 0, 4)
    from softlanding.optimal.limits import force_limit

    force_limit(robot)
    if not impact.v0 < 0:
        raise ParameterError("v0", "a landing under control needs v0 < 0")
    from softlanding.control.robust import DEFAULT_BRANCH_TIME, robust_landing, two_stage_landing
    from softlanding.optimal.landing import solve_landing
    from softlanding.util.progress import activity, step

    with activity("robust plan"):  # a minute or more: a bar with its stage on a terminal
        nominal = solve_landing(impact, robot, replay=False)
        step("nominal plan")
        clair = [solve_landing(impact, robot, g) for g in grounds]
        step("clairvoyant plans")
        robust = robust_landing(impact, grounds, robot, nominal=nominal, extra_pieces=extra,
                                clairvoyant=clair)
        step("robust schedule")
        branch = DEFAULT_BRANCH_TIME if a.branch_time is None else a.branch_time
        tree = two_stage_landing(robust, branch) if a.tree else None
    clair_depth = [c.depth for c in clair]
    chosen = tree if tree is not None else robust
    names = [f"K = {k:g}, c_d = {c:g}" for k, c in itertools.product(a.stiffness, a.cd)]
    written = None
    if plot:
        from softlanding.plots.control import plot_robust_landing

        written = savefig(plot_robust_landing(robust, tree, clair_depth), plot)
    if a.json:
        print_json({
            "worst_depth": chosen.worst, "feasible": chosen.feasible,
            "converged": robust.converged, "kkt_residual": robust.kkt_residual,
            "message": robust.message, "binding": _binding_json(robust, names),
            "clairvoyant_of": None if robust.clairvoyant_of is None
            else names[robust.clairvoyant_of], "plan": _plan_line(robust, names, clair),
            "robust_worst_depth": robust.worst, "robust_feasible": robust.feasible,
            "tree_worst_depth": None if tree is None else tree.worst,
            "tree_feasible": None if tree is None else tree.feasible,
            "nominal_worst_depth": robust.nominal_worst,
            "nominal_feasible": robust.nominal_feasible,
            "clairvoyant_worst_depth": max(clair_depth),
            "clairvoyant_depths": clair_depth,
            "clairvoyant_verified": [not c.unverified_reasons() for c in clair],
            "robust": _stiffness_shown(robust.to_dict()),
            "tree": None if tree is None else _stiffness_shown(tree.to_dict())})
    else:
        print_table(_table(robust, tree, clair, names, branch))
        if written:
            print(f"figure written to {written}")
    # an unconverged search's schedule is feasible but not an optimum: say so by the exit code
    ok = chosen.feasible and (robust.converged or a.accept_unverified)
    return EXIT_OK if ok else EXIT_FAILURE


def _plan_line(robust: Any, names: list[str], clair: list[Any]) -> str:
    """What the robust schedule is against the clairvoyant optima (and, where one ground
    binds, why its clairvoyant plan is not the answer)."""
    from softlanding.simulation.simulator import simulate

    k = robust.clairvoyant_of
    if k is not None:
        return (f"the clairvoyant optimum of {names[k]} (the binding ground; the others "
                f"slack): the worst depth is that ground's clairvoyant depth")
    bound = robust.lower_bound
    gap = robust.worst - bound
    line = (f"worst {gap:.3g} ({gap / bound:.2g} relative) above the largest clairvoyant "
            f"depth {bound:.12g}")
    if len(robust.multipliers) == 1:
        (b,) = robust.multipliers
        plan = clair[b].schedule()
        for g, name in zip(robust.grounds, names, strict=True):
            r = simulate(robust.robot, robust.impact, plan, g, energy=False)
            if not r.feasible:
                return (f"{line}; the binding ground's clairvoyant plan breaks a limit on "
                        f"{name} (stroke {r.stroke_min:.3g} to {r.stroke_max:.4g}, {r.status})")
            if r.depth > clair[b].depth * (1 + 1e-9):
                return f"{line}; the binding ground's clairvoyant plan lands deeper on {name}"
    return line


def _binding_line(robust: Any, names: list[str]) -> str:
    """The binding grounds and limits with their multipliers (the grounds' sum to 1)."""
    if not robust.multipliers:
        return "none (no KKT point)"
    grounds = ", ".join(f"{names[k]}: {v:.4g}" for k, v in robust.multipliers.items())
    limits = ", ".join(f"{kind}{'' if k is None else f' on {names[k]}'}: {v:.3g}"
                       for kind, k, v in robust.limits if v > 0)
    total = sum(robust.multipliers.values())
    return f"{grounds} (sum {total:.12g})" + (f"; limits {limits}" if limits else "")


def _binding_json(robust: Any, names: list[str]) -> dict[str, Any]:
    """The binding grounds and active limits, by name, with their multipliers."""
    return {"grounds": [{"ground": names[k], "multiplier": v}
                        for k, v in robust.multipliers.items()],
            "limits": [{"kind": kind, "ground": None if k is None else names[k],
                        "multiplier": v} for kind, k, v in robust.limits],
            "pin": None if robust.pin is None else
            {"piece": robust.pin[0] + 1, "ground": names[robust.pin[1]]},
            "off_pin": robust.off_pin}


__all__ = ["ground_set", "robust_command"]
