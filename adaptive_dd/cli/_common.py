"""What the command modules share: checked option types, the refusal of an option that does
not apply, the arm a command works on (:func:`load_arm`, an :class:`~adaptive_dd.plant.arm.Arm`;
whether it has the paper's closed forms is :func:`adaptive_dd.plant.two_link.closed_form_view`'s
to say, the package's one place, imported here for the commands), what ``validate`` prints of a
URDF arm (:func:`describe_arm`) and a log read through a scenario's ``[record]`` (:func:`read_arm_log`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.two_link import closed_form_view  # the one place: has the arm the closed forms

NAME_WIDTH = 44


def number(kind: type, lo: float, hi: float, lo_open: bool = False):
    """An argparse ``type`` accepting a finite ``kind`` in ``[lo, hi]`` (``(lo, hi]``)."""

    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"not {what}: {text!r}") from None
        if (kind is float and not math.isfinite(v)) or (v <= lo if lo_open else v < lo) or v > hi:
            raise argparse.ArgumentTypeError(f"{text} is outside {'(' if lo_open else '['}{lo:g}, {hi:g}]")
        return v

    parse.__name__ = kind.__name__
    return parse


POS = number(float, 0.0, 1e6, lo_open=True)
SEED = number(int, 0, 2**63 - 1)
SEEDS = number(int, 1, 10_000)
MASS = number(float, 0.0, 50.0)
RADIUS = number(float, 0.0, 0.5)
PERIOD = number(float, 1e-5, 0.1)
SUBSTEPS = number(int, 1, 100)


NO_PROGRESS_HELP = "no progress bar (there is none when stderr is not a terminal: a log file gets none)"


def show_progress(args) -> bool:
    """A progress bar unless ``--no-progress``, and only on a terminal: in a file stderr is a log,
    where a bar's carriage returns run into the messages printed beside it."""
    import sys

    isatty = getattr(sys.stderr, "isatty", None)
    return not args.no_progress and bool(isatty and isatty())


def add_command(sub, name: str, **kw) -> argparse.ArgumentParser:
    """The sub-parser of command ``name`` (no abbreviations; ``--debug`` after the command too)."""
    sp = sub.add_parser(name, allow_abbrev=False, **kw)
    # also after the command (``adaptive-dd benchmark --debug``); SUPPRESS: not reset when absent
    sp.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return sp


def add_window_option(p: argparse.ArgumentParser) -> None:
    """``--window START END`` of the commands that read a log through a scenario's ``[record]``."""
    p.add_argument(
        "--window",
        type=number(float, -1e11, 1e11),  # an epoch clock's seconds (about 1.7e9) included
        nargs=2,
        metavar=("START", "END"),
        help="with --arm: the part of the log to use [s of its clock] (replaces record.window)",
    )


def refuse(args: argparse.Namespace, options: tuple[str, ...], why: str, error=ParameterError) -> None:
    """An ``error`` (:class:`ParameterError`) naming those of ``options`` given on the command line
    and ``why`` they do not apply (an option that does not apply is never silently ignored)."""
    given = [o for o in options if o in getattr(args, "given", ())]
    if given:
        raise error(f"{', '.join(given)}: {why}")


def short(name: str) -> str:
    """``name`` cut to :data:`NAME_WIDTH` characters (a base parameter's name in a table)."""
    return name if len(name) <= NAME_WIDTH else name[: NAME_WIDTH - 3] + "..."


def arm_label(args_arm: str | None, arm) -> str:
    """How messages name the arm: 'the SICE arm', 'the two-link arm of FILE', 'the N-joint arm of FILE'."""
    if args_arm is None:
        return "SICE arm"
    kind = "two-link" if closed_form_view(arm) is not None else f"{arm.n_joints}-joint"
    return f"{kind} arm of {args_arm}"


def arm_file(args) -> None:
    """``args.arm`` as a file's path: a shipped scenario's name (``ur5_tool_swap``) resolved once,
    for every later read of it (:func:`~adaptive_dd.benchmark.scenario.scenario_file`)."""
    if getattr(args, "arm", None):
        from adaptive_dd.benchmark.scenario import scenario_file

        args.arm = str(scenario_file(args.arm))


def load_arm(path: str | None, repair_inertia: bool = False, *, general: str | None = None):
    """The arm of a scenario file's ``[arm]`` and ``[plant]`` tables (SICE arm if ``path`` is None):
    the model its controllers are given (``[model] from`` when there is one); ``repair_inertia``
    sets ``arm.repair_inertia = true`` (identify's --repair-inertia).

    An :class:`~adaptive_dd.plant.arm.Arm`; one of the paper's geometry has its closed forms
    (:func:`closed_form_view`). ``general``: ``general = true`` (no closed forms) even where the URDF
    is the paper's kind of two-link arm; the string names what needs it, for the
    :class:`ScenarioError` raised when the ``[arm]`` names no URDF.
    """
    from adaptive_dd.benchmark.scenario import model_and_plant, read_toml
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.plant.arm_tables import arm_from_tables
    from adaptive_dd.plant.two_link import ClosedFormTwoLink
    from adaptive_dd.plant.uncertainty import PLANT_TRUTH_KEYS

    if path is None:
        if general:
            from adaptive_dd.plant.arm import Arm

            return Arm.sice()
        return ClosedFormTwoLink.sice().to_arm()
    from adaptive_dd.benchmark.scenario import scenario_file

    path = str(scenario_file(path))  # a shipped scenario's name too
    data = read_toml(Path(path))
    from adaptive_dd.benchmark.scenario_base import KEYS

    known = {*KEYS, "record"}  # a benchmark scenario's tables, or an identification's [record]
    unknown = [t for t in data if t not in known]
    if unknown:  # as validate and the benchmark refuse it: [arms] is no [arm] with a typo read as none
        raise ScenarioError(f"{path}: [{unknown[0]}]: unknown table; allowed: {', '.join(sorted(known))}")
    table = data.get("arm")
    if general:
        if not (isinstance(table, dict) and ("urdf" in table or "robot" in table)):
            raise ScenarioError(
                f"{path}: {general} needs an [arm] from a URDF (urdf = ... or robot = ...); for the "
                'paper\'s arm use robot = "sice_arm"'
            )
        table = {**table, "general": True}
    if repair_inertia and isinstance(table, dict):
        table = {**table, "repair_inertia": True}
    plant = data.get("plant")
    law = {k: v for k, v in plant.items() if k not in PLANT_TRUTH_KEYS} if isinstance(plant, dict) else plant
    arm = arm_from_tables(table, law, str(path))
    return model_and_plant(str(path), arm, plant if isinstance(plant, dict) else None, data.get("model"))[0]


def describe_arm(arm) -> str:
    """What ``validate`` prints of a URDF arm: its URDF's notes, joints, base parameters, payload subspace."""
    lines = [f"# arm: {arm.urdf} ({arm.n_joints} joints, payload frame '{arm.payload_frame}')"]
    lines += [f"# note: {note}" for note in arm.urdf_notes]  # what the URDF had that is unusual, kept
    lim = arm.position_limits
    for j, name in enumerate(arm.joint_names):
        lines.append(
            f"#   joint{j + 1} {name}: limits [{lim[j, 0]:.4g}, {lim[j, 1]:.4g}], velocity "
            f"{arm.velocity_limits[j]:.4g}, effort {arm.actuator.torque_limit[j]:.4g}, viscous "
            f"{arm.viscous[j]:.4g}, Coulomb {arm.coulomb[j]:.4g}, armature {arm.armature[j]:.4g}"
        )
    if arm.locked:
        lines.append(f"#   locked at 0 (off the chain): {', '.join(arm.locked)}")
    lines.append(f"# base parameters: {arm.base.count} of {13 * arm.n_joints} standard")
    for k, (name, v) in enumerate(zip(arm.sigma_names, arm.sigma, strict=True)):
        lines.append(f"#   sigma[{k}] = {v:.6g}: {name}")
    if arm.base.unidentifiable:
        lines.append(f"# no torque depends on: {', '.join(arm.base.unidentifiable)}")
    names = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
    seen = [n for n, ok in zip(names, arm.payload_identifiable, strict=True) if ok]
    lines.append(
        f"# payload subspace: rank {arm.payload_rank} of 10; determined by the base parameters: "
        f"{', '.join(seen)}"
    )
    return "\n".join(lines)


IDENTIFICATION_TABLES = ("arm", "plant", "record")
"""The tables of an identification scenario (one with ``[record]``): what ``identify``, ``predict``
and ``validate`` read of it."""


def identification_tables(path, data: dict) -> None:
    """Refuse an identification scenario (``data`` holds ``[record]``) with any other table than
    :data:`IDENTIFICATION_TABLES`: a benchmark's ``[run]`` or ``[reference]`` there would be read
    by nothing. Same rule in ``validate``, ``identify`` and ``predict``.

    Raises
    ------
    ScenarioError
        Naming the file and the first such table.
    """
    from adaptive_dd.errors import ScenarioError

    extra = [k for k in data if k not in IDENTIFICATION_TABLES] if "record" in data else []
    if extra:
        raise ScenarioError(
            f"{path}: [{extra[0]}]: an identification scenario (with [record]) holds only "
            f"{', '.join(f'[{t}]' for t in IDENTIFICATION_TABLES)}; keep benchmark tables in another file"
        )


def read_arm_log(scenario: str, arm, files=None, window=None):
    """The scenario's :class:`~adaptive_dd.record.RecordSpec` and the log it describes, read."""
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.io import read_toml
    from adaptive_dd.record import read_log, record_spec

    data = read_toml(Path(scenario), ScenarioError)
    identification_tables(scenario, data)
    table = data.get("record")
    spec = record_spec(table, arm.joint_names, arm.joint_kinds, str(scenario), files=files)
    return spec, read_log(spec, window=tuple(window) if window else None, arm=arm)
