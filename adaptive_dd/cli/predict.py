"""``adaptive-dd predict --arm SCENARIO --model model.json [FILES]``: the torque prediction error of
an identified model on another record.

Any arm that ``identify --arm`` wrote a model for: the arm is the model's own
(``model.json``), the record is read through the scenario's ``[record]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.cli._common import POS, add_command, add_window_option, read_arm_log
from adaptive_dd.errors import DataError, ParameterError

__all__ = ["add_parser", "lowpass", "run"]

Array = NDArray[np.float64]
LOWPASS_ORDER = 4


def add_parser(sub) -> None:
    """The options of ``predict``."""
    r = add_command(sub, "predict", help="torque prediction error of an identified model on another record")
    r.add_argument("data", nargs="*", help="the record's file(s) (default: the scenario's record.files)")
    r.add_argument("--arm", required=True, metavar="SCENARIO", help="scenario TOML with [arm] and [record]")
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
    """Predict the record's torque; print the error per joint, unfiltered and low-passed; write both."""
    from adaptive_dd.identification.identified_model import load_identified_model
    from adaptive_dd.record import derivatives

    m = load_identified_model(args.model)
    _check_same_urdf(args.arm, m, args.model)
    arm = m.arm()
    model = m.arm_model()
    _, rec = read_arm_log(args.arm, arm, args.data, args.window)
    qd, qdd = derivatives(rec.q, rec.sample_period)
    if rec.qd_measured:
        qd = rec.qd
    tau_hat = m.predict(rec.q, qd, qdd, model)
    print(
        f"{rec.source}: {rec.t.size} samples at T = {rec.sample_period:.6g} s "
        f"({rec.t[0]:.4g}-{rec.t[-1]:.4g} s); model {args.model}; accelerations by Savitzky-Golay "
        "(cubic, ~0.1 s)"
    )
    rows = [("unfiltered", rec.tau, tau_hat)]
    if args.lowpass:
        rows.append(
            (
                f"low-passed {args.lowpass:g} Hz",
                lowpass(rec.tau, args.lowpass, rec.sample_period),
                lowpass(tau_hat, args.lowpass, rec.sample_period),
            )
        )
    used = np.asarray(m.used, dtype=bool)
    for label, tau, th in rows:
        _print_errors(label, tau, th, arm.joint_names, used)
    _write(args, rec, tau_hat, rows[-1], arm.joint_names, used)
    print(f"wrote {Path(args.out) / 'prediction.csv'}, {Path(args.out) / 'prediction.png'}")
    return 0


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
                fmt="%.8g",
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
    return filtfilt(b, a, x, axis=0)


def _check_same_urdf(scenario: str, m, model_path) -> None:
    """The scenario's ``[arm]`` names the URDF the model was identified on (the model's arm is used)."""
    from adaptive_dd.errors import ScenarioError
    from adaptive_dd.io import read_toml

    table = read_toml(Path(scenario), ScenarioError).get("arm") or {}
    if "robot" in table:
        from adaptive_dd.robots import robot_urdf

        path = robot_urdf(table["robot"])
    elif isinstance(table.get("urdf"), str):
        path = Path(table["urdf"])
        path = path if path.is_absolute() else Path(scenario).parent / path
    else:
        raise ScenarioError(f"{scenario}: predict needs an [arm] with urdf = ... or robot = ...")
    if Path(path).resolve() != Path(m.urdf).resolve():
        raise DataError(
            f"{model_path}: identified on {m.urdf}, but the scenario's [arm] is {path}: use the scenario "
            "the model was identified with"
        )
