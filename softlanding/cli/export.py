"""``softlanding export-controller``: the compiled landing controller written as C source."""

from __future__ import annotations

import argparse

from softlanding.cli.ground import model_ground
from softlanding.cli.output import EXIT_OK, print_json, print_table, robot_of
from softlanding.errors import ParameterError, check


def export_command(a: argparse.Namespace) -> int:
    """Run ``softlanding export-controller`` (the parsed arguments; the exit code).

    Parameters
    ----------
    a : argparse.Namespace
        Parsed arguments.
    """
    from softlanding.control.options import DEFAULT_PERIOD, check_noise, check_period
    from softlanding.optimal.limits import force_limit

    # (every option checked before the controller's compiled code is imported)
    if a.l0 is not None:
        raise ParameterError("--l0", "does not apply: the controller does not use the leg's "
                                     "rest length")
    period = DEFAULT_PERIOD if a.period is None else check_period("--period", a.period)
    noise = check_noise("--noise-std", a.noise_std)
    margin = check("--margin", a.margin, (lambda v: v >= 0, "must be >= 0"))
    filtered = a.estimator == "filtered"
    if filtered and not noise:
        raise ParameterError("--estimator", "filtered applies with --noise-std > 0 (exact "
                                            "measurements have nothing to filter)")
    robot = robot_of(a)
    u_max = force_limit(robot)
    model = model_ground(a)
    from softlanding.control import bangbang as bb
    from softlanding.control.export_c.binding import find_compiler
    from softlanding.control.state_landing import ground_numbers
    from softlanding.util.files import atomic_folder, output_folder

    k, c_d = ground_numbers(model)
    if a.check and find_compiler() is None:
        raise ParameterError("--check", "needs a C compiler (cc, gcc or $CC on the path); "
                                        "none found")
    out = output_folder(a.out, "out", a.force)
    from softlanding.control.export_c.check import check_export
    from softlanding.control.export_c.layout import indices
    from softlanding.control.export_c.writer import FILES, controller_sources, write_controller

    P = bb.robot_numbers(robot.r_m, robot.s, u_max, k, c_d,
                         bb.ground_force_noise(robot.r_m, noise, filtered), margin, period,
                         creep=True)  # (the creep law on, as mpc_landing runs it)
    text = (f"r_m = {robot.r_m:g}, s = {robot.s:g}, u_max = {u_max:g}; prior ground K = {k:g}, "
            f"c_d = {c_d:g}; sample period {period:g}; sensor noise {noise:g}; margin "
            f"{margin:g}; {a.estimator} estimate")
    sources = controller_sources(P, text, noise)
    result = None
    with atomic_folder(out, force=a.force) as tmp:
        write_controller(tmp, sources)
        if a.check:  # before the files are put in place: a failed check leaves nothing
            result = check_export(tmp)
    files = [str(out / name) for name in FILES]
    names = {i: k_ for k_, i in indices("P_").items()}
    fc = None if result is None else result.filter
    d = {"out": str(out), "files": files, "robot": text, "estimator": a.estimator,
         "sensor_noise": noise,
         "numbers": {names[i][2:]: float(v) for i, v in enumerate(P)},
         "check": None if result is None else {
             "landings": result.landings, "samples": result.steps,
             "pull_samples": result.pull_steps,
             "max_relative_difference": result.max_relative, "statuses": result.statuses,
             "filter": None if fc is None else {
                 "landings": fc.landings, "steps": fc.steps, "plans": fc.plans,
                 "paths": fc.paths, "max_relative_difference": fc.max_relative},
             "filtered_steps": None if result.filtered is None else {
                 "steps": result.filtered.steps, "weighted": result.filtered.weighted,
                 "recovery": result.filtered.outcomes, "statuses": result.filtered.statuses,
                 "weight_grid": result.filtered.weights,
                 "max_relative_difference": result.filtered.max_relative},
             "creep_law_samples": result.creep_law_samples(),
             "creep_landings": None if result.creep is None else {
                 "landings": result.creep.landings, "samples": result.creep.steps,
                 "filtered_samples": 0 if result.creep_filtered is None
                 else result.creep_filtered.steps,
                 "statuses": result.creep.statuses,
                 "filtered_statuses": {} if result.creep_filtered is None
                 else result.creep_filtered.statuses,
                 "max_relative_difference": result.creep.max_relative,
                 "filtered_max_relative_difference": {} if result.creep_filtered is None
                 else result.creep_filtered.max_relative}}}
    if a.json:
        print_json(d)
        return EXIT_OK
    rows: list[tuple[str, object]] = [("written to", str(out)),
                                      ("files", ", ".join(FILES)), ("exported for", text)]
    if result is not None:
        rows.append(("check against Python", result.describe()))
    print_table(rows)
    return EXIT_OK


__all__ = ["export_command", "model_ground"]
