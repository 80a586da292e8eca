"""``identify`` on the paper's two-link arm: one CSV ``t, q1, q2, [qd1, qd2,] tau1, tau2``, the
paper's estimators on sigma (eq. 9) with the Cramér-Rao bound beside, or the online estimator of
``adaptive_ct`` over the record (``--online``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def identify_two_link(args: argparse.Namespace, arm) -> int:
    """Read the one CSV, check it can be identified, then the estimator or the online run (which
    starts from ``arm``'s sigma: the SICE arm's, Table 1, without ``--arm``)."""
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.estimators import estimate
    from adaptive_dd.identification.log_fit import filter_time_constant
    from adaptive_dd.io import MIN_EQUATIONS, check_identifiable, read_recording
    from adaptive_dd.outputs import OutputSet

    if len(args.data) != 1:
        which = f"of the two-link arm of {args.arm}" if args.arm else "without --arm"
        raise DataError(f"identify {which} reads one CSV file, got {len(args.data)}: {args.data}")
    args.data = args.data[0]
    try:
        rec = read_recording(args.data)
    except DataError as e:  # a gap or a missing value: the --arm path reads the log as it comes
        if not any(w in str(e) for w in ("non-uniform sampling", "not a number", "non-finite value")):
            raise
        raise DataError(f"{e}; {LOG_REMEDY.format(file=args.data)}") from None
    if args.tau_f is None:  # sized to the sample rate, as on any arm: 0.02 s up to T = 10 ms
        args.tau_f = filter_time_constant(rec.sample_period)
    if args.method == "M2" and rec.qd is None:
        raise DataError(f"{args.data}: method M2 needs columns qd1, qd2 (use --method M1 for position only)")
    check_identifiable(rec, args.tau_f)
    _smooth_law_record(args)
    outputs = OutputSet(args.out)
    with outputs:
        if args.online:
            return _identify_online(args, arm, rec, outputs)
        return _identify(args, rec, outputs, estimate, MIN_EQUATIONS)


LOG_REMEDY = (
    "the paper's estimators read a uniformly sampled record with every cell a number; --arm reads a "
    "log as it comes (gaps bridged or split into pieces, rows with missing values left out): identify "
    '{file} --arm SCENARIO, where SCENARIO\'s [arm] has robot = "sice_arm" and general = true for the '
    "paper's arm (benchmarks/scenarios/sice_general.toml in the repository has them), with --window START "
    "END to use part of the log; or cut the file to a stretch without them"
)
GENERAL_REMEDY = (
    'identify it on the general model: --arm a scenario whose [arm] has robot = "sice_arm" and general = true'
)


def _smooth_law_record(args) -> None:
    """A record ``simulate`` made on the general model with the smooth Coulomb law (its
    ``trajectory.json`` says so): the closed forms' output error and Cramér-Rao bound simulate
    stick-slip friction, so output error is refused (on such a 10 s record it landed 60-340 of its
    bounds off the truth) and the bound's caveat said."""
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification.friction_width import simulated_width

    made = simulated_width(args.data) if not args.online else None
    if made is None:
        return
    why = (
        f"{args.data} was simulated on the general model with the smooth Coulomb law fc tanh(qd / "
        f"{made[0]:g}) ({made[1]}), and the paper's closed forms simulate stick-slip friction"
    )
    if args.estimator == "output_error":
        raise DataError(f"{why}: their output error would fit the wrong plant; {GENERAL_REMEDY}")
    print(f"note: {why}: the Cramér-Rao bound below is that of the stick-slip plant; {GENERAL_REMEDY}")


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
        f"{args.estimator}, method {args.method}, split {res.split}, tau_f = {args.tau_f:.6g}"
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


def _identify_online(args, arm, rec, outputs) -> int:
    """The online estimator of ``adaptive_ct`` over a record: estimates and alarms over time."""
    import dataclasses

    from adaptive_dd.controllers.adaptive import ADAPTIVE_ONLINE
    from adaptive_dd.errors import DataError
    from adaptive_dd.identification import two_link_online

    if rec.qd is None:
        raise DataError(f"{args.data}: --online needs the measured velocity (columns qd1, qd2)")
    cfg = dataclasses.replace(ADAPTIVE_ONLINE, sample_period=rec.sample_period, tau_f=args.tau_f)
    # the arm's sigma: the nominal model the estimator starts from (the SICE arm's without --arm)
    r = two_link_online.run_two_link_online(rec.q, rec.qd, rec.tau, cfg, arm.sigma)
    model, alarms = r.sigma_model[0], r.alarm_times()[0]
    mass = arm.payload_mass_from_sigma(model)
    start = f"the sigma of {args.arm}" if args.arm else "Table 1"
    print(
        f"{rec.source}: online estimator of adaptive_ct (tau_f = {args.tau_f:.6g} s, started at {start}), "
        f"{rec.t.size} samples; {len(alarms)} change alarm(s)"
        + (f" at {', '.join(f'{a:.3f}' for a in alarms)} s" if alarms else "")
        + f"; skipped samples {int(r.n_skipped[0])}"
    )
    _write_online(args, rec, outputs, model, mass, r.alarm[0], alarms)
    return 0


def _write_online(args, rec, outputs, model, mass, alarm, alarms) -> None:
    """The final estimates printed; online.csv and online.png written."""
    from adaptive_dd.outputs import atomic_write
    from adaptive_dd.plant.parameters import SIGMA_NAMES
    from adaptive_dd.plotting import plot_estimates

    print(f"{'param':>6} {'final':>12}")
    for k, name in enumerate(SIGMA_NAMES):
        print(f"{name:>6} {model[-1, k]:12.5g}")
    print(f"payload mass implied at the end: {round(float(mass[-1]), 3) + 0.0:.3f} kg")
    with atomic_write(outputs.path("online.csv")) as fh:
        fh.write("t," + ",".join(SIGMA_NAMES) + ",payload_mass,alarm\n")
        for k in range(rec.t.size):
            vals = ",".join(f"{v:.9g}" for v in model[k])
            fh.write(f"{rec.t[k]:.9g},{vals},{mass[k]:.6g},{int(alarm[k])}\n")
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


def _print_with_bound(final, std, crb, rec, args: argparse.Namespace) -> None:
    from adaptive_dd.plant.parameters import SIGMA_NAMES

    if crb is None:  # said on stderr by _identify_bound
        print(f"{'param':>6} {'estimate':>12} {'std':>10}")
        for k, name in enumerate(SIGMA_NAMES):
            print(f"{name:>6} {final[k]:12.5g} {std[k]:10.2g}")
        return
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
    if getattr(args, "estimator", None) == "paper":
        print(
            "note: the paper's estimator's std is its forgetting-factor RLS's P on the scalar splits, not "
            "a confidence interval: it leaves out the construction's bias (docs/paper_reading.md), which "
            "can be many of these std; --estimator exact or output_error for bounds that hold the truth"
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
    """Cramér-Rao bound at the estimate for the record's torque, the initial state estimated too;
    None (said) when the model at the estimate, driven by the record's torque, does not stay finite."""
    from adaptive_dd.errors import SignalError
    from adaptive_dd.identification.fisher import fisher_information
    from adaptive_dd.plant.parameters import project_sigma

    qd0 = np.zeros(2)
    if rec.qd is not None:  # a measured velocity within 3 noise std of zero: at rest (stuck)
        at_rest = np.abs(rec.qd[0]) <= 3 * np.sqrt(np.asarray(args.velocity_variance))
        qd0 = np.where(at_rest, 0.0, rec.qd[0])
    try:
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
    except SignalError as exc:
        print(
            f"CRB: not computed: the record's torque drives the model at this estimate to a non-finite "
            f"state ({exc}): the estimate is far from the arm that made the record (a short or little "
            "exciting record); a longer record, or --estimator exact / output_error",
            file=sys.stderr,
        )
        return None
