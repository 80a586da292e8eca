"""``adaptive-dd simulate``: a record of the arm to identify from, its truth known.

Two experiments (``--experiment``), each with one meaning on every arm it applies to:

- ``table2``: the paper's open-loop Table 2 experiment (1 Hz sine torques of the SICE arm's
  amplitudes, the payload a disk centred on the tip) on the closed forms' compiled plant. The
  paper's two-link arm only: open-loop torques of those amplitudes mean nothing on another arm
  (under gravity it falls), so it is refused there.
- ``reference``: the scenario's ``[reference]`` (without ``--arm``: the shipped ``payload_swap``
  scenario's) tracked by computed torque, on the arm's general model (a URDF arm of the paper's
  kind included; the SICE arm is :meth:`~adaptive_dd.plant.arm.Arm.sice`); any arm from a URDF.

The default is the paper's experiment on the paper's arm and the reference on any other.
``--duration``, ``--sample-period``, ``--substeps``, ``--seeds``, ``--seed``, ``--payload``,
``--radius``, ``--no-noise``, ``--no-quantize``, ``--no-saturate`` and ``--out`` mean the same in
both; ``--com``, ``--plant`` and ``--plant-seed`` are options of the reference experiment, refused
with ``table2``. ``--plant-seed K`` runs the robot the benchmark meets at seed index K (a scenario
with ``[plant.uncertainty]``: :func:`~adaptive_dd.plant.uncertainty.plant_draws`, the benchmark's
own draw), its parameters written to ``OUT/plant.json``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from adaptive_dd.cli._common import (
    MASS,
    PERIOD,
    RADIUS,
    SEED,
    SEEDS,
    SUBSTEPS,
    add_command,
    arm_file,
    arm_label,
    closed_form_view,
    load_arm,
    number,
    refuse,
)
from adaptive_dd.errors import ParameterError

__all__ = ["EXPERIMENTS", "add_parser", "run", "simulate_arm"]

EXPERIMENTS = ("table2", "reference")


PLANTS = ("model", "benchmark")
"""``--plant``'s values: the identification model, or the benchmark's plant."""


def _plant_name(value: str) -> str:
    """``--plant``'s value; ``serial`` (its name before 0.3) is read as ``benchmark``, with a warning."""
    if value == "serial":
        print("warning: --plant serial is deprecated; use --plant benchmark (same plant)", file=sys.stderr)
        return "benchmark"
    return value


def add_parser(sub) -> None:
    """The options of ``simulate``."""
    s = add_command(
        sub,
        "simulate",
        help="simulate an identification record: the paper's open-loop Table 2 experiment or the "
        "scenario's reference tracked",
    )
    s.add_argument(
        "--duration", type=number(float, 0.0, math.inf, lo_open=True), default=10.0, help="[s] (default 10)"
    )
    s.add_argument("--sample-period", type=PERIOD, default=1e-3, help="T [s] (default 0.001)")
    s.add_argument("--substeps", type=SUBSTEPS, default=2, help="RK4 steps per sample")
    s.add_argument("--seeds", type=SEEDS, default=1, help="number of trials (noise seeds)")
    s.add_argument("--seed", type=SEED, default=0, help="base seed")
    s.add_argument("--payload", type=MASS, default=0.0, metavar="KG")
    s.add_argument("--radius", type=RADIUS, help="tip disk radius [m] (default: the arm's)")
    s.add_argument(
        "--com",
        type=number(float, -1.0, 1.0),
        nargs=3,
        metavar="M",
        help="payload centre of mass in the payload frame [m] (--experiment reference; default 0 0 0)",
    )
    s.add_argument(
        "--arm",
        metavar="SCENARIO",
        help="simulate the [arm] and [plant] of a scenario TOML (default: the SICE arm)",
    )
    s.add_argument(
        "--experiment",
        choices=EXPERIMENTS,
        help="table2: the paper's open-loop Table 2 experiment (the paper's two-link arm only); "
        "reference: the scenario's [reference] tracked by computed torque, writes t, q1..qN, qd1..qdN, "
        "tau1..tauN (any arm from a URDF); default: table2 on the paper's arm, reference on any other",
    )
    s.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    s.add_argument("--no-quantize", action="store_true", help="no encoder or D/A quantization")
    s.add_argument("--no-saturate", action="store_true", help="no torque saturation")
    s.add_argument(
        "--plant",
        default="model",
        type=_plant_name,
        choices=PLANTS,
        help="--experiment reference: the identification model's RK4 with tanh friction (default) or the "
        "benchmark's compiled plant with the arm's friction law (stick-slip); 'serial', its old name, "
        "is read as 'benchmark' with a warning",
    )
    s.add_argument(
        "--plant-seed",
        type=SEED,
        metavar="K",
        help="--experiment reference on a scenario with [plant.uncertainty]: simulate the robot the "
        "benchmark meets at seed index K (the same draw and seed stream, numpy default_rng([[run] seed, K, "
        "2])), written to OUT/plant.urdf with its parameters in OUT/plant.json (default: the [plant] before "
        "any draw); the sensor noise stays --seed's",
    )
    s.add_argument("--out", default="results/simulate", help="output folder")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Check the run's size, then the paper's experiment or the N-joint record."""
    from adaptive_dd.benchmark.scenario import LIMITS, run_estimate
    from adaptive_dd.outputs import OutputSet

    if args.duration < 10 * args.sample_period:
        raise ParameterError(
            f"--duration {args.duration} s is shorter than 10 samples of {args.sample_period} s"
        )
    n = round(args.duration / args.sample_period)
    est = run_estimate(n, args.seeds, 1)
    if est.bytes > LIMITS["max_bytes"] or est.seconds > LIMITS["max_seconds"]:
        raise ParameterError(f"run too large: {est}; reduce --duration or --seeds")
    if est.large:
        print(f"estimate: {est}", file=sys.stderr)
    arm_file(args)
    arm = load_arm(args.arm)
    two = closed_form_view(arm)  # the paper's closed forms, or None
    experiment = args.experiment or ("table2" if two is not None else "reference")
    if experiment == "reference":
        _no_payload_place(args)
        with OutputSet(args.out) as outputs:
            return simulate_arm(args, args.arm, outputs)
    if two is None:
        raise ParameterError(
            f"--experiment table2: the paper's open-loop experiment (sine torques of the SICE arm's "
            f"amplitudes) is for the paper's two-link arm; the {arm_label(args.arm, arm)} tracks its "
            "scenario's [reference] (--experiment reference)"
        )
    refuse(
        args,
        ("--com", "--plant", "--plant-seed"),
        "options of --experiment reference (an arm from a URDF tracking its scenario's [reference]); "
        f"the {arm_label(args.arm, arm)} runs the paper's Table 2 experiment on its own plant (the "
        "payload a disk centred on the tip)",
    )
    from adaptive_dd.benchmark.scenario import read_toml

    _no_payload_place(args)
    if args.arm and args.experiment is None and "reference" in read_toml(args.arm):
        print(  # a designed trajectory (excite's) is not what table2 runs: said, not silently passed over
            f"note: {args.arm}'s [reference] is not used: the paper's arm runs the Table 2 experiment by "
            "default (open-loop sine torques); --experiment reference tracks the [reference]"
        )
    with OutputSet(args.out) as outputs:
        return _table2(args, two, n, outputs)


def _no_payload_place(args: argparse.Namespace) -> None:
    """``--com`` and ``--radius`` place a payload: without ``--payload`` (0 kg) refused, not ignored."""
    if not args.payload:
        why = "where and how large the payload is; without --payload KG (0 kg) there is none"
        refuse(args, ("--com", "--radius"), why)


def _table2(args: argparse.Namespace, arm, n: int, outputs) -> int:
    """The paper's open-loop Table 2 experiment on a two-link arm."""
    import dataclasses

    from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.simulator import PayloadSchedule, simulate_open_loop
    from adaptive_dd.plotting import plot_trajectory

    tau = table2_torque(args.seeds, n, args.sample_period)
    sensor = dataclasses.replace(
        arm.sensor,
        quantize=not args.no_quantize,
        position_variance=(0.0, 0.0) if args.no_noise else TABLE2["position_variance"],
        velocity_variance=(0.0, 0.0) if args.no_noise else TABLE2["velocity_variance"],
    )
    actuator = dataclasses.replace(arm.actuator, saturate=not args.no_saturate, quantize=not args.no_quantize)
    res = simulate_open_loop(
        tau,
        trial_rngs(args.seed, args.seeds),
        arm=arm,
        sample_period=args.sample_period,
        substeps=args.substeps,
        payload=PayloadSchedule(initial_mass=args.payload, radius=args.radius),
        sensor=sensor,
        actuator=actuator,
    )
    res.save(str(outputs.path("trajectory.npz")))
    write_recording(outputs.path("trajectory.csv"), res.t, res.q_meas[0], res.qd_meas[0], res.tau[0])
    plot_trajectory(res, outputs.path("trajectory.png"))
    _print_table2(args, arm, res, TABLE2)
    return 0


def _print_table2(args: argparse.Namespace, arm, res, table2: dict) -> None:
    print(
        f"Table 2 experiment: 1 Hz sine torques {table2['amplitude']} N m, {args.duration} s at "
        f"T = {args.sample_period} s, payload {args.payload} kg, {args.seeds} trial(s)"
    )
    print(f"  arm: {args.arm or 'SICE'} (l1 = {arm.l1} m, l2 = {arm.l2} m), plant friction {arm.friction}")
    print(f"  max |q|   [rad]    : {np.abs(res.q).max(axis=(0, 1)).round(4)}")
    print(f"  max |qd|  [rad/s]  : {np.abs(res.qd).max(axis=(0, 1)).round(4)}")
    print(f"  rms tau   [N m]    : {np.sqrt((res.tau**2).mean(axis=(0, 1))).round(4)}")
    print(f"  stuck fraction     : {(res.qd == 0).mean(axis=(0, 1)).round(4)}")
    print(f"  saturated fraction : {res.saturated.mean(axis=(0, 1)).round(4)}")
    print(f"  failed trials      : {int(res.failed.sum())}")
    out = Path(args.out)
    print(
        f"wrote {out / 'trajectory.npz'} (all trials), {out / 'trajectory.csv'} (trial 0, "
        f"measured), {out / 'trajectory.png'}"
    )


def simulate_arm(args: argparse.Namespace, scenario_path: str, outputs) -> int:
    """``adaptive-dd simulate --arm SCENARIO`` for an N-joint arm: identification records, truth known."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.experiments import trial_rngs
    from adaptive_dd.identification.records import simulate_record
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.arm import payload_parameters

    sc = load_scenario(scenario_path)
    arm = _record_arm(args, sc, scenario_path, outputs)
    where = (
        f"{arm.n_joints}-joint arm of {scenario_path}"
        if scenario_path
        else "the SICE arm (2 joints; the reference of the shipped payload_swap.toml)"
    )
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
    write_recording(outputs.path("trajectory.csv"), rec.t, rec.q[0], rec.qd[0], rec.tau[0])
    _write_made_by(outputs.path("trajectory.json"), arm, getattr(args, "plant", "model"), payload)
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
    _print_record(args, arm, sc, rec, where, payload)
    return 0


def _record_arm(args: argparse.Namespace, sc, scenario_path: str, outputs):
    """The arm simulated: the general model of the scenario's arm, its ``[plant]`` where it has one
    (written to OUT/plant.urdf), with the sensor's quantization and the actuator's saturation as the
    options say."""
    import dataclasses

    arm = sc.arm
    if closed_form_view(arm) is not None:  # the paper's kind: its general model
        arm = load_arm(scenario_path, general="--experiment reference")
    if sc.plant is not None:  # the scenario's robot is not its [arm]: simulate the robot
        from adaptive_dd.plant.urdf_write import write_urdf_links

        p = _drawn_plant(args, sc, scenario_path, outputs)
        path = write_urdf_links(arm, p.pi_links, outputs.path("plant.urdf"), f"the plant of {scenario_path}")
        t = lambda x: tuple(float(v) for v in x)  # noqa: E731
        arm = arm.with_(urdf=path, viscous=t(p.viscous), coulomb=t(p.coulomb), armature=t(p.armature))
    elif getattr(args, "plant_seed", None) is not None:
        raise ParameterError(
            f"--plant-seed {args.plant_seed}: {scenario_path or 'the SICE arm'} draws no plant (no "
            "[plant.uncertainty]): every benchmark seed meets the [arm] itself; drop --plant-seed"
        )
    if arm.sensor.quantize == args.no_quantize:
        arm = arm.with_(sensor=dataclasses.replace(arm.sensor, quantize=not args.no_quantize))
    if arm.actuator.saturate == args.no_saturate:
        arm = arm.with_(actuator=dataclasses.replace(arm.actuator, saturate=not args.no_saturate))
    return arm


def _drawn_plant(args: argparse.Namespace, sc, scenario_path: str, outputs):
    """The plant simulated (a :class:`~adaptive_dd.plant.uncertainty.PlantDraw`): the scenario's
    ``[plant]`` before any draw, or with ``--plant-seed K`` the robot the benchmark meets at seed
    index K (:func:`~adaptive_dd.plant.uncertainty.plant_draws`, the benchmark's own draw), its
    parameters written to OUT/plant.json; says which on stdout."""
    import json

    from adaptive_dd.plant.uncertainty import plant_draws

    spec, out, k = sc.plant, Path(args.out), getattr(args, "plant_seed", None)
    if k is None:
        print(
            f"the plant: the scenario's [plant] before any draw, written to {out / 'plant.urdf'}"
            + (
                " ([plant.uncertainty] draws a plant per benchmark seed: --plant-seed K simulates seed K's)"
                if spec.uncertainty
                else ""
            )
        )
        return spec.nominal()
    if spec.uncertainty is None:
        raise ParameterError(
            f"--plant-seed {k}: {scenario_path} draws no plant (no [plant.uncertainty]): every benchmark "
            "seed meets the [plant] itself; drop --plant-seed"
        )
    nominal, drawn = spec.nominal(), plant_draws(sc, [k])[0]
    masses = zip(drawn.pi_links[0::10], nominal.pi_links[0::10], strict=True)  # each link's mass first
    mass_error = [float(m / m0 - 1.0) if m0 > 0 else 0.0 for m, m0 in masses]
    with open(outputs.path("plant.json"), "w", encoding="utf-8") as f:
        json.dump(
            {
                "scenario": str(scenario_path),
                "seed_index": int(k),
                "seed_rule": f"numpy.random.default_rng([{int(sc.seed)}, {int(k)}, 2]): [run] seed, K, 2",
                "mass_relative_error": mass_error,
                "drawn": drawn.to_dict(),
                "nominal": nominal.to_dict(),
            },
            f,
            indent=2,
        )
    print(
        f"the plant: the robot of the benchmark's seed index {k} (drawn from [plant.uncertainty] as the "
        f"benchmark draws it), written to {out / 'plant.urdf'}, its parameters and the [plant]'s in "
        f"{out / 'plant.json'}; link masses against the [plant]'s [%]: "
        f"{np.round(100 * np.array(mass_error), 2).tolist()}"
    )
    return drawn


def _write_made_by(path, arm, plant: str, payload=None) -> None:
    """``trajectory.json`` beside the record: how its plant's friction was simulated, which
    ``adaptive-dd identify`` reads to fit the same Coulomb law (``--coulomb-width auto``), and the
    payload simulated (None: none): its mass, centre of mass and inertia about it, the truth an
    identified payload is checked against."""
    import json

    model = plant != "benchmark"  # the identification model's RK4: fc tanh(qd / v_f)
    made = {
        "plant": "model" if model else "benchmark",
        "coulomb_law": "tanh" if model else arm.friction,
        "friction_velocity": float(arm.friction_velocity) if model or arm.friction == "tanh" else None,
        "payload": None if payload is None else _payload_truth(payload),
    }
    with open(path, "w", encoding="utf-8") as f:
        json.dump(made, f, indent=2)


def _payload_truth(p) -> dict:
    """The payload of ten parameters ``p`` (about the payload frame) as mass, centre of mass and
    inertia about it (``[ixx, iyy, izz, ixy, ixz, iyz]``), as ``identify`` prints and writes them."""
    from adaptive_dd.identification.payload_pair import _inertia_about_com, six

    p = np.asarray(p, float)
    ic = _inertia_about_com(p)
    return {
        "mass_kg": float(p[0]),
        "com_m": [float(x) for x in p[1:4] / p[0]],
        "inertia_com_kg_m2": six(ic),
        "params": [float(x) for x in p],
    }


def _print_record(args: argparse.Namespace, arm, sc, rec, where: str, payload=None) -> None:
    plant = getattr(args, "plant", "model")
    print(
        f"{where}: the scenario's reference tracked by computed torque "
        f"(the plant's own model, 40 rad/s), {args.duration} s at T = {args.sample_period} s, payload "
        f"{args.payload} kg"
        + (f" at [{', '.join(f'{c:g}' for c in args.com)}] m" if args.payload and args.com else "")
        + (
            " (inertia about its centre of mass [ixx, iyy, izz] "
            f"{[float(f'{x:.4g}') for x in _payload_truth(payload)['inertia_com_kg_m2'][:3]]} kg m^2)"
            if payload is not None
            else ""
        )
        + f", {args.seeds} trial(s), "
        + (
            f"the benchmark's plant, friction {arm.friction}"
            if plant == "benchmark"
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
        f"wrote {out / 'trajectory.csv'} (trial 0, measured), {out / 'trajectory.json'} (how it was "
        f"simulated), {out / 'trajectory.npz'} (all trials and "
        "the truth)"
    )
