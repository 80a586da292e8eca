"""``adaptive-dd identify``: the arm's parameters from a record.

The paper's arm (no ``--arm``, or a scenario whose arm is the paper's kind) is identified from
one CSV by the paper's estimators on its seven base parameters (eq. 9), with the Cramér-Rao
bound beside (:mod:`adaptive_dd.cli._identify_two_link`); any other arm from its log, read as
the scenario's ``[record]`` says, by weighted least squares and output error
(:mod:`adaptive_dd.cli._identify_log`). The options of one path are refused on the other.
"""

from __future__ import annotations

import argparse

from adaptive_dd.cli._common import (
    POS,
    add_command,
    add_window_option,
    arm_file,
    arm_label,
    closed_form_view,
    load_arm,
    number,
    refuse,
)

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The options of ``identify``."""
    i = add_command(sub, "identify", help="estimate sigma from a recorded experiment (CSV)")
    i.add_argument(
        "data",
        nargs="*",
        help="CSV with header t,q1,q2,qd1,qd2,tau1,tau2 (qd optional for M1); with --arm: the log's file(s), "
        "read as the scenario's [record] says (default: its record.files); several records are fitted "
        "jointly, each as many files as record.files names, or a TOML with its own [record]; gaps are split "
        "into continuous pieces (docs/real_log.md)",
    )
    _add_two_link_options(i)
    i.add_argument(
        "--arm",
        metavar="SCENARIO",
        help="a scenario TOML with [arm] from a URDF and, for a real log, [record] (default: CSV t, q1..qN, "
        "[qd1..qdN,] tau1..tauN); prints weighted least squares with Newey-West std, output error where "
        "the record can be simulated; writes OUT/model.json (docs/real_log.md)",
    )
    _add_arm_options(i)
    i.add_argument("--out", default="results/identify", help="folder (with --arm: model.json, estimates.csv)")
    i.set_defaults(func=run)


def _add_two_link_options(i: argparse.ArgumentParser) -> None:
    from adaptive_dd.experiments import TABLE2
    from adaptive_dd.identification.estimators import ESTIMATORS

    i.add_argument(
        "--estimator",
        default="exact",
        choices=(*ESTIMATORS, "output_error"),
        help="output_error: maximum likelihood started from 'exact' (needs qd)",
    )
    i.add_argument("--method", default="M2", choices=("M1", "M2"))
    i.add_argument("--split", default="15", choices=("15", "16", "full"), help="split of 'paper'")
    i.add_argument(
        "--tau-f",
        type=POS,
        default=None,
        help="filter time constant [s] (default: 2 sample periods, at least 0.02)",
    )
    i.add_argument(
        "--true", type=number(float, -1e6, 1e6), nargs=7, metavar="S", help="true sigma, to mark on the plot"
    )
    for option, what, default, table in (
        ("--position-variance", "q1, q2 [rad^2]", "position_variance", "Table 2"),
        ("--velocity-variance", "qd1, qd2 [(rad/s)^2]", "velocity_variance", "Table 4"),
    ):
        i.add_argument(
            option,
            type=number(float, 0.0, 1.0, lo_open=True),  # a variance of 0 makes no bound
            nargs=2,
            default=list(TABLE2[default]),
            metavar="V",
            help=f"noise variance of {what} for the bound (default: {table})",
        )
    i.add_argument(
        "--online",
        action="store_true",
        help="run the online estimator of adaptive_ct (change detection included) over the record; "
        "writes online.csv (estimates, payload mass and alarms over time) and online.png",
    )


def _add_arm_options(i: argparse.ArgumentParser) -> None:
    i.add_argument(
        "--baseline",
        nargs="+",
        metavar="CSV",
        help="with --arm: the unloaded record(s)' file(s), read through the same [record] (several records "
        "fitted jointly); prints the payload and writes OUT/payload.json",
    )
    i.add_argument(
        "--payload-only",
        action="store_true",
        help="with --arm: the arm known (URDF), fit the payload alone; printed, and written to "
        "OUT/payload.json when --out is given",
    )
    i.add_argument(
        "--segment-length",
        type=number(int, 10, 10**6),
        default=200,
        help="with --arm: output-error segment length [samples] (default 200)",
    )
    i.add_argument(
        "--max-iter", type=number(int, 1, 1000), default=30, help="with --arm: output-error iterations"
    )
    add_window_option(i)
    i.add_argument(
        "--repair-inertia",
        action="store_true",
        help="with --arm: repair chain links whose URDF inertia is not a rigid body's (reported)",
    )
    i.add_argument(
        "--hold-unseen",
        choices=("on", "off"),
        default="on",
        help="with --arm: hold at the URDF's values the directions of the base parameters the record cannot "
        "see (the estimate's std along them above the prior's; default on; off: every direction estimated)",
    )
    i.add_argument(
        "--coulomb-width",
        type=coulomb_width_option,
        default="auto",
        metavar="auto|noise|profile|V",
        help="with --arm: the width v of the Coulomb law fc tanh(qd / v) [rad/s]. auto (default): on a "
        "record of `simulate` with its trajectory.json, the width it was simulated with (noise for a law "
        "with a sign); else profile (noise with --payload-only); noise: the record's velocity noise (of "
        "velocities derived from the positions: the positions' noise through the derivative; the arm's "
        "friction_velocity if its law is tanh); profile: per fitted "
        "joint, the width of the record's profile likelihood over a grid (printed with its 95 %% interval; "
        "docs/real_log.md); V > 0: that width for every joint",
    )
    i.add_argument(
        "--torque-offset",
        choices=("auto", "on", "off"),
        default="auto",
        help="with --arm: fit a constant offset per torque channel with the parameters (a sensor's zero; "
        "stored in model.json, added by predict). auto (default): on for a record read through a [record] "
        "table, off for the simulator's records",
    )
    i.add_argument(
        "--output-error",
        choices=("auto", "on", "off"),
        default="auto",
        help="with --arm: output error beside the WLS estimate (the model written is output error's where "
        "it converged with its noise model, normalised residual <= 2, else the WLS one; auto: for records "
        "in the simulator's format only)",
    )


def coulomb_width_option(text: str):
    """``--coulomb-width``: ``"auto"``, ``"noise"``, ``"profile"`` or a width in (0, 10] rad/s (a float)."""
    if text in ("auto", "noise", "profile"):
        return text
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (0.0 < v <= 10.0):  # NaN and inf fail too
        raise argparse.ArgumentTypeError(
            f"{text!r} is not 'auto', 'noise', 'profile' or a width in (0, 10] rad/s"
        )
    return v


TWO_LINK_OPTIONS = (
    "--estimator",
    "--method",
    "--split",
    "--true",
    "--online",
    "--position-variance",
    "--velocity-variance",
)
"""Options of the paper's identification (:mod:`adaptive_dd.cli._identify_two_link`), refused on
any other arm."""
ARM_OPTIONS = (
    "--baseline",
    "--payload-only",
    "--window",
    "--repair-inertia",
    "--output-error",
    "--segment-length",
    "--max-iter",
    "--hold-unseen",
    "--coulomb-width",
    "--torque-offset",
)
"""Options of the identification of any arm from a log (:mod:`adaptive_dd.cli._identify_log`),
refused on the paper's arm."""


def run(args: argparse.Namespace) -> int:
    """Refuse the other path's options, then identify on the arm's path."""
    from adaptive_dd.errors import DataError

    arm_file(args)
    arm = load_arm(args.arm, args.repair_inertia)
    two = closed_form_view(arm)  # the paper's closed forms, or None
    if two is not None:
        from adaptive_dd.cli._identify_two_link import identify_two_link

        why = (
            "only with --arm SCENARIO of an arm from a URDF, identified by weighted least squares; the "
            f"{arm_label(args.arm, arm)} is identified by the paper's estimators ([arm] general = true "
            "takes a URDF of the paper's kind to the general path)"
        )
        refuse(args, ARM_OPTIONS, why, DataError)
        if args.online:  # the online estimator of adaptive_ct runs with its own settings
            refuse(
                args,
                ("--estimator", "--method", "--split", "--position-variance", "--velocity-variance"),
                "options of the batch estimators; --online runs adaptive_ct's online estimator with its own "
                "settings (drop --online to use them)",
                DataError,
            )
        if args.estimator != "paper":  # the splits are the paper's estimator's: the others fit all seven
            refuse(args, ("--split",), f"a split of the paper's estimator; --estimator {args.estimator} "
                   "fits the seven parameters at once (add --estimator paper)", DataError)  # fmt: skip
        return identify_two_link(args, two)
    from adaptive_dd.cli._identify_log import identify_log
    from adaptive_dd.outputs import OutputSet

    refuse(
        args,
        TWO_LINK_OPTIONS,
        "options of the two-link identification; an N-joint arm from a URDF (--arm) is identified by "
        "weighted least squares (docs/real_log.md)",
        DataError,
    )
    if args.output_error == "off":
        refuse(
            args,
            ("--segment-length", "--max-iter"),
            "options of the output error, which --output-error off skips",
            DataError,
        )
    if args.payload_only:  # prints the payload fitted on the known arm; payload.json with --out
        refuse(
            args,
            ("--baseline",),
            "--payload-only fits the payload of one record on the known arm; --baseline fits a loaded "
            "and an unloaded record instead (without --payload-only)",
            DataError,
        )
        refuse(
            args,
            ("--output-error", "--hold-unseen"),
            "--payload-only fits the payload by output error alone, the arm held at its URDF's values (no "
            "least squares, nothing held or skipped)",
            DataError,
        )
        if "--out" not in getattr(args, "given", ()):
            return identify_log(args, arm, None)  # printed only: no output folder made
        with OutputSet(args.out) as outputs:
            return identify_log(args, arm, outputs)
    if args.baseline:  # before the loaded record's fit, not after it
        from adaptive_dd.identification.payload_pair import payload_seen

        payload_seen(arm, "a loaded and an unloaded record (--baseline)")
    with OutputSet(args.out) as outputs:
        return identify_log(args, arm, outputs)
