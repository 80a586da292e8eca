"""Trace one trial of a drawn arm: where in time adaptive_ct's tracking error exceeds its floor's.

Runs ``benchmarks/scenarios/population.toml`` on ``random:ARM`` (as ``benchmark --arms`` does) and
prints, per 0.5 s window of trial ``SEED``, the RMS and peak error norms of ``adaptive_ct`` and
``ct_oracle``, adaptive_ct's saturated fraction, its alarm times, and how far its estimate is from
the true base parameters (and the payload mass its control model carries) at a few instants of the
first segment, and the payload mass and inertia its control model carries against the truth after
the first swap.

Run: ``PYTHONPATH=. python benchmarks/trace_random_arm.py ARM SEED [--prior-noise X]`` (``X``:
adaptive_ct's ``OnlineConfig.prior_noise``; 0 weighs the compact payload prior against the
estimator's covariance as it is).
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("arm", type=int, help="the arm's seed (random:ARM)")
    ap.add_argument("seed", type=int, help="the trial's seed index")
    ap.add_argument("--window", type=float, default=0.5, help="s per line")
    ap.add_argument(
        "--prior-noise", type=float, default=None, help="adaptive_ct's prior_noise (default: its own)"
    )
    args = ap.parse_args()
    sc = population_scenario(read_toml(TEMPLATE), str(TEMPLATE), args.arm)
    sc = dataclasses.replace(sc, seeds=args.seed + 1, controllers=("ct_oracle", "adaptive_ct"))
    if args.prior_noise is not None:
        sc = with_settings(sc, "adaptive_ct", {"estimator": {"prior_noise": args.prior_noise}})
    res = run_benchmark(sc, progress=False, keep_trajectories=args.seed + 1)
    t = res.t
    a, o = res.runs["adaptive_ct"], res.runs["ct_oracle"]
    ea, eo = a.e_norm[args.seed].astype(float), o.e_norm[args.seed].astype(float)
    print(f"random:{args.arm} seed {args.seed}: swaps {sc.swap_times} s of {sc.swap_masses} kg")
    print("adaptive_ct alarms [s]:", [round(float(x), 3) for x in (a.alarm_times or [[]])[args.seed]])
    for lo in np.arange(0.0, sc.duration, args.window):
        m = (t >= lo) & (t < lo + args.window)
        ra, ro = np.sqrt(np.mean(ea[m] ** 2)), np.sqrt(np.mean(eo[m] ** 2))
        sat = a.saturated[args.seed][m].mean() if a.saturated is not None else float("nan")
        print(
            f"{lo:5.1f}-{lo + args.window:4.1f} s: adaptive_ct {1e3 * ra:.4f} mrad, ct_oracle {1e3 * ro:.4f} "
            f"mrad, ratio {ra / ro:.2f}, peaks {1e3 * ea[m].max():.3f} / {1e3 * eo[m].max():.3f} mrad, "
            f"saturated {sat:.3f}"
        )
    if a.sigma_hat is not None:
        sh = np.asarray(a.sigma_hat)[args.seed]
        d = sh - res.sigma_true
        mass = sc.arm.payload_from_sigma(sh).params[:, 0]  # the control model's payload mass
        for at in (0.1, 0.15, 0.2, 0.25, 0.5, 1.0, 2.0, 3.0):
            k = int(np.searchsorted(t, at))
            j = int(np.abs(d[k]).argmax())
            print(
                f"t = {at} s: largest |sigma_hat - sigma_true| {abs(d[k, j]):.3g} (base parameter {j}); "
                f"the control model's payload mass {mass[k]:.4f} kg"
            )
        # the payload's mass and inertia about its frame (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) in the model
        # control uses, against the truth, after the first swap
        pay_hat = sc.arm.payload_from_sigma(sh).params
        pay_true = sc.arm.payload_from_sigma(np.broadcast_to(res.sigma_true, sh.shape)).params
        t0 = sc.swap_times[0] if sc.swap_times else 0.0
        for dt in (0.05, 0.1, 0.5, 1.0, 2.0, 3.0):
            k = int(np.searchsorted(t, t0 + dt))
            if k < len(t):
                print(
                    f"t = {t0 + dt:.2f} s: the control model's payload mass {pay_hat[k, 0]:.4f} kg "
                    f"(true {pay_true[k, 0]:.4f}), inertia "
                    f"{np.array2string(pay_hat[k, 4:], precision=4, suppress_small=True)} kg m^2, "
                    f"true {np.array2string(pay_true[k, 4:], precision=4, suppress_small=True)}"
                )


if __name__ == "__main__":
    main()
