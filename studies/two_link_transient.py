"""Where a two-link segment's excess over the floor comes from: adaptive_ct's squared tracking
error in windows after the swap that starts the segment, its share of the segment's sum and the
RMS ratio to ct_oracle in each window (median over seeds); the share before adaptive_ct's alarm
and in the 50 ms after it; the segment's ratio without its first 50 ms, 0.2 s and 0.5 s. The
closed-form two-link path (``run_benchmark``; ``studies/swap_transient.py`` is the N-joint form).

    python studies/two_link_transient.py [SCENARIO.toml] [--segment 1] [--seeds 20] [--set KEY=VALUE ...]

``--set`` puts ``KEY = VALUE`` (TOML) in ``[controllers.adaptive_ct]``, e.g. ``--set observer=false``.
"""

from __future__ import annotations

import argparse
import copy
import itertools
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np

from adaptive_dd.benchmark.metrics import FALSE_ALARM_WINDOW
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import parse_scenario, read_toml

EDGES = (0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.075, 0.1, 0.2, 0.3, 0.5, 1.0)
"""[s] after the swap: the windows' edges (the last window runs to the segment's end)."""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument(
        "scenario", nargs="?", default=str(resources.files("adaptive_dd.scenarios") / "payload_swap.toml")
    )
    ap.add_argument("--segment", type=int, default=1, help="segment index (1: the one after the first swap)")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    d = copy.deepcopy(read_toml(Path(a.scenario)))
    d["run"]["controllers"] = ["ct_oracle", "adaptive_ct"]
    table = d.setdefault("controllers", {}).setdefault("adaptive_ct", {})
    for kv in a.set:
        table.update(tomllib.loads(kv))
    sc = parse_scenario(d, a.scenario, Path(a.scenario).stem)
    res = run_benchmark(sc, progress=False, keep_trajectories=0, seed_indices=tuple(range(a.seeds)))
    T, g = sc.sample_period, a.segment
    bounds = (0.0, *sc.swap_times, sc.duration)
    k0, k1 = round(bounds[g] / T), round(bounds[g + 1] / T)
    ea = res.runs["adaptive_ct"].e_norm[:, k0:k1].astype(float) ** 2
    eo = res.runs["ct_oracle"].e_norm[:, k0:k1].astype(float) ** 2
    whole = np.sqrt(ea.mean(1) / eo.mean(1))
    span = f"{bounds[g]:g}-{bounds[g + 1]:g} s"
    print(f"{a.scenario}, segment {g} ({span}), {a.seeds} seeds, {a.set}: ratio mean {whole.mean():.3f}")
    print("after the swap [ms]   share of adaptive_ct's sum of |e|^2 (mean)   RMS ratio (median)")
    total = ea.sum(1)
    for lo, hi in itertools.pairwise((*EDGES, (k1 - k0) * T)):
        i, j = round(lo / T), round(hi / T)
        share = np.mean(ea[:, i:j].sum(1) / total)
        r = np.median(np.sqrt(ea[:, i:j].mean(1) / eo[:, i:j].mean(1)))
        print(f"  {1e3 * lo:6.0f} - {1e3 * hi:6.0f}   {share:.3f}   {r:.2f}")
    swap = bounds[g]
    delays = [min((x - swap for x in at if 0 <= x - swap < FALSE_ALARM_WINDOW), default=np.nan)
              for at in res.runs["adaptive_ct"].alarm_times]  # fmt: skip
    pre = [ea[i, : round(dl / T)].sum() / total[i] for i, dl in enumerate(delays) if np.isfinite(dl)]
    post = [
        ea[i, round(dl / T) : round(dl / T) + 50].sum() / total[i]
        for i, dl in enumerate(delays)
        if np.isfinite(dl)
    ]
    print(f"detection delay: median {1e3 * np.nanmedian(delays):.0f} ms; share of the segment's sum "
          f"before the alarm {np.mean(pre):.3f}, in the 50 ms after it {np.mean(post):.3f}")  # fmt: skip
    for cut in (0.05, 0.2, 0.5):
        i = round(cut / T)
        rest = np.mean(np.sqrt(ea[:, i:].mean(1) / eo[:, i:].mean(1)))
        print(f"ratio without the segment's first {1e3 * cut:g} ms: mean {rest:.3f}")


if __name__ == "__main__":
    main()
