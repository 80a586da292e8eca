"""``adaptive-dd predict --arm SCENARIO --model model.json [FILES]``: the torque prediction error of
an identified model on another record.

Any arm that ``identify --arm`` wrote a model for: the arm is the model's own
(``model.json``), the record is read through the scenario's ``[record]`` (without one: the
simulator's CSV ``t, q1..qN, [qd1..qdN,] tau1..tauN``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.cli._common import POS, add_command, add_window_option
from adaptive_dd.errors import DataError, ParameterError

__all__ = ["add_parser", "lowpass", "run", "same_arm"]

Array = NDArray[np.float64]
LOWPASS_ORDER = 4


def add_parser(sub) -> None:
    """The options of ``predict``."""
    r = add_command(sub, "predict", help="torque prediction error of an identified model on another record")
    r.add_argument(
        "data",
        nargs="*",
        help="the record(s)' file(s) (default: the scenario's record.files); several records as for "
        "identify: "
        "each as many files as record.files names, or a TOML with its own [record]",
    )
    r.add_argument(
        "--arm",
        required=True,
        metavar="SCENARIO",
        help="scenario TOML with [arm] and an optional [record]: how a real log's files are read (column "
        "names, units, gains; docs/real_log.md); without it the record is the simulator's CSV t, q1..qN, "
        "[qd1..qdN,] tau1..tauN",
    )
    r.add_argument(
        "--model", required=True, metavar="JSON", help="model.json written by identify --arm --out"
    )
    add_window_option(r)
    r.add_argument(
        "--lowpass",
        type=POS,
        default=2.0,
        metavar="HZ",
        help="also compare after a zero-phase Butterworth low-pass (order 4) of both [Hz] (default 2)",
    )
    r.add_argument("--out", default="results/predict", help="folder for prediction.csv and prediction.png")
    r.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Predict each record's torque; print the error per joint, unfiltered and low-passed, per record
    when several and pooled; write both."""
    from adaptive_dd.cli._common import arm_file, load_arm
    from adaptive_dd.cli._records import read_records
    from adaptive_dd.identification.identified_model import load_identified_model
    from adaptive_dd.outputs import check_output_dir
    from adaptive_dd.record_pieces import clock

    check_output_dir(args.out)  # before any work, as every command does
    m = load_identified_model(args.model, need_urdf=False)
    arm_file(args)
    arm = load_arm(args.arm, m.repair_inertia)
    model = same_arm(m, arm, args.model, args.arm)
    _, rec, recs = read_records(args.arm, arm, args.data, args.window)
    used = np.asarray(m.used, dtype=bool)
    parts = [_predict(r, m, model, args.lowpass) for r in recs]
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s "
        f"({clock(rec.t[0])}-{clock(rec.t[-1])} s); model {args.model}; accelerations by Savitzky-Golay "
        "(cubic, ~0.1 s)"
        + (
            f"; {len(rec.spans)} continuous pieces, each differentiated and low-passed on its own"
            if len(rec.spans) > 1
            else ""
        )
    )
    for (
        note
    ) in rec.notes:  # what reading left out or repaired (gaps, missed samples, repeats), as identify says
        print(f"  {note}")
    labels = ["unfiltered"] + ([f"low-passed {args.lowpass:g} Hz"] * bool(args.lowpass))
    if len(recs) > 1:
        for r, (tau, th, lp) in zip(recs, parts, strict=True):
            print(f"record {r.source}:")
            for label, (a, b) in zip(labels, [(tau, th), *lp], strict=False):
                _print_errors(label, a, b, arm.joint_names, used)
        print(f"all {len(recs)} records:")
    tau = np.concatenate([p[0] for p in parts])
    th = np.concatenate([p[1] for p in parts])
    rows = [("unfiltered", tau, th)]
    if args.lowpass:
        rows.append(
            (
                labels[1],
                np.concatenate([p[2][0][0] for p in parts]),
                np.concatenate([p[2][0][1] for p in parts]),
            )
        )
    for label, a, b in rows:
        _print_errors(label, a, b, arm.joint_names, used)
    _write(args, rec, th, rows[-1], arm.joint_names, used)
    print(f"wrote {Path(args.out) / 'prediction.csv'}, {Path(args.out) / 'prediction.png'}")
    return 0


def _predict(rec, m, model, cutoff):
    """``(tau, tau_hat, [(tau_lp, tau_hat_lp)])`` of one record, each piece differentiated (and
    low-passed, ``cutoff`` [Hz], None: not) on its own."""
    from adaptive_dd.record import derivatives

    th = np.empty_like(rec.tau)
    for a, b in rec.spans:
        qd, qdd = derivatives(rec.q[a:b], rec.sample_period)
        if rec.qd_measured:
            qd = rec.qd[a:b]
        th[a:b] = m.predict(rec.q[a:b], qd, qdd, model)
    if not cutoff:
        return rec.tau, th, []
    lp = [
        np.concatenate([lowpass(x[a:b], cutoff, rec.sample_period) for a, b in rec.spans])
        for x in (rec.tau, th)
    ]
    return rec.tau, th, [tuple(lp)]


def _print_errors(label: str, tau: Array, th: Array, names, used) -> None:
    err = np.sqrt(np.mean((tau - th) ** 2, axis=0))
    ref = np.sqrt(np.mean(tau**2, axis=0))
    print(f"torque prediction error, {label} [N m rms (relative to the torque's rms)]:")
    for j in range(len(names)):
        tag = "" if used[j] else "   (channel not fitted)"
        print(
            f"  {names[j]:<24} {err[j]:9.4g} ({100 * err[j] / max(ref[j], 1e-300):5.1f} %) "
            f"of {ref[j]:.4g}{tag}"
        )
    pooled = np.sqrt(np.mean((tau - th)[:, used] ** 2))
    print(f"  pooled over the fitted channels: {pooled:.4g} N m")


def _write(args: argparse.Namespace, rec, tau_hat: Array, last_row, names, used) -> None:
    """OUT/prediction.csv (t, tau1..tauN, tau_hat1..tau_hatN) and OUT/prediction.png (``last_row``)."""
    from adaptive_dd.identification_plots import plot_torque_fit
    from adaptive_dd.outputs import OutputSet, atomic_write

    with OutputSet(args.out) as outputs:
        n = len(names)
        with atomic_write(outputs.path("prediction.csv")) as fh:
            head = ["t", *[f"tau{j + 1}" for j in range(n)], *[f"tau_hat{j + 1}" for j in range(n)]]
            np.savetxt(
                fh,
                np.column_stack([rec.t, rec.tau, tau_hat]),
                delimiter=",",
                header=",".join(head),
                comments="",
                fmt=["%.15g", *["%.8g"] * (2 * n)],  # 15 digits: an epoch's stamps keep their 10 us steps
            )
        label, tau, th = last_row
        plot_torque_fit(
            rec.t,
            tau[:, used],
            th[:, used],
            outputs.path("prediction.png"),
            f"measured vs predicted torque ({label}), the fitted channels",
            labels=[names[j] for j in np.flatnonzero(used)],
        )


def lowpass(x: Array, cutoff: float, T: float) -> Array:
    """Zero-phase Butterworth low-pass (order 4, forward and backward) along axis 0."""
    from scipy.signal import butter, filtfilt

    if not 0 < cutoff < 0.5 / T:
        raise ParameterError(f"--lowpass {cutoff} Hz must be in (0, {0.5 / T:.4g}) (the Nyquist frequency)")
    b, a = butter(LOWPASS_ORDER, cutoff, fs=1.0 / T)
    return filtfilt(b, a, x, axis=0, padlen=min(3 * max(len(a), len(b)), x.shape[0] - 1))


def same_arm(m, arm, model_path, scenario):
    """The identification model of ``arm`` (the scenario's) when it is the arm ``m`` was identified on,
    by content (:func:`~adaptive_dd.identification.identified_model.arm_identity`), whatever its path.

    Raises
    ------
    DataError
        Another arm, naming what differs (joints, axes, placements, the parameters the model fixed).
    """
    from adaptive_dd.identification.identified_model import arm_identity, identity_differences
    from adaptive_dd.identification.model import arm_model

    if list(arm.joint_names) != list(m.joint_names):
        raise DataError(
            f"{model_path}: identified on an arm of joints {m.joint_names} ({Path(m.urdf).name}), but the "
            f"arm of {scenario} has {list(arm.joint_names)}: use the scenario the model was identified with"
        )
    model = arm_model(arm)
    mine = m.identity
    if mine is None:  # a file written before identities: the arm at its URDF path
        mine = arm_identity(m.arm(), arm_model(m.arm()), m.identified)
    held = m.identified if model.p == len(m.identified) else np.ones(model.p, bool)
    diff = identity_differences(mine, arm_identity(arm, model, held))
    if diff:
        more = f" (and {len(diff) - 6} more)" if len(diff) > 6 else ""
        raise DataError(
            f"{model_path}: identified on another arm than the one of {scenario} ({arm.urdf}); what differs "
            f"(the model's, then this arm's): {'; '.join(diff[:6])}{more}"
        )
    if list(model.names) != list(m.names):
        raise DataError(
            f"{model_path}: its {len(m.names)} base parameters are not those of the arm of {scenario} "
            f"({model.p}): another arm (or the URDF changed since the identification)"
        )
    return m.arm_model(arm)
