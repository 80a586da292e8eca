"""Command-line interface: ``adaptive-dd {check,simulate,reproduce,identify,benchmark,sweep,validate}``.

Exit codes: 0 success, 1 a check or an estimate failed, 2 a user error (bad option,
scenario, record or output path; one line naming the problem), 3 an internal error
(a short message; the traceback with ``--debug``), 130 interrupted.
"""

from __future__ import annotations

import argparse
import math
import sys
import traceback
from pathlib import Path

import numpy as np

from adaptive_dd.cli_arm import describe_arm
from adaptive_dd.cli_arm import load_arm as _load_arm
from adaptive_dd.errors import OutputError, ParameterError

__all__ = ["EXIT_INTERNAL", "EXIT_INTERRUPTED", "EXIT_USAGE", "build_parser", "main"]

EXIT_USAGE = 2
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130
ISSUE_TRACKER = "the adaptive_dd issue tracker"


def _number(kind: type, lo: float, hi: float, lo_open: bool = False):
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


_POS = _number(float, 0.0, 1e6, lo_open=True)
_SEED = _number(int, 0, 2**63 - 1)
_SEEDS = _number(int, 1, 10_000)
_MASS = _number(float, 0.0, 50.0)
_RADIUS = _number(float, 0.0, 0.5)
_PERIOD = _number(float, 1e-5, 0.1)
_SUBSTEPS = _number(int, 1, 100)


def _sub(sub, name: str, **kw) -> argparse.ArgumentParser:
    sp = sub.add_parser(name, allow_abbrev=False, **kw)
    # also after the command (``adaptive-dd benchmark --debug``); SUPPRESS: not reset when absent
    sp.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return sp


def _refuse(args: argparse.Namespace, options: tuple[str, ...], why: str) -> None:
    """A :class:`ParameterError` naming the first of ``options`` given on the command line and
    ``why`` it does not apply (an option that does not apply is never silently ignored)."""
    given = [o for o in options if o in getattr(args, "given", ())]
    if given:
        raise ParameterError(f"{', '.join(given)}: {why}")


def _cmd_check(args: argparse.Namespace) -> int:
    from adaptive_dd.plant.arm import Arm
    from adaptive_dd.plant.parameters import Payload
    from adaptive_dd.plant.pinocchio_model import two_link_cross_check

    arm = _load_arm(args.arm)
    radius = arm.payload_radius if args.radius is None else args.radius
    # with --arm: the arm without payload and with one (--payload, or 2 kg)
    masses = [0.0, args.payload or 2.0] if args.arm else [args.payload]
    failed = 0
    for mass in masses:
        payload = Payload(mass, radius) if mass else None
        label = f"payload {mass} kg, radius {radius} m" if payload else "no payload"
        where = f"arm of {args.arm}" if args.arm else "the SICE arm"
        if isinstance(arm, Arm):
            from adaptive_dd.plant.pinocchio_check import cross_check

            print(
                f"Cross-check against Pinocchio ({where}: {arm.n_joints} joints of {arm.urdf.name}, "
                f"{label} at '{arm.payload_frame}', {args.states} random states)"
            )
            results = cross_check(
                arm,
                {"mass": mass, "radius": radius} if mass else None,
                n_states=args.states,
                rng=np.random.default_rng(args.seed),
            )
        else:
            print(
                f"Cross-check of adaptive_dd.plant against Pinocchio ({where}, {label}, "
                f"{args.states} random states)"
            )
            if arm.physical is None:
                print("  (sigma-only arm: Pinocchio model built from TwoLinkArm.equivalent_physical())")
            results = two_link_cross_check(
                arm, payload, n_states=args.states, rng=np.random.default_rng(args.seed)
            )
        for r in results:
            print("  " + str(r))
        bad = [r for r in results if not r.passed]
        print(f"{len(results) - len(bad)} passed, {len(bad)} failed")
        failed += len(bad)
    return 1 if failed else 0


def _cmd_simulate(args: argparse.Namespace) -> int:
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
    arm = _load_arm(args.arm)
    from adaptive_dd.plant.arm import Arm

    if isinstance(arm, Arm):  # N joints: identification records (cli_serial)
        from adaptive_dd.cli_simulate import simulate_arm

        _refuse(
            args,
            ("--no-saturate",),
            f"does not apply to an arm from a URDF (the {arm.n_joints}-joint arm of {args.arm}): its "
            "computed-torque record is always limited to the arm's torque limits",
        )
        with OutputSet(args.out) as outputs:
            return simulate_arm(args, args.arm, outputs)
    _refuse(
        args,
        ("--com", "--plant"),
        f"apply to an arm from a URDF only; the {'two-link arm of ' + args.arm if args.arm else 'SICE arm'} "
        "runs the paper's Table 2 experiment on its own plant (the payload a disk centred on the tip)",
    )
    with OutputSet(args.out) as outputs:
        return _simulate(args, n, outputs)


def _simulate(args: argparse.Namespace, n: int, outputs) -> int:
    import dataclasses

    from adaptive_dd.experiments import TABLE2, table2_torque, trial_rngs
    from adaptive_dd.io import write_recording
    from adaptive_dd.plant.simulator import PayloadSchedule, simulate_open_loop
    from adaptive_dd.plotting import plot_trajectory

    tau = table2_torque(args.seeds, n, args.sample_period)
    arm = _load_arm(args.arm)
    sensor = dataclasses.replace(
        arm.sensor,
        quantize=not args.no_quantize,
        position_variance=(0.0, 0.0) if args.no_noise else TABLE2["position_variance"],
        velocity_variance=(0.0, 0.0) if args.no_noise else TABLE2["velocity_variance"],
    )
    actuator = dataclasses.replace(arm.actuator, saturate=not args.no_saturate, quantize=not args.no_quantize)
    payload = PayloadSchedule(initial_mass=args.payload, radius=args.radius)
    res = simulate_open_loop(
        tau,
        trial_rngs(args.seed, args.seeds),
        arm=arm,
        sample_period=args.sample_period,
        substeps=args.substeps,
        payload=payload,
        sensor=sensor,
        actuator=actuator,
    )
    res.save(str(outputs.path("trajectory.npz")))
    write_recording(outputs.path("trajectory.csv"), res.t, res.q_meas[0], res.qd_meas[0], res.tau[0])
    plot_trajectory(res, outputs.path("trajectory.png"))
    print(
        f"Table 2 experiment: 1 Hz sine torques {TABLE2['amplitude']} N m, {args.duration} s at "
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
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from adaptive_dd.identification.reproduce import TAU_F_GRID
    from adaptive_dd.outputs import OutputSet

    tau_f = tuple(args.tau_f) if args.tau_f else TAU_F_GRID
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        written = _reproduce(args, tau_f, outputs)
    if written:
        print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _reproduce(args: argparse.Namespace, tau_f: tuple, outputs) -> list[Path]:
    from adaptive_dd.identification.reproduce import (
        format_bounds,
        format_comparison,
        format_summary,
        format_table,
        run_reproduce,
    )

    res = run_reproduce(
        seeds=args.seeds,
        seed=args.seed,
        tau_f=tau_f,
        estimators=tuple(args.estimators),
        progress=not args.no_progress,
        keep_theta=(_FIG5, _OURS),
        noise=not args.no_noise,
        extra_estimators=tuple(args.extra_estimators),
    )
    if args.no_noise:
        print("\nNOISE-FREE sensors (--no-noise): the errors below are modelling errors only")
    print(
        f"\nEstimation error [%] after 10 000 samples, mean±std over {args.seeds} seeds "
        "(paper's value in parentheses)\n"
    )
    for method, table in (("M1", "Table 3"), ("M2", "Table 5")):
        if (method, "15", "paper") in res.errors:
            print(f"{table} ({method}, estimator 'paper', split (15)):")
            print(format_table(res, method, "15", "paper", with_paper=True) + "\n")
            print(
                f"{table}: ours / paper = ratio (mean error [%] over {args.seeds} seeds; "
                "README, Identification: why they differ)"
            )
            print(format_comparison(res, method) + "\n")
    for method in ("M1", "M2"):
        if (method, "full", "exact") in res.errors:
            print(
                f"Ours ({method}, estimator 'exact': exact filtered regressor, aligned torque, "
                "data selection, full RLS):"
            )
            print(format_table(res, method, "full", "exact", with_paper=False) + "\n")
    print("Worst mean error over the seven parameters [%], every configuration:")
    print(format_summary(res) + "\n")
    if res.crb is not None:
        print(
            "Against the information limit (Cramér-Rao bound of this experiment: Table 2 torques, "
            "Table 2 + 4 noise, q and qd measured, torque known):"
        )
        print(format_bounds(res) + "\n")
    written = _reproduce_figures(res, tau_f, outputs)
    if args.json:
        res.write_json(outputs.extra(args.json))
        written.append(Path(args.json))
    return written


_FIG5 = ("M2", "15", "paper")
_OURS = ("M2", "full", "exact")


def _reproduce_figures(res, tau_f: tuple, outputs) -> list:
    """Fig. 5-like estimate histories and the Fig. 7 model responses; prints Fig. 7's rms."""
    from adaptive_dd.identification.reproduce import model_responses
    from adaptive_dd.plant.two_link import TwoLinkArm
    from adaptive_dd.plotting import plot_estimates, plot_model_response

    out = outputs.folder
    written = []
    t = res.sim.t
    i5 = tau_f.index(0.006) if 0.006 in tau_f else 0
    i_best = tau_f.index(0.02) if 0.02 in tau_f else len(tau_f) - 1
    figures = (
        (_FIG5, i5, "fig5_paper_M2.png", "paper's M2 estimator, split (15)", "paper M2"),
        (_OURS, i_best, "fig5_exact_M2.png", "estimator 'exact' (M2)", "exact M2"),
    )
    models = {}
    for key, i, name, label, short in figures:
        if key in res.theta:
            title = f"Estimates, {label}, tau_f = {tau_f[i]}"
            plot_estimates(t, res.theta[key][i], TwoLinkArm.sice().sigma, outputs.path(name), title)
            written.append(out / name)
            models[f"{short}, tau_f = {tau_f[i]}"] = res.theta[key][i][:, -1].mean(axis=0)
    if models:
        arm_q, qs = model_responses(models, res.sim.t.size)
        plot_model_response(
            t,
            arm_q,
            qs,
            outputs.path("fig7_model_response.png"),
            "TwoLinkArm and identified models, same torque (Table 2)",
        )
        written.append(out / "fig7_model_response.png")
        for k, q in qs.items():
            rms = np.sqrt(((q - arm_q) ** 2).mean(axis=0))
            print(f"Fig. 7: rms difference arm - model ({k}): {rms.round(4)} rad")
    return written


def _cmd_identify(args: argparse.Namespace) -> int:
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.estimators import estimate
    from adaptive_dd.io import MIN_EQUATIONS, check_identifiable, read_recording
    from adaptive_dd.outputs import OutputSet

    if args.arm:  # an N-joint arm from a URDF: its own path (adaptive_dd.cli_log)
        from adaptive_dd.plant.arm import Arm

        arm = _load_arm(args.arm, args.repair_inertia)
        if isinstance(arm, Arm):
            from adaptive_dd.cli_log import identify_log
            from adaptive_dd.experiments import TABLE2

            two_link = {
                "--estimator": args.estimator != "exact",
                "--method": args.method != "M2",
                "--split": args.split != "15",
                "--true": args.true is not None,
                "--online": args.online,
                "--position-variance": list(args.position_variance) != list(TABLE2["position_variance"]),
                "--velocity-variance": list(args.velocity_variance) != list(TABLE2["velocity_variance"]),
            }
            given = [o for o, v in two_link.items() if v]
            if given:
                raise DataError(
                    f"{', '.join(given)}: options of the two-link identification; an N-joint arm from a "
                    "URDF (--arm) is identified by weighted least squares (docs/real_log.md)"
                )

            outputs = OutputSet(args.out)
            with outputs:
                return identify_log(args, arm, outputs)
    arm_only = {
        "--baseline": args.baseline,
        "--payload-only": args.payload_only,
        "--window": args.window,
        "--repair-inertia": args.repair_inertia,
        "--output-error": args.output_error != "auto",
        "--segment-length": args.segment_length != 200,
        "--max-iter": args.max_iter != 30,
    }
    given = [o for o, v in arm_only.items() if v]
    if given:
        raise DataError(f"{', '.join(given)}: only with --arm SCENARIO of an N-joint arm from a URDF")
    if len(args.data) != 1:
        raise DataError(f"identify without --arm reads one CSV file, got {len(args.data)}: {args.data}")
    args.data = args.data[0]
    args.tau_f = 0.02 if args.tau_f is None else args.tau_f
    rec = read_recording(args.data)
    if args.method == "M2" and rec.qd is None:
        raise DataError(f"{args.data}: method M2 needs columns qd1, qd2 (use --method M1 for position only)")
    check_identifiable(rec, args.tau_f)
    outputs = OutputSet(args.out)
    with outputs:
        if args.online:
            return _identify_online(args, rec, outputs)
        return _identify(args, rec, outputs, estimate, MIN_EQUATIONS)


def _log_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--window",
        type=_number(float, -1e9, 1e9),
        nargs=2,
        metavar=("START", "END"),
        help="with --arm: the part of the log to use [s of its clock] (replaces record.window)",
    )


def _cmd_predict(args: argparse.Namespace) -> int:
    from adaptive_dd.cli_log import predict_log

    return predict_log(args)


def _identify(args, rec, outputs, estimate, min_equations: int) -> int:
    from adaptive_dd.errors import DataError
    from adaptive_dd.plotting import plot_estimates

    oe = args.estimator == "output_error"
    res = estimate(
        rec.q,
        rec.tau,
        rec.qd,
        estimator="exact" if oe else args.estimator,
        method=args.method,
        split=args.split,
        tau_f=args.tau_f,
        sample_period=rec.sample_period,
    )
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s; estimator "
        f"{args.estimator}, method {args.method}, split {res.split}, tau_f = {args.tau_f}"
    )
    print(f"equations used: {int(res.n_used)} of {2 * rec.t.size}")
    if int(res.n_used) < min_equations:
        raise DataError(
            f"{rec.source}: only {int(res.n_used)} usable equations (the arm barely moves or the "
            f"record is short); identify needs at least {min_equations}"
        )
    final, std = res.final, res.std
    if oe:
        final, std = _identify_output_error(rec, res.final, args)
    if not np.all(np.isfinite(final)):
        print(
            "warning: the estimate is not finite: the record does not excite the arm enough", file=sys.stderr
        )
        return 1
    _print_with_bound(final, std, _identify_bound(rec, final, args), rec, args)
    ref = np.full(7, np.nan) if args.true is None else np.asarray(args.true, float)
    plot_estimates(
        rec.t,
        res.theta[None],
        np.where(np.isfinite(ref), ref, final),
        outputs.path("convergence.png"),
        f"{Path(args.data).name}: {args.estimator} ({args.method})",
        reference_label="true value" if args.true is not None else "final estimate",
    )
    print(f"wrote {Path(args.out) / 'convergence.png'}")
    return 0


def _identify_online(args, rec, outputs) -> int:
    """The online estimator of ``adaptive_ct`` over a record: estimates and alarms over time."""
    import dataclasses

    from adaptive_dd.controllers.adaptive import ADAPTIVE_ONLINE
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.two_link_online import run_two_link_online
    from adaptive_dd.outputs import atomic_write
    from adaptive_dd.plant.parameters import SIGMA_NAMES
    from adaptive_dd.plant.two_link import TwoLinkArm
    from adaptive_dd.plotting import plot_estimates

    if rec.qd is None:
        raise DataError(f"{args.data}: --online needs the measured velocity (columns qd1, qd2)")
    cfg = dataclasses.replace(ADAPTIVE_ONLINE, sample_period=rec.sample_period, tau_f=args.tau_f)
    sice = TwoLinkArm.sice()  # a record's arm: the SICE arm (the nominal model the estimator starts from)
    r = run_two_link_online(rec.q, rec.qd, rec.tau, cfg, sice.sigma)
    model, alarms = r.sigma_model[0], r.alarm_times()[0]
    mass = sice.payload_mass_from_sigma(model)
    print(
        f"{rec.source}: online estimator of adaptive_ct (tau_f = {args.tau_f} s, started at Table 1), "
        f"{rec.t.size} samples; {len(alarms)} change alarm(s)"
        + (f" at {', '.join(f'{a:.3f}' for a in alarms)} s" if alarms else "")
        + f"; skipped samples {int(r.n_skipped[0])}"
    )
    print(f"{'param':>6} {'final':>12}")
    for k, name in enumerate(SIGMA_NAMES):
        print(f"{name:>6} {model[-1, k]:12.5g}")
    print(f"payload mass implied at the end: {mass[-1]:.3f} kg")
    path = outputs.path("online.csv")
    with atomic_write(path) as fh:
        fh.write("t," + ",".join(SIGMA_NAMES) + ",payload_mass,alarm\n")
        for k in range(rec.t.size):
            vals = ",".join(f"{v:.9g}" for v in model[k])
            fh.write(f"{rec.t[k]:.9g},{vals},{mass[k]:.6g},{int(r.alarm[0, k])}\n")
    ref = np.full(7, np.nan) if args.true is None else np.asarray(args.true, float)
    plot_estimates(
        rec.t,
        model[None],
        np.where(np.isfinite(ref), ref, model[-1]),
        outputs.path("online.png"),
        f"{Path(args.data).name}: online estimator of adaptive_ct",
        reference_label="true value" if args.true is not None else "final estimate",
        alarms=alarms,
    )
    print(f"wrote {Path(args.out) / 'online.csv'}, {Path(args.out) / 'online.png'}")
    return 0


def _print_with_bound(final, std, crb, rec, args: argparse.Namespace) -> None:
    from adaptive_dd.plant.parameters import SIGMA_NAMES

    print(f"{'param':>6} {'estimate':>12} {'std':>10} {'CRB std':>10} {'CRB [%]':>9} {'std/CRB':>8}")
    for k, name in enumerate(SIGMA_NAMES):
        print(
            f"{name:>6} {final[k]:12.5g} {std[k]:10.2g} {crb.crb_std[k]:10.2g} "
            f"{crb.crb_std_pct[k]:9.2g} {std[k] / crb.crb_std[k]:8.1f}"
        )
    print(
        f"CRB: the smallest std any unbiased estimator can reach from this record (measured "
        f"torque, noise variances q {args.position_variance}, qd {args.velocity_variance}, "
        f"signals {'q, qd' if rec.qd is not None else 'q'}, initial state unknown), evaluated at the "
        "estimate; "
        f"condition number {crb.condition_number:.3g}"
    )


def _identify_output_error(rec, sigma0, args: argparse.Namespace):
    from adaptive_dd.identification.two_link_output_error import output_error_fit

    if rec.qd is None:
        raise ValueError(f"{args.data}: estimator output_error needs columns qd1, qd2")
    fit = output_error_fit(
        rec.q,
        rec.qd,
        rec.tau,
        sigma0,
        rec.sample_period,
        args.position_variance,
        args.velocity_variance,
    )
    print(f"output error: {fit.nfev} evaluations, {fit.message}")
    return fit.sigma, fit.std


def _identify_bound(rec, sigma, args: argparse.Namespace):
    """Cramér-Rao bound at the estimate for the record's torque, the initial state estimated too."""
    from adaptive_dd.identification.fisher import fisher_information
    from adaptive_dd.plant.parameters import project_sigma

    qd0 = np.zeros(2)
    if rec.qd is not None:  # a measured velocity within 3 noise std of zero: at rest (stuck)
        at_rest = np.abs(rec.qd[0]) <= 3 * np.sqrt(np.asarray(args.velocity_variance))
        qd0 = np.where(at_rest, 0.0, rec.qd[0])
    return fisher_information(
        project_sigma(sigma),
        rec.tau,
        rec.sample_period,
        args.position_variance,
        args.velocity_variance,
        measured=("q", "qd") if rec.qd is not None else ("q",),
        q0=rec.q[0],
        qd0=qd0,
        initial_state="unknown",
    )


def _cmd_excite(args: argparse.Namespace) -> int:
    from adaptive_dd.cli_simulate import cmd_excite

    return cmd_excite(args)


def _cmd_benchmark(args: argparse.Namespace) -> int:
    import dataclasses

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.outputs import OutputSet

    sc = load_scenario(args.scenario)
    if args.seeds is not None:
        sc = dataclasses.replace(sc, seeds=args.seeds)
    if sc.estimate().large:
        print(f"estimate: {sc.estimate()}", file=sys.stderr)
    outputs = OutputSet(args.out, extras=(args.json,) if args.json else ())
    with outputs:
        written = _benchmark(args, sc, outputs)
    print("wrote " + ", ".join(str(w) for w in written))
    return 0


def _benchmark(args: argparse.Namespace, sc, outputs) -> list[Path]:
    from adaptive_dd._numba_cache import announce_compilation
    from adaptive_dd.benchmark.metrics import compute_metrics, release_error_norm
    from adaptive_dd.benchmark.report import format_report, write_csv, write_json
    from adaptive_dd.benchmark.runner import run_benchmark
    from adaptive_dd.plotting import plot_benchmark_estimates, plot_tracking_errors

    with announce_compilation(sc.arm):  # a cold cache compiles first: say so, and for how long
        res = run_benchmark(sc, progress=not args.no_progress, on_run=release_error_norm)
        metrics = compute_metrics(res)
    print(format_report(metrics, res))
    if "excitation_report" in res.cache:  # [run] excite: what the identification found
        print(res.cache["excitation_report"].summary())
    out = Path(args.out)
    write_csv(metrics, outputs.path("metrics.csv"))
    write_json(metrics, outputs.extra(args.json) if args.json else outputs.path("metrics.json"))
    fmts = tuple(args.figure_formats)
    plot_tracking_errors(res, outputs.path("tracking_error.png"), formats=fmts)
    written = [out / "metrics.csv", Path(args.json or out / "metrics.json")]
    written += [out / f"tracking_error.{f}" for f in fmts]
    if any(r.sigma_hat is not None for r in res.runs.values()):
        plot_benchmark_estimates(res, outputs.path("estimates.png"), formats=fmts)
        written += [out / f"estimates.{f}" for f in fmts]
    if sc.n_joints != 2:  # N-joint arms: one panel per joint as well
        from adaptive_dd.plotting import plot_joint_errors

        plot_joint_errors(res, outputs.path("joint_errors.png"), formats=fmts)
        written += [out / f"joint_errors.{f}" for f in fmts]
    frame = res.to_frame()
    frame.to_csv(outputs.path("per_seed.csv"), index=False)
    written.append(out / "per_seed.csv")
    if res.plant is not None:  # the plant is not the model: each seed's drawn plant
        from adaptive_dd.benchmark.results import plant_frame

        plant_frame(res).to_csv(outputs.path("plant.csv"), index=False)
        written.append(out / "plant.csv")
    return written


def _cmd_validate(args: argparse.Namespace) -> int:
    from adaptive_dd.benchmark.scenario import format_scenario, load_scenario

    if args.scenario and Path(args.scenario).is_file():
        from adaptive_dd.cli_log import is_identification_scenario, validate_identification

        if is_identification_scenario(args.scenario):  # [arm] and [record]: no benchmark tables needed
            return validate_identification(args.scenario)
    sc = load_scenario(args.scenario)
    print(format_scenario(sc))
    from adaptive_dd.plant.arm import Arm

    if isinstance(sc.arm, Arm):
        print(describe_arm(sc.arm))
    from adaptive_dd.benchmark.preflight import preflight, resolved_settings, torque_peaks

    for line in resolved_settings(sc):
        print(line)

    peak, _, _ = torque_peaks(sc)
    limit = sc.arm.actuator.torque_limit
    print(
        "# peak |tau| along the reference (inverse dynamics, every payload): "
        + ", ".join(
            f"joint{j + 1} {peak[j]:.4g} N m ({peak[j] / limit[j]:.0%} of its limit)"
            for j in range(peak.size)
        )
    )
    problems, warnings = preflight(sc)
    for w in warnings:
        print(f"adaptive-dd validate: warning: {w}", file=sys.stderr)
    if problems:
        print(f"adaptive-dd validate: {len(problems)} problem(s) the run would meet:", file=sys.stderr)
        for p in problems:
            print(f"  {p}", file=sys.stderr)
        return 1
    print(
        f"# checked: the reference within the arm's position and velocity limits (torque: "
        f"{'see the warning' if warnings else 'within'}); {len(sc.controllers)} controller(s) built"
    )
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    import dataclasses

    from adaptive_dd.sweep import run_sweep
    from adaptive_dd.sweep_spec import load_sweep

    sweep = load_sweep(args.sweep)
    if args.block is not None:
        sweep = dataclasses.replace(sweep, block=min(args.block, sweep.seeds))
    if args.scheduler and args.workers:
        print("adaptive-dd sweep: --workers is ignored with --scheduler", file=sys.stderr)
    res = run_sweep(
        sweep, args.out, scheduler=args.scheduler, workers=args.workers, progress=not args.no_progress
    )
    failed = res.table.loc[res.table["failed"], "error"]
    print(
        f"{len(res.table)} rows ({res.failed_rows} failed), {res.ran} tasks run, {res.reused} reused; "
        f"wrote {res.table_path}" + "".join(f", {p}" for p in res.heatmaps)
    )
    if res.failed_rows:
        n_tasks = res.table.loc[res.table["failed"], "task"].nunique()
        print(
            f"{'error' if res.failed_rows == len(res.table) else 'warning'}: {res.failed_rows} of "
            f"{len(res.table)} rows failed (in {n_tasks} task(s)); why:",
            file=sys.stderr,
        )
        for msg, count in failed.value_counts().head(5).items():
            print(f"  {count} rows: {msg}", file=sys.stderr)
    if res.failed_rows == len(res.table):
        print("every row failed: no heat map drawn; fix the cause above and rerun", file=sys.stderr)
        return 1
    if sweep.heatmap and not res.heatmaps:
        hm = sweep.heatmap
        print(
            f"no heat map: no grid point has a seed where both {hm['adaptive']} and {hm['floor']} finished "
            f"segment {hm['segment']}",
            file=sys.stderr,
        )
    elif sweep.heatmap:
        from adaptive_dd.sweep import ratio_medians

        hm = sweep.heatmap
        r = ratio_medians(res.table, hm, [a for a, _ in sweep.axes])
        print(
            f"median over seeds of rms {hm['adaptive']} / rms {hm['floor']}, segment {hm['segment']}"
            f" (rows {hm['y']}, columns {hm['x']}; median over any other axes):"
        )
        print(r.pivot_table(index=hm["y"], columns=hm["x"], values="ratio", aggfunc="median").round(3))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``adaptive-dd`` parser (no abbreviations of options; checked numeric options)."""
    from adaptive_dd import __version__

    p = argparse.ArgumentParser(prog="adaptive-dd", description=__doc__, allow_abbrev=False)
    p.add_argument("--version", action="version", version=f"adaptive-dd {__version__}")
    p.add_argument("--debug", action="store_true", help="show the traceback of an internal error")
    sub = p.add_subparsers(dest="command", required=True)

    c = _sub(sub, "check", help="cross-check the dynamics against Pinocchio")
    c.add_argument("--payload", type=_MASS, default=0.0, metavar="KG", help="tip disk mass [kg]")
    c.add_argument("--radius", type=_RADIUS, help="tip disk radius [m] (default: the arm's)")
    c.add_argument(
        "--arm", metavar="SCENARIO", help="check the [arm] of a scenario TOML, with and without payload"
    )
    c.add_argument("--states", type=_number(int, 1, 100_000), default=200, help="number of random states")
    c.add_argument("--seed", type=_SEED, default=0)
    c.set_defaults(func=_cmd_check)

    s = _sub(sub, "simulate", help="simulate the paper's open-loop Table 2 experiment")
    s.add_argument(
        "--duration", type=_number(float, 0.0, math.inf, lo_open=True), default=10.0, help="[s] (default 10)"
    )
    s.add_argument("--sample-period", type=_PERIOD, default=1e-3, help="T [s] (default 0.001)")
    s.add_argument("--substeps", type=_SUBSTEPS, default=2, help="RK4 steps per sample")
    s.add_argument("--seeds", type=_SEEDS, default=1, help="number of trials (noise seeds)")
    s.add_argument("--seed", type=_SEED, default=0, help="base seed")
    s.add_argument("--payload", type=_MASS, default=0.0, metavar="KG")
    s.add_argument("--radius", type=_RADIUS, help="tip disk radius [m] (default: the arm's)")
    s.add_argument(
        "--com",
        type=_number(float, -1.0, 1.0),
        nargs=3,
        metavar="M",
        help="payload centre of mass in the payload frame [m] (arm from a URDF; default 0 0 0)",
    )
    s.add_argument(
        "--arm",
        metavar="SCENARIO",
        help="simulate the [arm] and [plant] of a scenario TOML; an arm from a URDF tracks the scenario's "
        "[reference] by computed torque and writes t, q1..qN, qd1..qdN, tau1..tauN",
    )
    s.add_argument("--no-noise", action="store_true", help="noise-free sensors")
    s.add_argument("--no-quantize", action="store_true", help="no encoder or D/A quantization")
    s.add_argument("--no-saturate", action="store_true", help="no torque saturation")
    s.add_argument(
        "--plant",
        default="model",
        choices=("model", "serial"),
        help="arm from a URDF: the identification model's RK4 with tanh friction (default) or the "
        "benchmark's compiled plant with the arm's friction law (stick-slip)",
    )
    s.add_argument("--out", default="results/simulate", help="output folder")
    s.set_defaults(func=_cmd_simulate)

    from adaptive_dd.experiments import TABLE2
    from adaptive_dd.identification.estimators import ESTIMATORS
    from adaptive_dd.identification.reproduce import DEFAULT_ESTIMATORS, EXTRA_ESTIMATORS

    r = _sub(sub, "reproduce", help="reproduce Tables 3 and 5 of the paper (and ours beside)")
    r.add_argument("--seeds", type=_SEEDS, default=10, help="Monte-Carlo seeds (default 10)")
    r.add_argument("--seed", type=_SEED, default=0, help="base seed")
    r.add_argument(
        "--tau-f",
        type=_number(float, 0.0, 1.0, lo_open=True),
        nargs="+",
        help="filter time constants [s] (default: the paper's)",
    )
    r.add_argument(
        "--estimators",
        nargs="+",
        default=list(DEFAULT_ESTIMATORS),
        choices=ESTIMATORS,
        help="estimators to run (kalman equals batch_ls here and costs ~1 min more)",
    )
    r.add_argument(
        "--extra-estimators",
        nargs="+",
        default=[],
        choices=EXTRA_ESTIMATORS,
        help="also run output error (~6 s per seed) and/or the augmented EKF (~1 min per 10 seeds)",
    )
    r.add_argument("--out", default="results/reproduce", help="folder for figures")
    r.add_argument("--json", metavar="PATH", help="write tidy rows as JSON")
    r.add_argument("--no-noise", action="store_true", help="noise-free sensors (modelling errors only)")
    r.add_argument("--no-progress", action="store_true")
    r.set_defaults(func=_cmd_reproduce)

    i = _sub(sub, "identify", help="estimate sigma from a recorded experiment (CSV)")
    i.add_argument(
        "data",
        nargs="*",
        help="CSV with header t,q1,q2,qd1,qd2,tau1,tau2 (qd optional for M1); with --arm: the log's file(s), "
        "read as the scenario's [record] says (default: its record.files; see docs/real_log.md)",
    )
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
        type=_POS,
        default=None,
        help="filter time constant [s] (default 0.02; with --arm: 2 sample periods, at least 0.02)",
    )
    i.add_argument(
        "--true", type=_number(float, -1e6, 1e6), nargs=7, metavar="S", help="true sigma, to mark on the plot"
    )
    i.add_argument(
        "--position-variance",
        type=_number(float, 0.0, 1.0),
        nargs=2,
        default=list(TABLE2["position_variance"]),
        metavar="V",
        help="noise variance of q1, q2 [rad^2] for the bound (default: Table 2)",
    )
    i.add_argument(
        "--velocity-variance",
        type=_number(float, 0.0, 1.0),
        nargs=2,
        default=list(TABLE2["velocity_variance"]),
        metavar="V",
        help="noise variance of qd1, qd2 [(rad/s)^2] for the bound (default: Table 4)",
    )
    i.add_argument(
        "--online",
        action="store_true",
        help="run the online estimator of adaptive_ct (change detection included) over the record; "
        "writes online.csv (estimates, payload mass and alarms over time) and online.png",
    )
    i.add_argument(
        "--arm",
        metavar="SCENARIO",
        help="a scenario TOML with [arm] from a URDF and, for a real log, [record] (default: CSV t, q1..qN, "
        "[qd1..qdN,] tau1..tauN); prints weighted least squares with Newey-West std, output error where "
        "the record can be simulated; writes OUT/model.json (docs/real_log.md)",
    )
    i.add_argument(
        "--baseline",
        nargs="+",
        metavar="CSV",
        help="with --arm: the unloaded record's file(s), read through the same [record]; prints the payload",
    )
    i.add_argument(
        "--payload-only", action="store_true", help="with --arm: the arm known (URDF), fit the payload alone"
    )
    i.add_argument(
        "--segment-length",
        type=_number(int, 10, 10**6),
        default=200,
        help="with --arm: output-error segment length [samples] (default 200)",
    )
    i.add_argument(
        "--max-iter", type=_number(int, 1, 1000), default=30, help="with --arm: output-error iterations"
    )
    _log_options(i)
    i.add_argument(
        "--repair-inertia",
        action="store_true",
        help="with --arm: repair chain links whose URDF inertia is not a rigid body's (reported)",
    )
    i.add_argument(
        "--output-error",
        choices=("auto", "on", "off"),
        default="auto",
        help="with --arm: refine by output error (auto: for records in the simulator's format only)",
    )
    i.add_argument("--out", default="results/identify", help="folder (with --arm: model.json, estimates.csv)")
    i.set_defaults(func=_cmd_identify)

    r = _sub(sub, "predict", help="torque prediction error of an identified model on another record")
    r.add_argument("data", nargs="*", help="the record's file(s) (default: the scenario's record.files)")
    r.add_argument("--arm", required=True, metavar="SCENARIO", help="scenario TOML with [arm] and [record]")
    r.add_argument(
        "--model", required=True, metavar="JSON", help="model.json written by identify --arm --out"
    )
    _log_options(r)
    r.add_argument(
        "--lowpass",
        type=_POS,
        default=2.0,
        metavar="HZ",
        help="also compare after a zero-phase Butterworth low-pass (order 4) of both [Hz] (default 2)",
    )
    r.add_argument("--out", default="results/predict", help="folder for prediction.csv and prediction.png")
    r.set_defaults(func=_cmd_predict)

    e = _sub(sub, "excite", help="design an exciting trajectory for an arm from a URDF")
    e.add_argument("--arm", required=True, metavar="SCENARIO", help="scenario TOML with [arm] urdf/robot")
    e.add_argument("--harmonics", type=_number(int, 1, 20), default=5, help="Fourier harmonics (default 5)")
    e.add_argument("--f0", type=_POS, default=0.1, help="base frequency [Hz] (default 0.1: 10 s period)")
    e.add_argument("--acceleration", type=_POS, default=5.0, help="|qdd| limit [rad/s^2] (default 5)")
    e.add_argument("--margin", type=_number(float, 0.0, 1.0), default=0.1, help="position margin [rad]")
    e.add_argument("--maxiter", type=_number(int, 1, 10000), default=100, help="SLSQP iterations")
    e.add_argument("--duration", type=_POS, default=10.0, help="record length for the bounds [s]")
    e.add_argument("--ramp", type=_number(float, 0.0, 100.0), default=0.5, help="reference ramp [s]")
    e.add_argument("--seed", type=_SEED, default=0, help="seed of the random start")
    e.add_argument("--out", default="results/excite/scenario.toml", help="scenario file to write")
    e.set_defaults(func=_cmd_excite)

    b = _sub(sub, "benchmark", help="payload-swap tracking benchmark (the main job)")
    b.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    b.add_argument("--out", default="results/benchmark", help="folder for CSV, JSON and figures")
    b.add_argument("--json", metavar="PATH", help="where to write the JSON (default OUT/metrics.json)")
    b.add_argument("--seeds", type=_SEEDS, help="override the scenario's number of seeds")
    b.add_argument(
        "--figure-formats",
        nargs="+",
        default=["png"],
        choices=("png", "pdf", "svg"),
        help="formats of the figures (default png)",
    )
    b.add_argument("--no-progress", action="store_true")
    b.set_defaults(func=_cmd_benchmark)

    v = _sub(sub, "validate", help="check a scenario and print it resolved (defaults marked)")
    v.add_argument("scenario", nargs="?", help="scenario TOML (default: the shipped payload_swap)")
    v.set_defaults(func=_cmd_validate)

    w = _sub(sub, "sweep", help="grid over scenario fields x controllers x seeds, on Dask")
    w.add_argument("sweep", help="sweep TOML (see docs/sweeps.md)")
    w.add_argument("--out", default="results/sweep", help="folder for cells, table and heatmaps")
    w.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (default: local cluster)")
    w.add_argument(
        "--workers", type=_number(int, 1, 1024), help="local cluster worker processes (default: all cores)"
    )
    w.add_argument("--block", type=_SEEDS, metavar="SEEDS", help="seeds per task (overrides sweep.block)")
    w.add_argument("--no-progress", action="store_true")
    w.set_defaults(func=_cmd_sweep)
    return p


def _is_user_error(exc: BaseException) -> bool:
    """Our errors, file-system errors, and plain ValueErrors raised by adaptive_dd's own code."""
    from adaptive_dd.errors import DataError, ScenarioError, SignalError, UrdfError

    errors = ParameterError | ScenarioError | DataError | SignalError | OutputError | UrdfError | OSError
    if isinstance(exc, errors):
        return True
    if type(exc) is ValueError and exc.__traceback__ is not None:
        last = traceback.extract_tb(exc.__traceback__)[-1].filename
        return Path(last).resolve().is_relative_to(Path(__file__).resolve().parent)
    return False


def _user_message(exc: BaseException) -> str:
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return f"{where}{exc.strerror or exc}"
    return str(exc)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 ok, 1 failed check, 2 user error, 3 internal error)."""
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)
    args.given = frozenset(a.split("=", 1)[0] for a in argv if a.startswith("--"))
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print(f"adaptive-dd {args.command}: interrupted; outputs left as before", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if _is_user_error(exc):  # our errors name what was wrong and where
            print(f"adaptive-dd {args.command}: error: {_user_message(exc)}", file=sys.stderr)
            return EXIT_USAGE
        if args.debug:
            traceback.print_exc()
        print(
            f"adaptive-dd {args.command}: internal error: {type(exc).__name__}: {exc}; please report it "
            f"at {ISSUE_TRACKER}, rerun with --debug for the traceback",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
