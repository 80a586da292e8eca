"""How much of a drawn arm's loss after a swap the sensors' noise makes: adaptive_ct / ct_oracle per
segment, and the payload adaptive_ct's control model carries against the truth, with the stated
position and velocity noise scaled.

Runs ``benchmarks/scenarios/population.toml`` (or ``--template FILE``) on ``random:ARM`` for each
ARM given (as ``benchmark --arms`` does; ``ct_oracle`` and ``adaptive_ct``), with the scenario's
``[noise]`` variances times ``--position-noise`` and ``--velocity-noise`` (1: as stated; both the
run's draws and what the arm states to the controllers), and ``adaptive_ct``'s estimator settings
``--set KEY=VALUE`` (e.g. ``prior_noise=40``). Prints per arm the segments' mean ratio, pooled over
the arms and seeds their mean / p90 / max, the model's payload inertia about the payload frame
against the truth at the end of each loaded segment (the ratio of the traces, mean over the
seeds; pooled: mean and range), the alarms more than 0.5 s after every swap (false
alarms) and the swaps with no alarm within 0.5 s (missed), and with ``--at T [T ...]`` the control
model's payload (mass, first moments, inertia about the payload frame) at those instants of seed 0
against the truth. Asserts nothing.

Run: ``PYTHONPATH=. python benchmarks/sensor_noise_split.py ARM [ARM ...] [--first-arm K --arms N]
[--seeds 3] [--velocity-noise 0.01] [--position-noise 1] [--set prior_noise=40] [--at 4.25 7]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.population import population_scenario
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import _with_stated_noise, read_toml
from adaptive_dd.benchmark.scenario_settings import with_settings

TEMPLATE = Path(__file__).resolve().parent / "scenarios" / "population.toml"


def _scenario(template: Path, arm: int, seeds: int, fp: float, fv: float, est: dict):
    sc = population_scenario(read_toml(template), str(template), arm)
    pv = tuple(fp * x for x in sc.position_variance)
    vv = tuple(fv * x for x in sc.velocity_variance)
    sc = dataclasses.replace(
        sc,
        seeds=seeds,
        controllers=("ct_oracle", "adaptive_ct"),
        position_variance=pv,
        velocity_variance=vv,
        arm=_with_stated_noise(sc.arm, pv, vv),
    )
    return with_settings(sc, "adaptive_ct", {"estimator": est}) if est else sc


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False)
    ap.add_argument("arm", type=int, nargs="*", help="the arms' seeds (random:ARM)")
    ap.add_argument("--first-arm", type=int, default=None)
    ap.add_argument("--arms", type=int, default=None)
    ap.add_argument("--template", type=Path, default=TEMPLATE)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--position-noise", type=float, default=1.0, help="x the stated variance")
    ap.add_argument("--velocity-noise", type=float, default=1.0, help="x the stated variance")
    ap.add_argument("--set", action="append", default=[], help="adaptive_ct estimator KEY=VALUE")
    ap.add_argument("--at", type=float, nargs="*", default=[], help="instants [s] of the payload print")
    args = ap.parse_args()
    arms = list(args.arm)
    if args.arms is not None:
        arms += list(range(args.first_arm or 0, (args.first_arm or 0) + args.arms))
    if not arms:
        ap.error("give arms' seeds or --arms N")
    est = {k: float(v) for k, v in (s.split("=", 1) for s in args.set)}
    ratios, false, missed, traces = [], 0, 0, []
    for arm in arms:
        sc = _scenario(args.template, arm, args.seeds, args.position_noise, args.velocity_noise, est)
        res = run_benchmark(sc, progress=False, keep_trajectories=args.seeds)
        t, a, o = res.t, res.runs["adaptive_ct"], res.runs["ct_oracle"]
        edges = [0.0, *sc.swap_times, sc.duration]
        rows = []
        for s in range(args.seeds):
            ea, eo = a.e_norm[s].astype(float), o.e_norm[s].astype(float)
            m = [(t >= t0) & (t < t1) for t0, t1 in itertools.pairwise(edges)]
            rows.append([np.sqrt(np.sum(ea[k] ** 2) / np.sum(eo[k] ** 2)) for k in m])
            al = [float(x) for x in (a.alarm_times or [[]] * args.seeds)[s]]
            false += sum(1 for x in al if not any(0.0 <= x - w < 0.5 for w in sc.swap_times))
            missed += sum(1 for w in sc.swap_times if not any(0.0 <= x - w < 0.5 for x in al))
        ratios += rows
        sh_all = np.asarray(a.sigma_hat)
        tr = []
        for s in range(args.seeds):
            ph = sc.arm.payload_from_sigma(sh_all[s]).params
            pt = sc.arm.payload_from_sigma(np.broadcast_to(res.sigma_true, sh_all[s].shape)).params
            row = []
            for t1, mass in zip(edges[2:], sc.swap_masses, strict=True):
                k = int(np.searchsorted(t, t1)) - 2  # the segment's last sample
                if mass > 0.0:
                    row.append((ph[k, 4] + ph[k, 6] + ph[k, 9]) / (pt[k, 4] + pt[k, 6] + pt[k, 9]))
            tr.append(row)
        traces += tr
        print(
            f"random:{arm}: per segment mean {np.round(np.mean(rows, axis=0), 3).tolist()}; the model's "
            f"inertia trace / the truth's at the end of each loaded segment "
            f"{np.round(np.mean(tr, axis=0), 3).tolist()}",
            flush=True,
        )
        if args.at:
            sh = np.asarray(a.sigma_hat)[0]
            ph = sc.arm.payload_from_sigma(sh).params
            pt = sc.arm.payload_from_sigma(np.broadcast_to(res.sigma_true, sh.shape)).params
            for x in args.at:
                k = min(int(np.searchsorted(t, x)), len(t) - 1)
                print(
                    f"  seed 0, t = {x:g} s: mass {ph[k, 0]:.3f} kg (true {pt[k, 0]:.3f}), first moments "
                    f"{np.round(ph[k, 1:4], 3)} (true {np.round(pt[k, 1:4], 3)}) kg m, inertia "
                    f"{np.round(ph[k, 4:], 4)} (true {np.round(pt[k, 4:], 4)}) kg m^2"
                )
    r = np.asarray(ratios)
    print(
        f"{len(r)} trials: mean {np.round(r.mean(axis=0), 3).tolist()}, p90 "
        f"{np.round(np.quantile(r, 0.9, axis=0), 3).tolist()}, max {np.round(r.max(axis=0), 3).tolist()}; "
        f"false alarms {false}, missed swaps {missed}"
    )
    tr = np.asarray(traces)
    print(
        f"inertia trace / the truth's at the end of each loaded segment: mean "
        f"{np.round(tr.mean(axis=0), 3).tolist()}, min {np.round(tr.min(axis=0), 3).tolist()}, max "
        f"{np.round(tr.max(axis=0), 3).tolist()}"
    )


if __name__ == "__main__":
    main()
