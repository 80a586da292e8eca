"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark}``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

__all__ = ["main"]


def _cmd_check(args: argparse.Namespace) -> int:
    from adaptive_dd.plant.parameters import TABLE1_PHYSICAL, Payload
    from adaptive_dd.plant.pinocchio_model import cross_check

    payload = Payload(args.payload, args.radius) if args.payload else None
    label = f"payload {args.payload} kg" if payload else "no payload"
    print(f"Cross-check of adaptive_dd.plant against Pinocchio ({label}, {args.states} random states)")
    results = cross_check(
        TABLE1_PHYSICAL, payload, n_states=args.states, rng=np.random.default_rng(args.seed)
    )
    for r in results:
        print("  " + str(r))
    failed = [r for r in results if not r.passed]
    print(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    return 1 if failed else 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.simulator import (
        ActuatorConfig,
        PayloadSchedule,
        SensorConfig,
        simulate_open_loop,
    )
    from adaptive_dd.plotting import plot_trajectory

    n = round(args.duration / args.sample_period)
    tau = table2_torque(args.seeds, n, args.sample_period)
    sensor = SensorConfig(
        quantize=not args.no_quantize,
        position_variance=(0.0, 0.0) if args.no_noise else TABLE2["position_variance"],
        velocity_variance=(0.0, 0.0) if args.no_noise else TABLE2["velocity_variance"],
    )
    actuator = ActuatorConfig(saturate=not args.no_saturate, quantize=not args.no_quantize)
    payload = PayloadSchedule(initial_mass=args.payload, radius=args.radius)
    res = simulate_open_loop(
        tau,
        trial_rngs(args.seed, args.seeds),
        sample_period=args.sample_period,
        substeps=args.substeps,
        payload=payload,
        sensor=sensor,
        actuator=actuator,
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    res.save(str(out / "trajectory.npz"))
    write_recording(out / "trajectory.csv", res.t, res.q_meas[0], res.qd_meas[0], res.tau[0])
    plot_trajectory(res, out / "trajectory.png")
    print(
        f"Table 2 experiment: 1 Hz sine torques {TABLE2['amplitude']} N m, {args.duration} s at "
        f"T = {args.sample_period} s, payload {args.payload} kg, {args.seeds} trial(s)"
    )
    print(f"  max |q|   [rad]    : {np.abs(res.q).max(axis=(0, 1)).round(4)}")
    print(f"  max |qd|  [rad/s]  : {np.abs(res.qd).max(axis=(0, 1)).round(4)}")
    print(f"  rms tau   [N m]    : {np.sqrt((res.tau**2).mean(axis=(0, 1))).round(4)}")
    print(f"  stuck fraction     : {(res.qd == 0).mean(axis=(0, 1)).round(4)}")
    print(f"  saturated fraction : {res.saturated.mean(axis=(0, 1)).round(4)}")
    print(f"  failed trials      : {int(res.failed.sum())}")
    print(
        f"wrote {out / 'trajectory.npz'} (all trials), {out / 'trajectory.csv'} (trial 0, "
        f"measured), {out / 'trajectory.png'}"
    )
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("check", help="cross-check the dynamics against Pinocchio")
    c.add_argument("--payload", type=float, default=0.0, metavar="KG", help="tip disk mass [kg]")
    c.add_argument("--radius", type=float, default=0.05, help="tip disk radius [m]")
    c.add_argument("--states", type=int, default=200, help="number of random states")
    c.add_argument("--seed", type=int, default=0)
    c.set_defaults(func=_cmd_check)

    s = sub.add_parser("simulate", help="simulate the paper's open-loop Table 2 experiment")
    s.add_argument("--duration", type=float, default=10.0, help="[s] (default 10)")
    s.add_argument("--sample-period", type=float, default=1e-3, help="T [s] (default 0.001)")
    s.add_argument("--substeps", type=int, default=2, help="RK4 steps per sample")
    s.add_argument("--seeds", type=int, default=1, help="number of trials (noise seeds)")
    s.add_argument("--seed", type=int, default=0, help="base seed")
    s.add_argument("--payload", type=float, default=0.0, metavar="KG")
    s.add_argument("--radius", type=float, default=0.05)
    s.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    s.add_argument("--no-quantize", action="store_true", help="no encoder or D/A quantization")
    s.add_argument("--no-saturate", action="store_true", help="no torque saturation")
    s.add_argument("--out", default="results/simulate", help="output folder")
    s.set_defaults(func=_cmd_simulate)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ValueError as exc:  # our errors subclass ValueError and name what was wrong
        print(f"adaptive-dd {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
