"""Where a segment's excess over the floor comes from: adaptive_ct's squared tracking error in
windows after the swap that starts the segment, its share of the segment's sum, and the RMS
ratio to ct_oracle in each window (median over seeds); the segment's ratio without its first 50
ms and 0.5 s; the saturated fraction of both; the median detection delay.

    python studies/swap_transient.py SCENARIO.toml SEGMENT [--seeds 20]
"""

from __future__ import annotations

import argparse
import copy
import itertools
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml
from adaptive_dd.closed_loop.runner import run_closed_loop
from adaptive_dd.closed_loop.types import run_constants

EDGES = (0.0, 0.005, 0.010, 0.015, 0.020, 0.030, 0.050, 0.1, 0.2, 0.5)
"""[s] after the swap: the windows' edges (the last window runs to the segment's end)."""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenario")
    ap.add_argument("segment", type=int, help="segment index (1: the one after the first swap)")
    ap.add_argument("--seeds", type=int, default=20)
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    res = run_closed_loop(sc, seed_indices=tuple(range(a.seeds)), keep_trajectories=0)
    T, rc, g = sc.sample_period, run_constants(sc), a.segment
    k0, k1 = int(rc.seg_start[g]), int(rc.seg_end[g])
    ea = res.runs["adaptive_ct"].e_norm[:, k0:k1].astype(float) ** 2
    eo = res.runs["ct_oracle"].e_norm[:, k0:k1].astype(float) ** 2
    whole = np.mean(np.sqrt(ea.mean(1) / eo.mean(1)))
    print(f"{a.scenario}, segment {g} ({k0 * T:g}-{k1 * T:g} s), {a.seeds} seeds: ratio mean {whole:.3f}")
    print("after the swap [ms]   share of adaptive_ct's sum of |e|^2 (mean)   RMS ratio (median)")
    total = ea.sum(1)
    edges = (*EDGES, (k1 - k0) * T)
    for lo, hi in itertools.pairwise(edges):
        i, j = round(lo / T), round(hi / T)
        share = np.mean(ea[:, i:j].sum(1) / total)
        r = np.median(np.sqrt(ea[:, i:j].mean(1) / eo[:, i:j].mean(1)))
        print(f"  {1e3 * lo:6.0f} - {1e3 * hi:6.0f}   {share:.3f}   {r:.2f}")
    for cut in (0.05, 0.5):
        i = round(cut / T)
        r = np.mean(np.sqrt(ea[:, i:].mean(1) / eo[:, i:].mean(1)))
        print(f"ratio without the segment's first {1e3 * cut:g} ms: mean {r:.3f}")
    n = float(k1 - k0)
    sat = {nm: res.runs[nm].acc.n_saturated[:, g] / n for nm in ("adaptive_ct", "ct_oracle")}
    print(
        "samples with a saturated joint in the segment: "
        + ", ".join(f"{nm} mean {100 * v.mean():.3f} % (max {100 * v.max():.3f} %)" for nm, v in sat.items())
    )
    swap = sc.swap_times[g - 1]
    delays = [
        min((x - swap for x in at if 0 <= x - swap < FALSE_ALARM_WINDOW), default=np.nan)
        for at in res.runs["adaptive_ct"].alarm_times
    ]
    print(f"detection delay: median {1e3 * np.nanmedian(delays):.0f} ms")


if __name__ == "__main__":
    main()
