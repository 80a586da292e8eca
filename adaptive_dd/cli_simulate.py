"""The N-joint commands of the CLI: ``simulate --arm`` and ``excite`` for an Arm.

Kept apart from :mod:`adaptive_dd.cli` (which parses the arguments and dispatches here
when a scenario's arm is an :class:`~adaptive_dd.plant.arm.Arm`);
``identify --arm`` and ``predict`` are in :mod:`adaptive_dd.cli_log`.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["cmd_excite", "simulate_arm"]

Array = NDArray[np.float64]
NAME_WIDTH = 44


def _short(name: str) -> str:
    return name if len(name) <= NAME_WIDTH else name[: NAME_WIDTH - 3] + "..."


def simulate_arm(args: argparse.Namespace, scenario_path: str, outputs) -> int:
    """``adaptive-dd simulate --arm SCENARIO`` for an N-joint arm: identification records, truth known."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.experiments import trial_rngs
    from adaptive_dd.identification.records import simulate_record, write_serial_recording
    from adaptive_dd.plant.arm import payload_parameters

    sc = load_scenario(scenario_path)
    arm = sc.arm
    if sc.plant is not None:  # the scenario's robot is not its [arm]: simulate the robot
        from adaptive_dd.plant.urdf_write import write_urdf_links

        p = sc.plant
        path = write_urdf_links(arm, p.pi_links, outputs.path("plant.urdf"), f"the plant of {scenario_path}")
        arm = arm.with_(urdf=path, viscous=p.viscous, coulomb=p.coulomb, armature=p.armature)
        print(
            f"the plant: the scenario's [plant] before any draw, written to {Path(args.out) / 'plant.urdf'}"
            + (" ([plant.uncertainty] draws a plant per benchmark seed; not here)" if p.uncertainty else "")
        )
    if arm.sensor.quantize == args.no_quantize:
        import dataclasses

        arm = arm.with_(sensor=dataclasses.replace(arm.sensor, quantize=not args.no_quantize))
    radius = arm.payload_radius if args.radius is None else args.radius
    payload = (
        payload_parameters(args.payload, args.com or [0.0, 0.0, 0.0], radius=radius) if args.payload else None
    )
    rec = simulate_record(
        arm,
        sc.reference,
        args.duration,
        trial_rngs(args.seed, args.seeds),
        sample_period=args.sample_period,
        payload=payload,
        substeps=args.substeps,
        noise=not args.no_noise,
        quantize=not args.no_quantize,
        plant=getattr(args, "plant", "model"),
    )
    write_serial_recording(outputs.path("trajectory.csv"), rec.t, rec.q[0], rec.qd[0], rec.tau[0])
    np.savez_compressed(
        outputs.path("trajectory.npz"),
        t=rec.t,
        q=rec.q,
        qd=rec.qd,
        tau=rec.tau,
        q_true=rec.q_true,
        qd_true=rec.qd_true,
        sigma_true=rec.sigma_true,
        pi_true=rec.pi_true,
        payload=rec.payload,
    )
    print(
        f"{arm.n_joints}-joint arm of {scenario_path}: the scenario's reference tracked by computed torque "
        f"(the plant's own model, 40 rad/s), {args.duration} s at T = {args.sample_period} s, payload "
        f"{args.payload} kg, {args.seeds} trial(s), "
        + (
            f"the benchmark's plant, friction {arm.friction}"
            if getattr(args, "plant", "model") == "serial"
            else f"the identification model (RK4, friction tanh, v_f = {arm.friction_velocity} rad/s)"
        )
    )
    print(
        "  max |q - q_ref| [rad] : "
        f"{np.abs(rec.q_true - sc.reference.sample(rec.t)[0]).max(axis=(0, 1)).round(4)}"
    )
    print(f"  max |qd|  [rad/s]     : {np.abs(rec.qd_true).max(axis=(0, 1)).round(3)}")
    print(f"  rms tau   [N m]       : {np.sqrt((rec.tau**2).mean(axis=(0, 1))).round(3)}")
    print(f"  saturated fraction    : {rec.saturated.max(axis=0).round(4)}")
    out = Path(args.out)
    print(
        f"wrote {out / 'trajectory.csv'} (trial 0, measured), {out / 'trajectory.npz'} (all trials and "
        "the truth)"
    )
    return 0


def cmd_excite(args: argparse.Namespace) -> int:
    """``adaptive-dd excite --arm SCENARIO``: design an exciting trajectory; its bound beside a multi-sine."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.identification.excitation import (
        ExcitationLimits,
        design_excitation,
        multisine,
        reference_toml,
    )
    from adaptive_dd.outputs import atomic_write, check_output_file
    from adaptive_dd.plant.arm import Arm

    arm = load_scenario(args.arm).arm
    if not isinstance(arm, Arm):
        arm = _general_arm(args.arm)
    out = check_output_file(args.out)  # before the design, not after it
    lim = ExcitationLimits.of_arm(arm, acceleration=args.acceleration, margin=args.margin)
    plain = multisine(arm, lim, args.harmonics, args.f0)
    best, res = design_excitation(
        arm,
        lim,
        harmonics=args.harmonics,
        f0=args.f0,
        maxiter=args.maxiter,
        rng=np.random.default_rng(args.seed),
    )
    rows = excitation_bounds(arm, {"plain multi-sine": plain, "designed": best}, args.duration)
    print(
        f"{arm.n_joints}-joint arm of {args.arm}: {args.harmonics} harmonics of {args.f0} Hz; limits: "
        "positions "
        f"less {args.margin} rad, {0.8:.0%} of velocity and torque limits, |qdd| <= {args.acceleration} "
        "rad/s^2"
    )
    print(f"SLSQP: {res.nit} iterations, {res.message}")
    print(f"{'trajectory':<18} {'worst bound':>12}  {'worst base parameter':<{NAME_WIDTH}} {'median':>9}")
    for label, (worst, name, med) in rows.items():
        print(f"{label:<18} {100 * worst:11.3g}%  {_short(name):<{NAME_WIDTH}} {100 * med:8.3g}%")
    bad = [label for label, (worst, _, _) in rows.items() if not np.isfinite(worst)]
    if bad:  # said, not printed as a ratio of NaNs
        print(
            f"warning: the bound of the {' and '.join(bad)} record is not finite: the identification "
            f"model's sensitivities diverge along it (a stiff friction model at T = 1 ms, or a record "
            "that leaves the arm's range): the two cannot be compared",
            file=sys.stderr,
        )
    else:
        ratio = rows["plain multi-sine"][0] / rows["designed"][0]
        print(
            f"the designed trajectory shrinks the worst bound {ratio:.1f}x (Cramér-Rao std of the "
            f"segmented output error on a {args.duration} s record tracking it, relative to each "
            "parameter's magnitude)"
        )
    text = reference_toml(best.reference(ramp=args.ramp), f"designed by adaptive-dd excite --arm {args.arm}")
    with atomic_write(out) as fh:
        fh.write(_replace_reference(Path(args.arm).read_text(), text))
    print(f"wrote {out} (the scenario with the designed [reference])")
    return 0


def _general_arm(path: str):
    """The scenario's URDF arm as the general model (a two-link URDF of the paper's kind loads as
    the closed forms' :class:`~adaptive_dd.plant.two_link.TwoLinkArm`, which has no URDF to excite)."""
    from adaptive_dd.benchmark.scenario import read_toml
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.plant.arm_tables import arm_from_tables

    data = read_toml(Path(path))
    table = data.get("arm")
    if not (isinstance(table, dict) and ("urdf" in table or "robot" in table)):
        raise ScenarioError(
            f"{path}: excite needs an [arm] from a URDF (urdf = ... or robot = ...); for the paper's "
            'arm use robot = "sice_arm"'
        )
    return arm_from_tables({**table, "general": True}, data.get("plant"), str(path))


def _replace_reference(src: str, table: str) -> str:
    """The scenario text with its ``[reference]`` table (if any) replaced by ``table``."""
    out, skip = [], False
    for line in src.splitlines():
        head = line.strip()
        if head.startswith("["):
            skip = head.startswith("[reference]")
        if not skip:
            out.append(line)
    return "\n".join(out).rstrip() + "\n\n" + table


def excitation_bounds(arm, trajectories: dict, duration: float) -> dict:
    """``{label: (worst relative bound, its parameter's name, median)}`` of each trajectory's record."""
    from adaptive_dd.identification.excitation import relative_bounds
    from adaptive_dd.identification.model import arm_model
    from adaptive_dd.identification.output_error import cramer_rao_bound, measurement_std
    from adaptive_dd.identification.records import simulate_record

    model = arm_model(arm)
    std = measurement_std(arm)
    out = {}
    for label, tr in trajectories.items():
        rec = simulate_record(arm, tr.reference(ramp=0.5), duration, [np.random.default_rng(0)], noise=False)
        crb, _ = cramer_rao_bound(model, rec.sigma_true, rec.q_true[0], rec.qd_true[0], rec.tau[0], std)
        rb = relative_bounds(crb, model.sigma_ref, model.names)
        k = int(np.argmax(rb))
        out[label] = (float(rb[k]), model.names[k], float(np.median(rb)))
    return out
