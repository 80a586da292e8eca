"""A law's moving RMS error against its floor's, window by window, in one segment: what the
leaderboard's recovery time (``adaptive_dd.benchmark.time_to_floor``) reads.

Usage::

    python benchmarks/recovery_windows.py [SCENARIO] [--controller adaptive_ct] [--segment -1]
                                          [--seeds 10] [--window 0.25]

Runs the controller and its floor on ``SCENARIO`` (default ``benchmarks/scenarios/gen3_drawn.toml``)
and prints, per seed, the segment's RMS ratio, the recovery time and the ratio of the two causal
moving RMS errors at the end of each ``--window``; then, over the seeds, the mean of the windows'
ratios in the segment's first and second half. A ratio that drifts up through the segment is the
law's own; one that scatters about 1 is the sensors' noise. Asserts nothing.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from adaptive_dd.benchmark import load_scenario, run_benchmark
from adaptive_dd.benchmark.preflight import missing_floors
from adaptive_dd.benchmark.segments import moving_rms
from adaptive_dd.benchmark.time_to_floor import LEVEL, time_to_floor


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario", nargs="?", default="benchmarks/scenarios/gen3_drawn.toml")
    ap.add_argument("--controller", default="adaptive_ct")
    ap.add_argument("--segment", type=int, default=-1, help="segment index (default the last)")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--window", type=float, default=0.25, help="[s] the moving RMS's window")
    args = ap.parse_args()
    sc = load_scenario(args.scenario).with_controllers((args.controller,))
    add, _ = missing_floors(sc)
    if not add:
        raise SystemExit(f"{args.controller} has no floor that runs in {args.scenario}")
    floor = next(iter(add))
    sc = dataclasses.replace(sc.with_controllers((floor, args.controller)), seeds=args.seeds)
    res = run_benchmark(sc, progress=False)
    T = sc.sample_period
    a, b, mass = sc.segments()[args.segment]
    i0, i1 = round(a / T), round(b / T)
    e = res.runs[args.controller].e_norm[:, i0:i1].astype(float)
    f = res.runs[floor].e_norm[:, i0:i1].astype(float)
    n = max(1, round(args.window / T))
    ratio = moving_rms(e, n) / moving_rms(f, n)
    ends = np.arange(n - 1, e.shape[1], n)
    rec = time_to_floor(e, f, T, args.window, LEVEL)
    print(
        f"{args.scenario}: {args.controller} / {floor}, segment {a:g}-{b:g} s ({mass:g} kg), "
        f"{args.seeds} seeds"
    )
    print(
        f"moving RMS ratio at the end of each {args.window:g} s window (recovery: within {LEVEL}x to the end)"
    )
    for s in range(e.shape[0]):
        whole = np.sqrt(np.mean(e[s] ** 2) / np.mean(f[s] ** 2))
        t = "never" if np.isinf(rec[s]) else f"{rec[s]:.2f} s"
        print(
            f"  seed {s}: segment {whole:.3f}, recovery {t:>7}; "
            + " ".join(f"{x:.2f}" for x in ratio[s, ends])
        )
    half = ends.size // 2
    print(
        f"mean of the windows' ratios over the seeds: first half {ratio[:, ends[:half]].mean():.3f}, "
        f"second half {ratio[:, ends[half:]].mean():.3f}"
    )


if __name__ == "__main__":
    main()
