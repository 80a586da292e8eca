"""``adaptive-dd validate [SCENARIO]``: a scenario checked and printed resolved (defaults marked).

A benchmark scenario: its tables with the estimate of the run's size
(:meth:`~adaptive_dd.benchmark.scenario.Scenario.estimate`: the excitation phase of ``[run] excite``
included), the resolved controller settings, the peak torque along the reference and what the run
would meet (:func:`adaptive_dd.benchmark.preflight.preflight`), on
every arm; an arm from a URDF also prints its joints, base parameters and payload subspace. An
identification scenario (with ``[record]``): its ``[arm]`` and ``[record]``, resolved.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from adaptive_dd.cli._common import (
    add_command,
    closed_form_view,
    describe_arm,
    identification_tables,
    load_arm,
)

__all__ = ["add_parser", "is_identification_scenario", "run", "validate_identification"]


def add_parser(sub) -> None:
    """The options of ``validate``."""
    v = add_command(
        sub,
        "validate",
        help="check a scenario and print it resolved (defaults marked), with an estimate of the run's "
        "time (the kernels' compilation on a cold cache and a [run] excite phase included, each said)",
    )
    v.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    v.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the scenario resolved; 1 if the run would meet a problem."""
    from adaptive_dd.benchmark.controller_entries import variants_line
    from adaptive_dd.benchmark.preflight import resolved_settings
    from adaptive_dd.benchmark.scenario import format_scenario, load_scenario, runtime_line

    if args.scenario and Path(args.scenario).is_file():
        if is_identification_scenario(args.scenario):  # [arm] and [record]: no benchmark tables needed
            return validate_identification(args.scenario)
    sc = load_scenario(args.scenario)
    print(format_scenario(sc))
    print(f"# {runtime_line(sc)}")
    if variants_line(sc):
        print(f"# {variants_line(sc)}")
    if sc.closed_forms is None:
        print(describe_arm(sc.arm))
    for line in resolved_settings(sc):
        print(line)
    _print_added_floors(sc)
    _print_torque_peaks(sc)
    return _preflight(sc)


def _print_added_floors(sc) -> None:
    """The floors ``adaptive-dd benchmark`` adds to the run (``cli.benchmark.with_floors``), and those
    it cannot (built for the other kind of arm)."""
    from adaptive_dd.benchmark.preflight import missing_floors

    add, cannot = missing_floors(sc)
    for floor, of in add.items():
        print(f"# the benchmark adds {floor}: the floor of {', '.join(of)} (list it in run.controllers)")
    for floor, of in cannot.items():
        print(f"# {floor}, the floor of {', '.join(of)}, does not run on this arm: set their tables' floor")


def _print_torque_peaks(sc) -> None:
    from adaptive_dd.benchmark.preflight import joint_units, torque_peaks

    peak, _, _ = torque_peaks(sc)
    limit = sc.arm.actuator.torque_limit
    units = joint_units(sc.arm)
    print(
        "# peak |tau| along the reference (inverse dynamics, every payload): "
        + ", ".join(
            f"joint{j + 1} {peak[j]:.4g} {units[j][2]} ({peak[j] / limit[j]:.0%} of its limit)"
            for j in range(peak.size)
        )
    )


def _preflight(sc) -> int:
    from adaptive_dd.benchmark import preflight as pf

    problems = pf.reference_problems(sc) + pf.controller_problems(sc)
    torque = pf.torque_problems(sc)
    also = pf.inertia_problems(sc) + pf.floor_problems(sc) + pf.capacity_problems(sc)
    for w in torque + also + pf.duration_problems(sc):
        print(f"adaptive-dd validate: warning: {w}", file=sys.stderr)
    if problems:
        print(f"adaptive-dd validate: {len(problems)} problem(s) the run would meet:", file=sys.stderr)
        for p in problems:
            print(f"  {p}", file=sys.stderr)
        return 1
    print(
        f"# checked: the reference within the arm's position and velocity limits (torque: "
        f"{'see the warning' if torque else 'within'}); {len(sc.controllers)} controller(s) built"
    )
    return 0


def is_identification_scenario(path) -> bool:
    """A scenario with a ``[record]`` table: an identification, read by ``identify``/``predict``."""
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.io import read_toml

    return "record" in read_toml(Path(path), ScenarioError)


def validate_identification(path) -> int:
    """``adaptive-dd validate`` of an identification scenario: its ``[arm]`` and ``[record]``, resolved.

    Raises
    ------
    ScenarioError
        A table other than ``[arm]``, ``[plant]``, ``[record]`` (a benchmark's tables do not
        belong here), or what :func:`adaptive_dd.record.record_spec` refuses.
    """
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.io import read_toml
    from adaptive_dd.record import record_spec

    data = read_toml(Path(path), ScenarioError)
    identification_tables(path, data)
    arm = load_arm(str(path))
    if closed_form_view(arm) is not None:
        raise ScenarioError(f"{path}: [record] needs an [arm] from a URDF (urdf = ... or robot = ...)")
    spec = record_spec(data["record"], arm.joint_names, arm.joint_kinds, str(path))
    print(
        f"# identification scenario {path}: [arm] and [record] (no [reference]: identify and predict "
        "read a log)"
    )
    _print_record_spec(spec, arm.joint_names)
    print(describe_arm(arm))
    from adaptive_dd.errors import DataError
    from adaptive_dd.record import read_log
    from adaptive_dd.record_pieces import clock

    try:
        log = read_log(spec, arm=arm)  # the files themselves: columns, cells, times, units, gaps
    except DataError as exc:  # identify would meet it too, unless --window cuts the part it is in
        print(
            "adaptive-dd validate: 1 problem identify and predict would meet reading the log:",
            file=sys.stderr,
        )
        print(f"  {exc}", file=sys.stderr)
        print(
            "  (identify and predict take --window START END: a part of the log without it reads)",
            file=sys.stderr,
        )
        return 1
    pieces = len(log.pieces) or 1
    print(
        f"# the log as identify reads it: {log.t.size} samples at T = {log.sample_period:.6g} s "
        f"({clock(log.t[0])}-{clock(log.t[-1])} s of its clock), {pieces} continuous piece(s)"
    )
    for note in log.notes:
        print(f"# {note}")
    return 0


def _print_record_spec(spec, joint_names) -> None:
    print(f"record.files = {[str(f) for f in spec.files]}")
    print(f"record.time = {spec.time!r}")
    for j, name in enumerate(joint_names):
        vel = (
            "derived"
            if spec.derive_velocity or spec.velocity is None
            else f"{spec.velocity[j]!r} (x {spec.position_scale[j]:.6g})"
        )
        print(
            f"record.joint{j + 1} = {{ joint = {name!r}, position = {spec.position[j]!r} "
            f"(x {spec.position_scale[j]:.6g}), "
            f"velocity = {vel}, torque = {spec.torque_gain[j]:.6g} * {spec.torque[j]!r} + "
            f"{spec.torque_offset[j]:.6g}{'' if spec.used[j] else ', excluded'} }}"
        )
    print(f"record.window = {list(spec.window) if spec.window else 'the whole log'}")
