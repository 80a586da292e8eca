"""A logger that drops rows one at a time: what reading the log as it comes keeps.

Usage::

    python benchmarks/log_drops.py [--rate 0.01] [--seeds 5] [--velocity derived|measured] [--period 0.005]
    python benchmarks/log_drops.py --closed-loop --velocity measured   # the record `simulate --arm` writes

Per seed, a 24 s record of the ``vertical3`` arm at 200 Hz (``--period`` [s])
(:func:`adaptive_dd.identification.records.synthetic_log`) is written whole and with each row
dropped with probability ``--rate``, read back (:func:`adaptive_dd.record.read_log`: gaps of one
missed sample bridged, longer ones split) and fitted (:func:`adaptive_dd.identification.log_fit.fit_log`).
Prints the samples kept, the median std of the fit with drops over the whole log's, and the RMS
over the parameters of (with drops - whole) / std. Asserts nothing.

With ``--closed-loop`` the record is instead the one ``adaptive-dd simulate --arm
benchmarks/scenarios/ident_vertical3.toml --duration 24 --seed SEED`` writes (computed torque
tracking the scenario's reference, sensor noise and quantisation; ``--period`` its sample period):
its torque carries the feedback's noise from one sample to the next, so the torque of a missed
sample, which the bridge interpolates, is not the one applied.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.io import write_recording
from adaptive_dd.plant.arm import Arm
from adaptive_dd.record import read_log, record_spec
from adaptive_dd.robots import robot_urdf

T = 0.005


def _closed_loop(arm, seed: int, period: float):
    """The record ``simulate --arm ident_vertical3.toml --duration 24 --seed SEED`` writes."""
    from types import SimpleNamespace

    from adaptive_dd.benchmark.scenario import load_scenario
    from adaptive_dd.experiments import trial_rngs
    from adaptive_dd.identification.records import simulate_record

    sc = load_scenario(Path(__file__).parent / "scenarios" / "ident_vertical3.toml")
    rec = simulate_record(arm, sc.reference, 24.0, trial_rngs(seed, 1), sample_period=period)
    return SimpleNamespace(t=rec.t, q=rec.q[0], qd=rec.qd[0], tau=rec.tau[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=0.01, help="probability that a row is dropped")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--velocity", choices=("derived", "measured"), default="derived")
    ap.add_argument("--period", type=float, default=T, help="sample period of the log [s]")
    ap.add_argument("--closed-loop", action="store_true", help="the record `simulate --arm` writes")
    args = ap.parse_args()
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    model = arm_model(arm)
    folder = Path(tempfile.mkdtemp())
    for seed in range(args.seeds):
        log = _closed_loop(arm, seed, args.period) if args.closed_loop else None
        log = log or synthetic_log(arm, 24.0, args.period, np.random.default_rng(seed))
        drop = np.flatnonzero(np.random.default_rng(100 + seed).random(log.t.size) < args.rate)
        drop = drop[(drop > 0) & (drop < log.t.size - 1)]
        out = {}
        for label, rows in (("whole", []), ("drops", drop)):
            keep = np.setdiff1d(np.arange(log.t.size), rows)
            path = write_recording(
                folder / f"{label}{seed}.csv", log.t[keep], log.q[keep], log.qd[keep], log.tau[keep]
            )
            spec = record_spec(
                {"files": [str(path)], "velocity_source": args.velocity}
                | ({"velocity": "qd{i}"} if args.velocity == "measured" else {}),
                arm.joint_names,
                arm.joint_kinds,
                str(folder / "s.toml"),
            )
            rec = read_log(spec)
            fit = fit_log(
                model, rec.q, rec.qd, rec.tau, rec.used, np.ones(model.p, bool), tau_f=0.02,
                sample_period=rec.sample_period, channel_weight=rec.weight, torque_held=False,
                pieces=rec.pieces or None,
            )  # fmt: skip
            out[label] = (rec, fit)
        (r0, f0), (r1, f1) = out["whole"], out["drops"]
        pieces = len(r1.pieces) or 1
        print(
            f"seed {seed}: {drop.size} rows dropped, {pieces} piece(s), samples kept {r1.t.size}/{r0.t.size} "
            f"= {r1.t.size / r0.t.size:.3f}, median std / whole log's {np.median(f1.std / f0.std):.3f}, "
            f"rms (drops - whole) / std {np.sqrt(np.mean(((f1.sigma - f0.sigma) / f0.std) ** 2)):.2f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
