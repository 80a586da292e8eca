"""The TIAGo real log: held-out torque prediction against a plain least squares, and the bounds' honesty.

Run from the repository root::

    python benchmarks/real_log.py            # the shipped record, examples/tiago/tiago.toml
    python benchmarks/real_log.py --coulomb-width noise --torque-offset off   # the other choices
    python benchmarks/real_log.py --drop 28.0 10   # 10 rows dropped at 28 s, as a logger drops packets

1. Trained on 9.21-48 s, predicting 48-67.9 s (arm_1 ... arm_4, the channels that carry
   torque): adaptive_dd's weighted least squares on the exact filtered regression
   (:mod:`adaptive_dd.identification.log_fit`, what ``identify --arm`` runs) against a plain
   least squares on Pinocchio's ``computeJointTorqueRegressor`` with viscous, Coulomb
   (sign) and armature columns per joint, on the same resampled record with the same
   Savitzky-Golay velocities and accelerations; and the URDF alone. Errors are RMS after
   the same zero-phase 2 Hz low-pass of measured and predicted torque (order-4 Butterworth,
   forward-backward), and unfiltered.
2. The reported standard deviations against the spread of the estimates over disjoint
   windows of the excitation (each window identified alone): per identified base parameter
   the ratio spread / reported std (1 = honest), summarised by its median and quartiles, the
   fraction within a factor 3 against what an exact std gives with that many windows, and the
   ratio's scale ``sqrt(mean ratio^2)`` with the interval an exact std gives (:func:`honesty`:
   the count within a factor 3 hardly tells an exact std from one half the spread; the scale
   does).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import time
from pathlib import Path

import numpy as np

from adaptive_dd.cli._common import load_arm, read_arm_log
from adaptive_dd.cli.identify import coulomb_width_option
from adaptive_dd.cli.predict import lowpass
from adaptive_dd.identification.friction_width import (
    auto_coulomb_width,
    identification_model,
    profile_coulomb_width,
)
from adaptive_dd.identification.log_fit import (
    filter_time_constant,
    fit_log,
    identifiable_subset,
    predict_torque,
)
from adaptive_dd.record import derivatives

ROOT = Path(__file__).resolve().parent.parent


def plain_least_squares(arm, q, qd, qdd, tau, used):
    """Pinocchio's joint-torque regressor plus fv, fc (sign), Ia columns; min-norm least squares on
    the channels ``used``. Returns a predictor ``(q, qd, qdd) -> tau (N, n)``."""
    import pinocchio as pin

    model = arm.model
    data = model.createData()
    n = arm.n_joints

    def regressor(q, qd, qdd):
        rows = []
        for k in range(q.shape[0]):
            Y = pin.computeJointTorqueRegressor(model, data, arm.pin_configuration(q[k]), qd[k], qdd[k])
            rows.append(np.hstack([Y, np.diag(qd[k]), np.diag(np.sign(qd[k])), np.diag(qdd[k])]))
        return np.asarray(rows)  # (N, n, 13 n)

    W = regressor(q, qd, qdd)[:, used, :].reshape(-1, 13 * n)
    theta, *_ = np.linalg.lstsq(W, tau[:, used].reshape(-1), rcond=None)
    return lambda q, qd, qdd: regressor(q, qd, qdd) @ theta


def noise_model(arm, rec):
    """identify's model of ``rec``: the Coulomb width of its velocities' noise (derived velocities':
    the positions' noise through the derivative)."""
    return identification_model(arm, rec.qd, None if rec.qd_measured else rec.q, rec.sample_period)


def with_width(model, rec, K, choice, torque_held: bool, offset: bool = False):
    """``model`` with the Coulomb width ``identify --coulomb-width choice`` gives on ``rec``, and the
    joints whose width was estimated (None: none)."""
    if choice == "auto":  # identify's rule
        choice, _ = auto_coulomb_width(rec)
    if choice == "noise":
        return model, None
    if choice != "profile":
        return dataclasses.replace(model, friction_velocity=float(choice)), None
    T = rec.sample_period
    pr = profile_coulomb_width(
        model,
        rec.q,
        rec.qd,
        rec.tau,
        rec.used,
        K,
        tau_f=filter_time_constant(T),
        sample_period=T,
        torque_held=torque_held,
        pieces=rec.pieces or None,
        offset=offset,
    )
    return dataclasses.replace(model, friction_velocity=pr.width), pr.profiled


def rms(e):
    return np.sqrt(np.mean(e**2, axis=0))


def piecewise(rec, f):
    """``f(a, b)`` on each continuous piece ``[a, b)`` of ``rec``, the results end to end."""
    return np.concatenate([f(a, b) for a, b in rec.spans])


def drop_rows(scenario: str, at: float, rows: int) -> str:
    """A copy of the scenario and its record in a temporary folder (removed at exit), ``rows`` rows
    dropped from every file at ``at`` s (a logger's gap); returns the copy's scenario."""
    import atexit
    import shutil
    import tempfile

    import pandas as pd

    from adaptive_dd.io import read_toml
    from adaptive_dd.robots.example_robot_data import is_example_robot_data

    src = Path(scenario)
    dst = Path(tempfile.mkdtemp(prefix="real_log_gap_"))
    atexit.register(shutil.rmtree, dst, True)  # the copies go when the script ends
    table = read_toml(src)
    for f in table["record"]["files"]:
        frame = pd.read_csv(src.parent / f)
        i = int(np.searchsorted(frame[table["record"].get("time", "t")].to_numpy(), at))
        frame.drop(index=range(i, i + rows)).to_csv(dst / f, index=False)
    urdf = table.get("arm", {}).get("urdf")
    text = src.read_text(encoding="utf-8")
    if isinstance(urdf, str) and not is_example_robot_data(urdf) and not Path(urdf).is_absolute():
        if ".." in Path(urdf).parts:  # above the scenario's folder: named absolute in the copy
            text = text.replace(f'"{urdf}"', f'"{(src.parent / urdf).resolve().as_posix()}"')
        else:  # a relative URDF, where the copy finds it
            (dst / urdf).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(src.parent / urdf, dst / urdf)
    (dst / src.name).write_text(text, encoding="utf-8")
    print(f"{rows} rows dropped at {at} s from every file of the record (copies in {dst}, removed at exit)")
    return str(dst / src.name)


def honesty(ratio, windows: int) -> str:
    """What the spread over ``windows`` disjoint windows can show of the reported std (module docstring).

    With an exact std ``s`` the spread of ``W`` estimates is ``s sqrt(chi2(W - 1) / (W - 1))``, so the
    ratio spread / std of a parameter is that draw: ``P(1/3 < ratio < 3)`` is the fraction an exact
    std puts within a factor 3 (89.5 % with 3 windows, 95.4 % with 4). The ratio's scale, ``sqrt(mean
    ratio^2)``, estimates how many times the spread the std is: 1 for an exact std, with the 95 %
    interval of ``sqrt(chi2(P (W - 1)) / (P (W - 1)))`` over ``P`` parameters whose errors were
    independent (they are not quite: the interval is a lower bound on its width)."""
    from scipy.stats import chi2

    dof = windows - 1

    def within(f):
        return chi2.cdf(9 * dof / f**2, dof) - chi2.cdf(dof / (9 * f**2), dof)

    scale = float(np.sqrt(np.mean(np.square(ratio))))
    lo, hi = np.sqrt(chi2.ppf([0.025, 0.975], ratio.size * dof) / (ratio.size * dof))
    return (
        f"  an exact std would put {100 * within(1.0):.1f} % within a factor 3 with {windows} windows (the "
        f"spread of {windows} estimates is itself a chi-square({dof}) draw); so would a std "
        f"{1 / 1.5:.2f} times the spread {100 * within(1.5):.1f} %, one half {100 * within(2.0):.1f} %: "
        "the count tells little\n"
        f"  scale sqrt(mean (spread / std)^2): {scale:.2f} (an exact std: 1, 95 % {lo:.2f}-{hi:.2f} for "
        f"{ratio.size} independent parameters)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(ROOT / "examples" / "tiago" / "tiago.toml"))
    ap.add_argument("--train", type=float, nargs=2, default=[9.21, 48.0])
    ap.add_argument("--test", type=float, nargs=2, default=[48.0, 67.9])
    ap.add_argument("--windows", type=int, default=3, help="disjoint windows of the excitation (default 3)")
    ap.add_argument("--lowpass", type=float, default=2.0)
    ap.add_argument(
        "--coulomb-width",
        type=coulomb_width_option,
        default="auto",
        help="as identify's: auto (default: profile on a [record] log), noise, profile or a width [rad/s], "
        "for the fit and each window",
    )
    ap.add_argument(
        "--torque-offset",
        choices=("auto", "on", "off"),
        default="auto",
        help="as identify's: a torque offset per channel (auto, the default: on for a [record] log)",
    )
    ap.add_argument(
        "--torque-sampled", action="store_true", help="torque_held = false: the efforts as samples, not held"
    )
    ap.add_argument(
        "--drop", type=float, nargs=2, metavar=("AT", "ROWS"), help="drop ROWS rows at AT s (a gap) first"
    )
    args = ap.parse_args()
    t0 = time.perf_counter()
    if args.drop:
        args.scenario = drop_rows(args.scenario, args.drop[0], int(args.drop[1]))
    arm = load_arm(args.scenario)
    _, tr = read_arm_log(args.scenario, arm, window=args.train)
    model = noise_model(arm, tr)  # as identify: the Coulomb width from the record's noise
    _, te = read_arm_log(args.scenario, arm, window=args.test)
    used = tr.used
    names = [arm.joint_names[j] for j in np.flatnonzero(used)]
    lim = arm.position_limits
    K = identifiable_subset(model, used, lim[:, 0], lim[:, 1], np.random.default_rng(0))
    T = tr.sample_period
    held = not args.torque_sampled
    rule = model  # the URDF alone: its Coulomb law as identify's default
    offset = not tr.simulator_format if args.torque_offset == "auto" else args.torque_offset == "on"
    model, free = with_width(model, tr, K, args.coulomb_width, held, offset)
    print(
        f"Coulomb width (--coulomb-width {args.coulomb_width}) [rad/s]: "
        + " / ".join(f"{v:.3g}" for v in np.broadcast_to(model.friction_velocity, (model.n,))[used])
    )
    fit = fit_log(
        model,
        tr.q,
        tr.qd,
        tr.tau,
        used,
        K,
        tau_f=filter_time_constant(T),
        sample_period=T,
        torque_held=held,
        width_estimated=free,
        pieces=tr.pieces or None,
        offset=offset,
    )
    qd_te, qdd_te = (
        piecewise(te, lambda a, b, k=k: derivatives(te.q[a:b], te.sample_period)[k]) for k in (0, 1)
    )
    qd_tr, qdd_tr = (piecewise(tr, lambda a, b, k=k: derivatives(tr.q[a:b], T)[k]) for k in (0, 1))
    plain = plain_least_squares(arm, tr.q, qd_tr, qdd_tr, tr.tau, used)
    preds = {
        "adaptive_dd WLS (identify)": predict_torque(model, fit.sigma, te.q, qd_te, qdd_te)
        + (0.0 if fit.offset is None else fit.offset),
        "plain LS (Pinocchio + fv, fc sign, Ia)": plain(te.q, qd_te, qdd_te),
        "URDF alone": predict_torque(rule, rule.sigma_ref, te.q, qd_te, qdd_te),
    }

    def lp(x):
        return piecewise(te, lambda a, b: lowpass(x[a:b], args.lowpass, te.sample_period))

    meas_lp = lp(te.tau)
    print(
        f"{args.scenario}: trained on {args.train[0]}-{args.train[1]} s, predicting "
        f"{args.test[0]}-{args.test[1]} s; channels {', '.join(names)}"
    )
    print(
        f"torque rms over the test window, low-passed {args.lowpass} Hz: {np.round(rms(meas_lp[:, used]), 2)}"
    )
    print(
        f"{'model':<40} {'low-passed ' + str(args.lowpass) + ' Hz: per joint':<36} {'pooled':>7}"
        "   unfiltered pooled"
    )
    for label, th in preds.items():
        e_lp = meas_lp[:, used] - lp(th)[:, used]
        e = te.tau[:, used] - th[:, used]
        per = " / ".join(f"{x:.5f}" for x in rms(e_lp))
        print(f"{label:<40} {per:<36} {np.sqrt(np.mean(e_lp**2)):7.3f}   {np.sqrt(np.mean(e**2)):.3f}")
    # the bounds against disjoint windows
    _, whole = read_arm_log(args.scenario, arm)
    edges = np.linspace(whole.t[0], whole.t[-1], args.windows + 1)
    est, std, shares, widths = [], [], [], []
    for a, b in itertools.pairwise(edges):
        _, w = read_arm_log(args.scenario, arm, window=(a, b))
        wm, wfree = with_width(noise_model(arm, w), w, K, args.coulomb_width, held, offset)
        f = fit_log(
            wm,
            w.q,
            w.qd,
            w.tau,
            used,
            K,
            tau_f=filter_time_constant(w.sample_period),
            sample_period=w.sample_period,
            torque_held=held,
            width_estimated=wfree,
            pieces=w.pieces or None,
            offset=offset,
        )
        widths.append(np.broadcast_to(wm.friction_velocity, (wm.n,))[used])
        est.append(f.sigma[K])
        std.append(f.std[K])
        shares.append(f.held.share[K] if f.held is not None else np.zeros(K.sum()))
    # a parameter mostly held at the URDF's value (identify's 'held': over half its variance the
    # prior's) in some window is not an estimate: its spread says nothing of its reported std
    est_k = np.max(np.array(shares), axis=0) <= 0.5
    spread = np.std(np.array(est), axis=0, ddof=1)[est_k]
    reported = np.sqrt(np.mean(np.array(std) ** 2, axis=0))[est_k]
    ratio = spread / reported
    q1, med, q3 = np.percentile(ratio, [25, 50, 75])
    inside = np.mean((ratio > 1 / 3) & (ratio < 3))
    print(
        f"bounds vs {args.windows} disjoint windows of {edges[1] - edges[0]:.1f} s ({est_k.sum()} of "
        f"{K.sum()} identified base parameters; {(~est_k).sum()} mostly held in some window left out): "
        f"spread / reported std median {med:.2f} (quartiles {q1:.2f}-{q3:.2f}, "
        f"min {ratio.min():.2f}, max "
        f"{ratio.max():.2f}); within a factor 3: {100 * inside:.0f} %"
    )
    print(honesty(ratio, args.windows))
    if free is not None:
        print(
            "  Coulomb widths per window [rad/s]: "
            + "; ".join(" / ".join(f"{v:.2g}" for v in wd) for wd in widths)
        )
    worst = np.argsort(-np.abs(np.log(ratio)))[:3]
    names_k = [nm for nm, k in zip(model.names, K, strict=True) if k]
    names_k = [nm for nm, e in zip(names_k, est_k, strict=True) if e]
    print("  farthest from 1: " + "; ".join(f"{names_k[i][:40]} {ratio[i]:.2f}" for i in worst))
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
