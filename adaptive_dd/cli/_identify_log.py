"""``identify --arm``: identification of any arm from a log (the paper's two-link arm has its own
path, :mod:`adaptive_dd.cli._identify_two_link`).

The record is read through the scenario's ``[record]`` table (:mod:`adaptive_dd.record`;
without one, the simulator's ``t, q1.., qd1.., tau1..`` columns), identified by weighted least
squares on the exact filtered regression (:mod:`adaptive_dd.identification.log_fit`), then,
where it can simulate the record, refined by output error; the model goes to ``OUT/model.json``
(:mod:`adaptive_dd.identification.identified_model`).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.cli._common import NAME_WIDTH, short
from adaptive_dd.cli._identify_files import _write_estimates, _write_model
from adaptive_dd.cli._identify_payload import _print_payload, _write_payload
from adaptive_dd.cli._identify_width import choose_coulomb_width
from adaptive_dd.errors import DataError, ParameterError, SignalError

Array = NDArray[np.float64]


def _print_fit(model, fit, names: tuple[str, ...], loaded: bool = False) -> None:
    used = [names[j] for j in np.flatnonzero(fit.used)]
    print(
        f"weighted least squares on the exact filtered regression (tau_f = {fit.tau_f:.3g} s), "
        f"torque channels {', '.join(used)}; {int(fit.identified.sum())} of {model.p} base parameters "
        "identified, "
        f"{int((~fit.identified).sum())} not seen by the fitted channels, kept at the URDF's values"
    )
    pieces = "" if fit.regression.pieces is None else f", within each of {len(fit.regression.pieces)} pieces"
    from adaptive_dd.identification.log_covariance import filter_lag, lag_source

    span = lag_source(fit.lag, fit.regression.row_bounds(), filter_lag(fit.tau_f, fit.sample_period))
    print(
        "std: Newey-West sandwich on the residual (model error included), lag "
        f"{fit.lag} samples = {fit.lag * fit.sample_period:.3g} s ({span}{pieces}), its variance times "
        f"{fit.kernel_factor:.3g} for what the Bartlett sum leaves out (its weights, the lags beyond) "
        f"and {fit.dof_factor:.3g} for the "
        f"{fit.columns} columns fitted ({_columns(fit)}) to about {fit.n_eff:.0f} independent samples "
        "(n_eff / (n_eff - k))"
    )
    print(
        "  what a std means: the spread this estimate would have over records like this one (another "
        "take of the same excitation, another stretch of it), its residual's colour and changing level "
        f"included; estimate +- {fit.quantile:.3g} std (not 1.96: the std is estimated from the record, "
        "the quantile is Kiefer and Vogelsang's fixed-b one of the Newey-West t, its bandwidth fraction "
        f"b = {fit.bandwidth:.3g} from how much the std itself varies over such records) holds the "
        "parameters the "
        "model fits best on such records about 95 % of the time. It does not hold the choice of model "
        "(friction law, tau_f, the channels fitted)"
    )
    print(f"{'base parameter':<{NAME_WIDTH}} {'estimate':>11} {'std':>9} {'std/|est| %':>11} {'URDF':>11}")
    share = fit.held.share if fit.held is not None else np.zeros(model.p)
    for k, name in enumerate(model.names):
        if fit.identified[k]:
            rel = 100 * fit.std[k] / max(abs(fit.sigma[k]), 1e-300)
            note = f"{rel:11.3g}" if share[k] <= 0.5 else f"{'held':>11}"
            print(
                f"{short(name):<{NAME_WIDTH}} {fit.sigma[k]:11.5g} {fit.std[k]:9.2g} {note} "
                f"{model.sigma_ref[k]:11.5g}"
            )
    fixed = [model.names[k] for k in np.flatnonzero(~fit.identified)]
    if fixed:
        print(
            "not seen by the fitted channels, kept at the URDF's values: "
            + ", ".join(short(f) for f in fixed)
        )
    _print_held(model, fit, loaded)
    print(
        "per channel [N m rms], filtered: residual "
        + ", ".join(f"{names[j]} {fit.residual_rms[j]:.3g}" for j in np.flatnonzero(fit.used))
    )
    for j, ratio in fit.model_error_channels():
        print(
            f"warning: {names[j]}: the residual is {ratio:.0f}x the sensor noise ({fit.noise_rms[j]:.2g} N m "
            "after the filter): the model explains this channel far worse than the sensor allows (friction "
            "law, unmodelled dynamics, conversion constants, a clock offset between the log's files); "
            "the std above take its size into account, not a bias it leaves (a wrong conversion constant "
            "or clock offset biases the estimates beyond them: fix those first)"
        )


def _columns(fit) -> str:
    """What the fit's ``k`` columns are: parameters, offsets, Coulomb widths."""
    k = int(fit.identified.sum())
    m = 0 if fit.offset is None else int(fit.used.sum())
    parts = [f"{k} parameters"] + [f"{m} torque offsets"] * bool(m)
    if fit.columns > k + m:
        parts.append(f"{fit.columns - k - m} Coulomb widths")
    return ", ".join(parts)


def _far(held) -> str:
    """How far the URDF is from a record's estimate, against its stated uncertainty (a conflict's)."""
    return f"{np.sqrt(held.scale2):.3g}x further from the estimate than the stated uncertainty allows"


def _print_held(model, fit, loaded: bool = False) -> None:
    """The directions the record cannot see, held at the URDF's values, and why (``loaded``: the
    record is the loaded one of ``--baseline``'s pair, which the URDF's prior is not about)."""
    held = fit.held
    if held is not None and held.conflict:
        far = _far(held)
        if loaded:  # the payload the URDF lacks puts it there: expected, not a fault of the data
            print(
                f"no direction held by the URDF's prior: the URDF is {far}, as the payload this loaded "
                "record carries (and the URDF lacks) makes it; every direction is estimated, and the pair's "
                "difference below is the payload (the unloaded record is held to the URDF below)"
            )
            return
        print(
            f"no direction held by the URDF's prior: along the directions the record sees best the URDF is "
            f"{far} (a prior the record contradicts: "
            "adaptive_dd.identification.held_directions.prior_conflict), so every direction is estimated; "
            "state the URDF's uncertainty ([plant.uncertainty]) to hold"
        )
        return
    if held is None or held.count == 0:
        return
    print(
        f"held at the URDF's values, {held.count} direction(s) the record cannot see (the estimate's std "
        "along each above the prior's, the stated uncertainty about the URDF; their std is the prior's, "
        "'held' above: adaptive_dd.identification.held_directions):"
    )
    if held.scale2 > 1.0:
        print(
            f"  the prior widened {np.sqrt(held.scale2):.3g}x: along the directions the record sees best the "
            "URDF is that much further from the estimate than the stated uncertainty allows"
        )
    for line in held.describe(model.names, short):
        print(f"  {line}")


def _information(model, fit) -> Array:
    """Information for the consistent fit: the estimate's, and those held at the URDF pinned to 0.1 %."""
    F = np.zeros((model.p, model.p))
    K = fit.identified
    F[np.ix_(K, K)] = np.linalg.pinv(fit.cov[np.ix_(K, K)], rcond=1e-12, hermitian=True)
    pin = 1e-3 * np.maximum(np.abs(model.sigma_ref), 1e-6)
    F[~K, ~K] = 1.0 / pin[~K] ** 2
    return F


def _output_error(args, arm, model, rec, fit):
    """Output error from the WLS estimate where the record can be simulated, else a message; the fit
    to write: output error's (:func:`_with_output_error`) when it converged with its noise model,
    else ``fit``."""
    from adaptive_dd.identification.output_error import fit_output_error, measurement_std

    mode = args.output_error
    if mode == "off" or (mode == "auto" and not rec.simulator_format):
        unused = [o for o in ("--max-iter", "--segment-length") if o in getattr(args, "given", ())]
        print(
            (
                "output error: skipped (a real log: the open-loop simulation of a position-controlled arm "
                "drifts; --output-error on to try it)"
                if mode == "auto"
                else "output error: skipped (--output-error off)"
            )
            + (f"; {', '.join(unused)} not used" if unused else "")
        )
        return fit
    if not rec.used.all():
        print("output error: skipped (it simulates every joint; the record leaves torque channels out)")
        return fit
    if len(rec.spans) > 1:
        print("output error: skipped (it simulates one continuous record; this one has several pieces)")
        return fit
    std = measurement_std(arm).copy()
    if not rec.qd_measured:
        std[arm.n_joints :] = np.inf
    print(  # it runs for minutes on a long record of a 7-joint arm: say so before, not after
        f"output error: maximum likelihood from the WLS estimate, up to {args.max_iter} iterations over "
        f"segments of {args.segment_length} samples (--output-error off skips it) ...",
        flush=True,
    )
    E = _free_directions(fit)
    # the channels read tau + b: the offsets fitted with the parameters come off the applied torque
    tau = rec.tau if fit.offset is None else rec.tau - np.where(fit.used, fit.offset, 0.0)[None, :]
    try:
        oe = fit_output_error(
            model,
            rec.q,
            rec.qd,
            tau,
            fit.sigma,
            std,
            sample_period=rec.sample_period,
            segment_length=args.segment_length,
            max_iter=args.max_iter,
            E=E,
        )
    except (SignalError, ParameterError, np.linalg.LinAlgError) as exc:
        print(f"output error: skipped, the record cannot be simulated from the WLS estimate ({exc})")
        return fit
    _print_output_error_fit(
        oe,
        "; torque offsets fitted by WLS taken off the torques" if fit.offset is not None else "",
        " (another friction law, a torque scale or offset, a wrong sensor noise), so the output error's "
        "estimate and its Cramér-Rao bounds below do not hold",
    )
    print(
        f"{'base parameter':<{NAME_WIDTH}} {'WLS':>11} {'output err':>11} {'CRB std':>9} {'|WLS-OE|/CRB':>12}"
    )
    crb = np.sqrt(np.abs(np.diag(E @ np.linalg.pinv(oe.information, hermitian=True) @ E.T)))
    share = fit.held.share if fit.held is not None else np.zeros(model.p)
    for k, name in enumerate(model.names):
        if share[k] > 0.5:  # no estimate there, so no bound on one: the prior's std is in the WLS table
            row = f"{short(name):<{NAME_WIDTH}} {fit.sigma[k]:11.5g} {oe.sigma[k]:11.5g}"
            print(f"{row} {'held':>9} {'-':>12}")
            continue
        print(
            f"{short(name):<{NAME_WIDTH}} {fit.sigma[k]:11.5g} {oe.sigma[k]:11.5g} {crb[k]:9.2g} "
            f"{abs(fit.sigma[k] - oe.sigma[k]) / crb[k]:12.1f}"
        )
    if fit.held is not None and fit.held.count:
        print(
            f"output error kept the {fit.held.count} held direction(s) at the URDF's values; 'held': no "
            "estimate, so no Cramér-Rao bound (the prior's std is in the table above)"
        )
    print(
        "CRB: Cramér-Rao std at the estimate for this record, q and qd measured with the arm's sensor "
        f"noise, torque known, segments of {oe.segment_length} samples with unknown initial states"
    )
    if not oe.converged or _normalised_residual(oe) > RESIDUAL_LIMIT:
        print(
            "the model written (model.json, estimates.csv; what predict and [model] from read) is the WLS "
            "estimate, with its std: output error did not converge with its noise model"
        )
        return fit
    _disagreement(model, fit, oe, share)
    print(
        "the model written (model.json, estimates.csv; what predict and [model] from read) is output "
        "error's, with its Cramér-Rao std (95 % bound +- 1.96 std; the held directions keep the WLS "
        "prior's): it converged with its noise model, the maximum-likelihood estimate of this record"
    )
    return _with_output_error(fit, oe, E)


def _with_output_error(fit, oe, E):
    """``fit`` with output error's estimate and Cramér-Rao covariance in the directions ``E`` it
    moved (the held ones keep the WLS fit's prior covariance), the 95 % bound +- 1.96 std.

    On simulated vertical3 records (``python benchmarks/output_error_coverage.py``: 12 seeds, 17
    parameters) the written estimate's rms error is 0.048 times the least squares', its bound as
    honest (the truth inside 94.6 % against 95.6 %; rms of (estimate - truth) / std 1.06 both)."""
    import dataclasses

    # oe.information is (r, r) in the coordinates of E; the held directions are the null space of the
    # fit's oblique projector (the prior's scales), not E's orthogonal complement
    free = E @ np.linalg.pinv(oe.information, hermitian=True) @ E.T
    cov = free
    if fit.held is not None and fit.held.count:
        held = np.eye(E.shape[0]) - fit.held.projector
        cov = free + held @ fit.cov @ held.T
    return dataclasses.replace(
        fit, sigma=np.asarray(oe.sigma, float), cov=cov, std=np.sqrt(np.abs(np.diag(cov))), quantile=1.96
    )


def _disagreement(model, fit, oe, share) -> None:
    """A warning when output error, converged with its noise model, lies outside the WLS estimate's
    95 % bound on some parameters: there the least squares is biased and its bound does not hold the
    truth (on a simulated Kinova record, 13 of 35 parameters outside it; output error on them)."""
    residual = _normalised_residual(oe)
    if not oe.converged or residual > RESIDUAL_LIMIT:
        return
    free = (share <= 0.5) & (fit.std > 0)
    z = np.where(free, np.abs(fit.sigma - oe.sigma) / np.where(free, fit.std, 1.0), 0.0)
    out = np.flatnonzero(z > fit.quantile)
    if out.size == 0:
        return
    k = int(np.argmax(z))
    print(
        f"warning: output error lies outside the WLS estimate's 95 % bound on {out.size} of "
        f"{int(free.sum())} parameters (the farthest {short(model.names[k])}: {z[k]:.1f} of its WLS std); "
        "output error converged with its noise model (the sensors' noise, which the least squares "
        "leaves out of its regressor), so there the least squares is biased and its bound does not "
        "hold the truth (docs/real_log.md); the model written is output error's"
    )


RESIDUAL_LIMIT = 2.0
"""The output error's normalised residual above which ``identify`` warns that its model does not
explain the record (about 1 when the model and the noise are right; 28 with a torque offset not
taken off, 1.06 with a width profiled)."""


def _normalised_residual(oe) -> float:
    """Output error's ``2 cost / residuals``: about 1 when the model and the noise are right."""
    return 2 * oe.cost / oe.n_residuals


def _print_output_error_fit(oe, said: str, consequence: str) -> None:
    """Output error's iterations, convergence and normalised residual (``said`` appended), and a
    warning with ``consequence`` when the residual is above :data:`RESIDUAL_LIMIT`."""
    residual = _normalised_residual(oe)
    print(
        f"output error: {oe.iterations} iterations, {'converged' if oe.converged else 'NOT converged'}, "
        f"normalised residual {residual:.3f} (1 = the noise model){said}"
    )
    if residual > RESIDUAL_LIMIT:
        print(
            f"warning: the normalised residual is {residual:.3g}, not about 1: the model does not explain "
            f"the record to its sensors' noise{consequence}"
        )


def _free_directions(fit):
    """``E (p, r)``: the base parameters' directions output error may move, all but those the
    weighted least squares held (an orthonormal basis of its projector's range)."""
    p = fit.sigma.shape[0]
    if fit.held is None or fit.held.count == 0:
        return np.eye(p)
    U = np.linalg.svd(fit.held.projector)[0]
    return U[:, : p - fit.held.count]


def _consistent(model, fit):
    from adaptive_dd.identification.consistency import consistent_arm_fit

    try:
        cf = consistent_arm_fit(model, fit.sigma, _information(model, fit))
    except (ValueError, np.linalg.LinAlgError) as exc:
        print(f"no physically consistent fit: {exc}")
        return None
    print(
        "nearest physically consistent arm (every link's pseudo-inertia positive definite, friction and "
        f"armature >= 0): {cf.distance:.2f} std from the estimate"
    )
    return cf


def identify_log(args: argparse.Namespace, arm, outputs) -> int:
    """``adaptive-dd identify --arm SCENARIO [FILES]`` for an arm from a URDF."""
    from adaptive_dd.identification.friction_width import identification_model
    from adaptive_dd.identification.log_fit import MAX_DOF_FACTOR, identifiable_subset, too_few_samples
    from adaptive_dd.identification.regression import momentum_regressors
    from adaptive_dd.identification_plots import plot_torque_fit

    for note in arm.urdf_notes:
        print(f"note: {note}")
    spec, rec, tau_f = _read(args, arm, args.data)
    offset = _offset_choice(args, rec)
    derived = None if rec.qd_measured else rec.q  # the width of a derived velocity's noise
    model = identification_model(arm, rec.qd, derived, rec.sample_period)  # the width from the record's noise
    names = arm.joint_names
    if args.payload_only:
        if args.torque_offset == "on":
            raise DataError(
                "--torque-offset on: --payload-only fits by output error, which has no offsets; leave it "
                "out, or identify a loaded and an unloaded record instead (--baseline)"
            )
        model, _ = choose_coulomb_width(args, arm, model, rec, None, tau_f, spec.torque_held)
        return _payload_only(args, arm, model, rec, tau_f, outputs)
    lim = arm.position_limits
    K = identifiable_subset(model, rec.used, lim[:, 0], lim[:, 1], np.random.default_rng(0))
    model, profile = choose_coulomb_width(args, arm, model, rec, K, tau_f, spec.torque_held, offset)
    prior_std = _prior_std(args.arm, model) if args.hold_unseen == "on" else None
    free = None if profile is None else profile.profiled
    # the momentum regressors once, for the fit and the model error's other filters (_write_model)
    mom = momentum_regressors(model, rec.q, rec.qd)
    with warnings.catch_warnings():  # fit_log's warning of too few samples: said here
        warnings.filterwarnings("ignore", message=r"about .* independent samples for")
        fit = _fit_record(model, rec, K, tau_f, spec.torque_held, prior_std, free, offset, mom)
    if fit.n_eff < MAX_DOF_FACTOR * fit.columns:  # fewer than one a column: refused, nothing written
        few = too_few_samples(fit.n_eff, fit.columns, fit.regression.y.shape[0] * fit.sample_period)
        if fit.n_eff < fit.columns:
            raise DataError(f"{rec.source}: {few} ({_columns(fit)})")
        print(f"warning: {few}", file=sys.stderr)
    # before anything is printed: at twice tau_f its filters leave the fewest samples of the window
    me_var = _model_error(model, fit, rec, spec.torque_held, mom)
    _print_fit(model, fit, names, loaded=bool(args.baseline))
    _print_offset(args, fit, names)
    wls, fit = fit, _output_error(args, arm, model, rec, fit)  # output error's, when it converged
    cf = _consistent(model, fit)
    reg = fit.regression
    pred = reg.phi @ fit.sigma
    u = fit.used
    plot_torque_fit(
        rec.t[reg.samples()],
        reg.y[:, u],
        pred[:, u],
        outputs.path("torque_fit.png"),
        f"{Path(rec.source.split(',')[0]).name}: the filtered fit, the fitted channels",
        labels=[names[j] for j in np.flatnonzero(u)],
    )
    _write_estimates(outputs.path("estimates.csv"), model, fit)
    written = [outputs.path("estimates.csv"), outputs.path("torque_fit.png")]
    estimator = "wls" if fit is wls else "output_error"
    written += _write_model(outputs, arm, model, rec, fit, cf, spec, profile, me_var, estimator)
    del mom
    if args.baseline:
        written.append(_payload_pair(args, arm, model, wls, tau_f, K, outputs, offset))  # WLS both sides
    print("wrote " + ", ".join(str(Path(args.out) / Path(p).name) for p in written))
    return 0


def _model_error(model, fit, rec, torque_held: bool, momentum):
    """The fit's :func:`~adaptive_dd.identification.model_error.model_error_variance`, its error
    naming the record."""
    from adaptive_dd.identification.model_error import FILTER_FACTORS, model_error_variance

    try:
        return model_error_variance(model, fit, rec.q, rec.qd, rec.tau, torque_held, momentum)
    except DataError as exc:
        why = (
            f" (the model error's estimate at {max(FILTER_FACTORS):g} tau_f = "
            f"{max(FILTER_FACTORS) * fit.tau_f:g} s starts later in each piece)"
            if "a longer window is needed" in str(exc)
            else ""
        )
        raise DataError(f"{rec.source}: {exc}{why}") from None


def _read(args, arm, files):
    """The records ``files`` (grouped, :mod:`adaptive_dd.cli._records`) read and merged, the pieces too
    short to use left out, what was read printed; ``(spec, record, tau_f)``."""
    from adaptive_dd.cli._records import read_records
    from adaptive_dd.identification.log_fit import filter_time_constant
    from adaptive_dd.record_pieces import clock, drop_short

    spec, rec, recs = read_records(args.arm, arm, files, args.window)
    tau_f = args.tau_f or filter_time_constant(rec.sample_period)
    if tau_f < rec.sample_period:
        raise DataError(
            f"--tau-f: {tau_f:g} s is shorter than the record's sample period ({rec.sample_period:.6g} s): a "
            "filter faster than the samples passes the noise the derivative makes; give at least one "
            "sample period (the default: two, at least 0.02 s)"
        )
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s "
        f"({clock(rec.t[0])}-{clock(rec.t[-1])} s), {arm.n_joints} joints, {len(arm.sigma)} base parameters; "
        f"velocities {'measured' if rec.qd_measured else 'derived from the positions'}"
    )
    if len(recs) > 1:
        print(f"  {len(recs)} records fitted together, {len(rec.spans)} continuous pieces in all")
    for note in rec.notes:
        print(f"  {note}")
    rec, lines = drop_short(rec, int(np.ceil(10 * tau_f / rec.sample_period)))
    for line in lines:
        print(f"  {line}")
    if len(rec.spans) > 1:
        cut = int(np.ceil(10 * tau_f / rec.sample_period))
        print(
            f"  each of the {len(rec.spans)} pieces filtered on its own, its first {cut} samples "
            f"({cut * rec.sample_period:.3g} s = 10 tau_f, the filters' settling) left out"
        )
    return spec, rec, tau_f


def _offset_choice(args, rec) -> bool:
    """``--torque-offset``: auto is on for a record read through a ``[record]`` table (a real sensor's
    zero), off for the simulator's records (their torques have none)."""
    return not rec.simulator_format if args.torque_offset == "auto" else args.torque_offset == "on"


def _print_offset(args, fit, names) -> None:
    """The channels' torque offsets fitted (``--torque-offset``), or that none was."""
    if fit.offset is None:
        why = "--torque-offset off" if args.torque_offset == "off" else "auto: the simulator's record"
        print(f"torque offsets: none fitted ({why})")
        return
    why = "--torque-offset on" if args.torque_offset == "on" else "auto: a record read through [record]"
    each = [f"{names[j]} {fit.offset[j]:.3g} +- {fit.offset_std[j]:.2g}" for j in np.flatnonzero(fit.used)]
    head = f"torque offset per channel, fitted with the parameters ({why}; added by predict) [N m, +- 1 std]"
    print(f"{head}: {', '.join(each)}")


def _payload_only(args, arm, model, rec, tau_f, outputs=None) -> int:
    from adaptive_dd.identification.output_error import measurement_std
    from adaptive_dd.identification.payload_pair import payload_from_record

    if len(rec.spans) > 1:
        raise DataError(
            f"{rec.source}: --payload-only fits by output error, which simulates one continuous record; this "
            f"one has {len(rec.spans)} pieces (gaps or several records): identify a loaded and an unloaded "
            "record instead (--baseline)"
        )
    if not rec.used.all():
        raise DataError(
            f"{rec.source}: --payload-only fits by output error, which simulates every joint; the record "
            "leaves torque channels out: identify a loaded and an unloaded record instead (--baseline)"
        )
    try:
        pr = payload_from_record(
            arm,
            model,
            rec.q,
            rec.qd,
            rec.tau,
            measurement_std(arm),
            sample_period=rec.sample_period,
            segment_length=args.segment_length,
            max_iter=args.max_iter,
        )
    except (SignalError, np.linalg.LinAlgError) as exc:
        raise DataError(
            f"{rec.source}: --payload-only cannot simulate this record open loop ({exc}); identify a loaded "
            "and an unloaded record instead (--baseline)"
        ) from None
    which = (
        "the payload's 10 parameters"
        if pr.determined is None
        else f"the {int(sum(pr.determined))} of the payload's 10 parameters this arm determines"
    )
    print(
        f"{rec.source}: the arm known (its URDF), {which} fitted by output error (no filtered "
        f"regression: its time constant, {tau_f:g} s, does not apply)"
    )
    _print_output_error_fit(pr.fit, "", ", so the payload and its Cramér-Rao std below do not hold")
    if not pr.fit.converged:
        print(
            f"warning: output error stopped at --max-iter {args.max_iter} before converging: the payload "
            "below is not its optimum (raise --max-iter)"
        )
    _print_payload("payload (one record, arm known)", pr)
    if outputs is not None:
        _write_payload(outputs, pr, rec.source)
        print(f"wrote {Path(args.out) / 'payload.json'} (its scenario_payload is a [[payload]] entry)")
    return 0


def _prior_std(scenario: str, model):
    """Each base parameter's prior std about the URDF's value: the scenario's ``[plant.uncertainty]``
    levels, else issue 28's defaults (:func:`~adaptive_dd.identification.held_directions.base_prior_std`)."""
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.identification.held_directions import base_prior_std, stated_levels
    from adaptive_dd.io import read_toml
    from adaptive_dd.plant.uncertainty import _uncertainty

    table = (read_toml(Path(scenario), ScenarioError).get("plant") or {}).get("uncertainty")
    unc = None if table is None else _uncertainty(str(scenario), table)
    return base_prior_std(model, stated_levels(unc))


def _fit_record(
    model, rec, K, tau_f: float, torque_held: bool, prior_std=None, width_estimated=None, offset=False,
    momentum=None,
):  # fmt: skip
    """:func:`~adaptive_dd.identification.log_fit.fit_log` on a read record, the directions it cannot
    see held at the URDF's values with ``prior_std`` (None: none held), the Coulomb widths of the
    joints ``width_estimated`` counted as estimated, a torque offset per channel with ``offset``,
    ``momentum`` the record's momentum regressors when computed already; its errors name the record."""
    from adaptive_dd.identification.log_fit import fit_log

    try:
        return fit_log(
            model, rec.q, rec.qd, rec.tau, rec.used, K, tau_f=tau_f, sample_period=rec.sample_period,
            channel_weight=rec.weight, torque_held=torque_held, prior_std=prior_std,
            hold=prior_std is not None, width_estimated=width_estimated, pieces=rec.pieces or None,
            offset=offset, momentum=momentum,
        )  # fmt: skip
    except DataError as exc:
        raise DataError(f"{rec.source}: {exc}") from None
    except np.linalg.LinAlgError as exc:  # not met so far: the record's checks come first
        raise DataError(
            f"{rec.source}: the weighted least squares failed numerically ({exc}); check the record's "
            "conversions (a huge or constant column) and its window"
        ) from None


def _payload_pair(args, arm, model, fit, tau_f, K, outputs, offset=False):
    from adaptive_dd.identification.payload_pair import payload_from_pair

    print("unloaded record(s):")
    spec, base, _ = _read(args, arm, args.baseline)
    prior_std = _prior_std(args.arm, model) if args.hold_unseen == "on" else None
    other = _fit_record(model, base, K, tau_f, spec.torque_held, prior_std, offset=offset)
    if other.held is not None and other.held.conflict:  # no payload there: the URDF itself is off
        print(
            f"the unloaded record contradicts the URDF's prior too: the URDF is {_far(other.held)}, so "
            "the URDF itself is off, not only by the payload; state the URDF's uncertainty "
            "([plant.uncertainty])"
        )
    pr = payload_from_pair(arm, fit.sigma, fit.cov, other.sigma, other.cov, weighting="diagonal")
    loaded = ", ".join(args.data) if args.data else "the scenario's record"
    _print_payload(f"payload (loaded {loaded} - unloaded {', '.join(args.baseline)})", pr)
    print(
        "  +- is one std: the spread of this payload over pairs of records like these (each side's "
        "Newey-West covariance; the base parameters weighted by their own variance, the covariance a "
        "sandwich); +- 1.96 std holds the payload about 95 % of the time. Not the choice of model"
    )
    return _write_payload(outputs, pr, f"{loaded} - {', '.join(args.baseline)}")
