"""The N-joint commands of the CLI: ``identify --arm``, ``simulate --arm`` and ``excite`` for a SerialArm.

Kept apart from :mod:`adaptive_dd.cli` (which parses the arguments and dispatches here
when a scenario's arm is a :class:`~adaptive_dd.plant.serial_arm.SerialArm`).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError

__all__ = ["SerialIdentification", "cmd_excite", "identify_record", "identify_serial", "simulate_serial"]

Array = NDArray[np.float64]
NAME_WIDTH = 44


@dataclass(frozen=True)
class SerialIdentification:
    """Both estimates of one record: WLS on the exact filtered regression, then output error."""

    wls: object
    oe: object
    regression: object
    qd_measured: bool


def _velocity(rec, tau_f: float) -> Array:
    """Measured qd, or a Savitzky-Golay derivative of q (window ~ 2 tau_f) when not recorded."""
    if rec.qd is not None:
        return rec.qd
    from scipy.signal import savgol_filter

    win = max(5, 2 * round(tau_f / rec.sample_period) + 1)
    return savgol_filter(rec.q, win, 2, deriv=1, delta=rec.sample_period, axis=0)


def identify_record(
    arm, model, rec, *, tau_f: float, segment_length: int, max_iter: int
) -> SerialIdentification:
    """WLS then output error on one N-joint record (velocities estimated when not recorded).

    Raises
    ------
    DataError
        The record is too short, or does not excite some base parameter (named).
    """
    from adaptive_dd.identification.serial_output_error import measurement_std, serial_output_error
    from adaptive_dd.identification.serial_regression import (
        serial_filtered_regression,
        weighted_least_squares,
    )

    T = rec.sample_period
    if rec.t.size < max(2 * segment_length, 20 * tau_f / T):
        raise DataError(
            f"{rec.source}: {rec.t.size} samples; need at least two segments of {segment_length} and "
            f"20 tau_f = {20 * tau_f:.3g} s"
        )
    qd = _velocity(rec, tau_f)
    reg = serial_filtered_regression(model, rec.q, qd, rec.tau, tau_f=tau_f, sample_period=T)
    try:
        wls = weighted_least_squares(reg, model.names)
    except DataError as exc:
        raise DataError(f"{rec.source}: {exc}") from None
    std = measurement_std(arm)
    if rec.qd is None:  # velocities not measured: fit the positions alone
        std = std.copy()
        std[arm.n_joints :] = np.inf
    oe = serial_output_error(
        model,
        rec.q,
        qd,
        rec.tau,
        wls.sigma,
        std,
        sample_period=T,
        segment_length=segment_length,
        max_iter=max_iter,
    )
    return SerialIdentification(wls, oe, reg, rec.qd is not None)


def _short(name: str) -> str:
    return name if len(name) <= NAME_WIDTH else name[: NAME_WIDTH - 3] + "..."


def _print_estimates(model, ident: SerialIdentification) -> None:
    wls, oe = ident.wls, ident.oe
    print(
        f"{'base parameter':<{NAME_WIDTH}} {'WLS':>11} {'output err':>11} {'CRB std':>9} "
        f"{'CRB/|est| %':>11} {'|WLS-OE|/CRB':>12}"
    )
    for k, name in enumerate(model.names):
        rel = 100 * oe.std[k] / max(abs(oe.sigma[k]), 1e-300)
        print(
            f"{_short(name):<{NAME_WIDTH}} {wls.sigma[k]:11.5g} {oe.sigma[k]:11.5g} {oe.std[k]:9.2g} "
            f"{rel:11.3g} {abs(wls.sigma[k] - oe.sigma[k]) / oe.std[k]:12.1f}"
        )


def _print_standard(model, arm, oe) -> None:
    from adaptive_dd.identification.serial_model import standard_from_base

    vals, std, ok = standard_from_base(model, oe.sigma, np.linalg.inv(oe.information))
    names = arm.standard_names
    got = [f"{names[k]} = {vals[k]:.5g} +- {std[k]:.2g}" for k in np.flatnonzero(ok)]
    print(f"standard parameters identified on their own ({len(got)} of {len(names)}): " + "; ".join(got))
    none = set(arm.base.unidentifiable)
    print(
        f"unidentifiable (no torque depends on them, {len(none)}): "
        + (", ".join(n for n in names if n in none) or "none")
    )
    print(
        f"the other {len(names) - len(got) - len(none)} enter only through the base combinations above "
        "(the URDF's values are needed to split them)"
    )


def _print_payload(label: str, pr) -> None:
    c = pr.consistent
    print(
        f"{label}: mass {pr.mass:.5g} +- {pr.mass_std:.2g} kg; centre of mass "
        f"[{', '.join(f'{x * 1e3:.2f}' for x in pr.com)}] +- "
        f"[{', '.join(f'{x * 1e3:.2g}' for x in pr.com_std)}]"
        " mm in the payload frame"
    )
    ic = pr.inertia_com
    print(
        f"  inertia about the centre of mass [kg m^2]: Ixx {ic[0, 0]:.4g}, Iyy {ic[1, 1]:.4g}, Izz "
        f"{ic[2, 2]:.4g}, "
        f"Ixy {ic[0, 1]:.3g}, Ixz {ic[0, 2]:.3g}, Iyz {ic[1, 2]:.3g}"
    )
    if c.was_physical:
        print(f"  physically consistent as estimated (pseudo-inertia min eigenvalue {c.min_eigenvalue:.3g})")
    else:
        print(
            "  the unconstrained estimate is not a rigid body (pseudo-inertia eigenvalue "
            f"{c.min_eigenvalue:.3g}); "
            f"constrained fit {c.distance:.2f} std away: values above are the constrained ones"
        )


def identify_serial(args: argparse.Namespace, arm, outputs) -> int:
    """``adaptive-dd identify --arm SCENARIO rec.csv`` for an N-joint arm."""
    from adaptive_dd.identification.consistency import consistent_arm_fit
    from adaptive_dd.identification.payload_pair import payload_from_pair, payload_from_record
    from adaptive_dd.identification.serial_model import serial_model
    from adaptive_dd.identification.serial_output_error import measurement_std
    from adaptive_dd.identification_plots import plot_torque_fit
    from adaptive_dd.io import read_serial_recording
    from adaptive_dd.outputs import atomic_write

    rec = read_serial_recording(args.data, arm.n_joints)
    model = serial_model(arm)
    kw = dict(tau_f=args.tau_f, segment_length=args.segment_length, max_iter=args.max_iter)
    if args.payload_only:
        qd = _velocity(rec, args.tau_f)
        pr = payload_from_record(
            arm,
            model,
            rec.q,
            qd,
            rec.tau,
            measurement_std(arm),
            sample_period=rec.sample_period,
            segment_length=args.segment_length,
            max_iter=args.max_iter,
        )
        print(
            f"{rec.source}: {rec.t.size} samples; the arm known (its URDF), the payload's 10 parameters "
            "fitted"
        )
        _print_payload("payload (one record, arm known)", pr)
        return 0
    ident = identify_record(arm, model, rec, **kw)
    oe = ident.oe
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s, {arm.n_joints} joints, "
        f"{model.p} base parameters; velocities "
        f"{'measured' if ident.qd_measured else 'estimated (not in the file)'}"
    )
    print(
        f"output error: {oe.iterations} iterations, {'converged' if oe.converged else 'NOT converged'}, "
        f"normalised residual {2 * oe.cost / oe.n_residuals:.3f} (1 = the noise model)"
    )
    _print_estimates(model, ident)
    print(
        "CRB: Cramér-Rao std at the estimate for this record, q and qd measured with the arm's sensor "
        "noise, "
        f"torque known, segments of {oe.segment_length} samples with unknown initial states"
    )
    reg = ident.regression
    pred = np.einsum("knp,p->kn", reg.phi, oe.sigma)
    res = reg.y - pred
    print(
        "residual torque per joint (filtered, output-error estimate) [N m rms]: "
        + ", ".join(f"{x:.3g}" for x in np.sqrt(np.mean(res**2, axis=0)))
    )
    _print_standard(model, arm, oe)
    fit = consistent_arm_fit(model, oe.sigma, oe.information)
    print(
        f"nearest physically consistent arm (every link's pseudo-inertia positive definite, friction >= 0): "
        f"{fit.distance:.2f} std from the estimate"
    )
    t = rec.t[reg.start :]
    plot_torque_fit(
        t, reg.y, pred, outputs.path("torque_fit.png"), f"{Path(args.data).name}: measured vs predicted"
    )
    with atomic_write(outputs.path("estimates.csv")) as fh:
        fh.write("name,wls,wls_std,output_error,crb_std\n")
        for k, name in enumerate(model.names):
            fh.write(
                f'"{name}",{ident.wls.sigma[k]:.10g},{ident.wls.std[k]:.4g},{oe.sigma[k]:.10g},{oe.std[k]:.4g}\n'
            )
    if args.baseline:
        base = read_serial_recording(args.baseline, arm.n_joints)
        other = identify_record(arm, model, base, **kw).oe
        pr = payload_from_pair(
            arm, oe.sigma, np.linalg.inv(oe.information), other.sigma, np.linalg.inv(other.information)
        )
        _print_payload(f"payload (loaded {Path(args.data).name} - unloaded {Path(args.baseline).name})", pr)
    print(f"wrote {Path(args.out) / 'estimates.csv'}, {Path(args.out) / 'torque_fit.png'}")
    return 0


def simulate_serial(args: argparse.Namespace, scenario_path: str, outputs) -> int:
    """``adaptive-dd simulate --arm SCENARIO`` for an N-joint arm: identification records, truth known."""
    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.experiments import trial_rngs
    from adaptive_dd.identification.serial_records import simulate_serial_record, write_serial_recording
    from adaptive_dd.plant.serial_arm import payload_parameters

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
    rec = simulate_serial_record(
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
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.identification.excitation import (
        ExcitationLimits,
        design_excitation,
        multisine,
        reference_toml,
    )
    from adaptive_dd.outputs import atomic_write
    from adaptive_dd.plant.serial_arm import SerialArm

    sc = load_scenario(args.arm)
    arm = sc.arm
    if not isinstance(arm, SerialArm):
        raise ScenarioError(f"{args.arm}: excite needs an [arm] from a URDF (urdf = ... or robot = ...)")
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
    ratio = rows["plain multi-sine"][0] / rows["designed"][0]
    print(
        f"the designed trajectory shrinks the worst bound {ratio:.1f}x (Cramér-Rao std of the segmented "
        "output "
        f"error on a {args.duration} s record tracking it, relative to each parameter's magnitude)"
    )
    text = reference_toml(best.reference(ramp=args.ramp), f"designed by adaptive-dd excite --arm {args.arm}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(out) as fh:
        fh.write(_replace_reference(Path(args.arm).read_text(), text))
    print(f"wrote {out} (the scenario with the designed [reference])")
    return 0


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
    from adaptive_dd.identification.serial_model import serial_model
    from adaptive_dd.identification.serial_output_error import measurement_std, serial_crb
    from adaptive_dd.identification.serial_records import simulate_serial_record

    model = serial_model(arm)
    std = measurement_std(arm)
    out = {}
    for label, tr in trajectories.items():
        rec = simulate_serial_record(
            arm, tr.reference(ramp=0.5), duration, [np.random.default_rng(0)], noise=False
        )
        crb, _ = serial_crb(model, rec.sigma_true, rec.q_true[0], rec.qd_true[0], rec.tau[0], std)
        rb = relative_bounds(crb, model.sigma_ref, model.names)
        k = int(np.argmax(rb))
        out[label] = (float(rb[k]), model.names[k], float(np.median(rb)))
    return out
