"""``adaptive-dd check``: the arm's dynamics against Pinocchio, on random states.

Every option applies to every arm: the paper's arm (no ``--arm``, or a scenario whose arm is the
paper's kind) is checked through its closed forms (eqs. 3-9), any other arm through the
general kernels; with ``--arm`` without payload and with one (``--payload``, or 2 kg).
"""

from __future__ import annotations

import argparse

import numpy as np

from adaptive_dd.cli._common import MASS, RADIUS, SEED, add_command, closed_form_view, load_arm, number

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """The options of ``check``."""
    c = add_command(sub, "check", help="cross-check the dynamics against Pinocchio")
    c.add_argument(
        "--payload",
        type=MASS,
        default=None,
        metavar="KG",
        help="tip disk mass [kg] (default 0; with --arm the arm is checked without payload and with "
        "this one, default 2 kg)",
    )
    c.add_argument("--radius", type=RADIUS, help="tip disk radius [m] (default: the arm's)")
    c.add_argument(
        "--arm", metavar="SCENARIO", help="check the [arm] of a scenario TOML, with and without payload"
    )
    c.add_argument("--states", type=number(int, 1, 100_000), default=200, help="number of random states")
    c.add_argument("--seed", type=SEED, default=0, help="seed of the random states (default 0)")
    c.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Check each payload; 1 if any check failed."""
    arm = load_arm(args.arm)
    radius = arm.payload_radius if args.radius is None else args.radius
    # with --arm: the arm without payload and with one (--payload, or 2 kg)
    if args.arm:  # an explicit --payload 0 is one check, without payload (it was replaced by 2 kg)
        masses = [0.0] if args.payload == 0.0 else [0.0, 2.0 if args.payload is None else args.payload]
    else:
        masses = [args.payload or 0.0]
    failed = 0
    for mass in masses:
        label = f"payload {mass} kg, radius {radius} m" if mass else "no payload"
        where = f"arm of {args.arm}" if args.arm else "the SICE arm"
        two = closed_form_view(arm)  # the paper's closed forms, checked through them
        results = (
            _check_arm(args, arm, mass, radius, where, label)
            if two is None
            else _check_two_link(args, two, mass, radius, where, label)
        )
        for r in results:
            print("  " + str(r))
        bad = [r for r in results if not r.passed]
        print(f"{len(results) - len(bad)} passed, {len(bad)} failed")
        failed += len(bad)
    return 1 if failed else 0


def _check_arm(args, arm, mass: float, radius: float, where: str, label: str) -> list:
    from adaptive_dd.plant.pinocchio_check import cross_check

    print(
        f"Cross-check against Pinocchio ({where}: {arm.n_joints} joints of {arm.urdf.name}, "
        f"{label} at '{arm.payload_frame}', {args.states} random states)"
    )
    return cross_check(
        arm,
        {"mass": mass, "radius": radius} if mass else None,
        n_states=args.states,
        rng=np.random.default_rng(args.seed),
    )


def _check_two_link(args, arm, mass: float, radius: float, where: str, label: str) -> list:
    from adaptive_dd.plant.parameters import Payload
    from adaptive_dd.plant.pinocchio_model import two_link_cross_check

    print(
        f"Cross-check of adaptive_dd.plant against Pinocchio ({where}, {label}, {args.states} random states)"
    )
    if arm.physical is None:
        print("  (sigma-only arm: Pinocchio model built from ClosedFormTwoLink.equivalent_physical())")
    payload = Payload(mass, radius) if mass else None
    return two_link_cross_check(arm, payload, n_states=args.states, rng=np.random.default_rng(args.seed))
