"""Per-segment ratio to the floor (mean, p90, max over seeds) and settled RMS error from a
benchmark's ``per_seed.csv``, optionally over the first ``--seeds`` seeds only (the seeds of a
shorter run: trial i draws from ``[seed, i]`` whatever the number of seeds).

    python benchmarks/ratio_table.py OUT/per_seed.csv [--controller adaptive_ct] [--seeds 20]
"""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("--controller", default="adaptive_ct")
    ap.add_argument("--seeds", type=int, default=None)
    a = ap.parse_args()
    df = pd.read_csv(a.csv)
    if a.seeds is not None:
        df = df[df.seed < a.seeds]
    c = df[df.controller == a.controller]
    floor = df[df.controller == c.floor.iloc[0]]
    print(f"{a.csv}: {a.controller}, {c.seed.nunique()} seeds")
    print("segment  mass   ratio mean    p90    max   settled RMS [mrad] ctrl / floor   false alarms")
    for g, s in c.groupby("segment"):
        r = s.ratio_to_floor.to_numpy()
        f = floor[floor.segment == g]
        print(
            f"{g:7d} {s.mass_kg.iloc[0]:5.1f} {r.mean():11.3f} {np.percentile(r, 90):6.3f} {r.max():6.2f}"
            f"   {1e3 * s.rms_error_settled_rad.mean():8.3f} / {1e3 * f.rms_error_settled_rad.mean():.3f}"
            f"   {int(np.nansum(s.false_alarms.to_numpy(dtype=float)))}"
        )


if __name__ == "__main__":
    main()
