"""What `identify --arm` writes on simulated records, against the truth: output error's estimate
(written when it converges with its noise model) beside the weighted least squares' (written with
`--output-error off`), over seeds.

    python benchmarks/output_error_coverage.py                 # vertical3, seeds 1..12
    python benchmarks/output_error_coverage.py --seeds 4 --scenario benchmarks/scenarios/ident_ur5.toml

For each seed: `adaptive-dd simulate --arm SCENARIO --seed S` (its trajectory.npz holds the true
base parameters), then `adaptive-dd identify --arm SCENARIO` twice (as written, and with
`--output-error off`), each one's `estimates.csv` read. Prints, over the identified parameters of
every seed: how often `|estimate - truth| <= half_width_95` (the written 95 % bound), the rms of
`(estimate - truth) / std`, the ratio of the two estimates' rms errors, each seed's coverage, and the
three parameters least often covered over the seeds with their mean z (a bias the pooled figure hides).
Asserts nothing.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parent.parent


def _run(*args: str) -> None:
    p = subprocess.run([sys.executable, "-m", "adaptive_dd.cli", *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"adaptive-dd {' '.join(args)} failed ({p.returncode}):\n{p.stderr[-2000:]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(ROOT / "benchmarks" / "scenarios" / "ident_vertical3.toml"))
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--first", type=int, default=1)
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for s in range(args.first, args.first + args.seeds):
            out = Path(tmp) / f"s{s}"
            _run("simulate", "--arm", args.scenario, "--seed", str(s), "--out", str(out))
            truth = np.load(out / "trajectory.npz")["sigma_true"]
            for how, extra in (("written", ()), ("wls", ("--output-error", "off"))):
                _run(
                    "identify",
                    "--arm",
                    args.scenario,
                    str(out / "trajectory.csv"),
                    "--out",
                    str(out / how),
                    *extra,
                )
                e = pd.read_csv(out / how / "estimates.csv")
                e["truth"], e["seed"], e["how"] = truth, s, how
                rows.append(e[e["identified"] == 1])
            print(f"seed {s} done", file=sys.stderr, flush=True)
    d = pd.concat(rows)
    d["inside"] = (d["estimate"] - d["truth"]).abs() <= d["half_width_95"]
    d["z"] = (d["estimate"] - d["truth"]) / d["std"]
    print(f"{args.scenario}: seeds {args.first}..{args.first + args.seeds - 1}")
    for how, g in d.groupby("how", sort=False):
        label = (
            "written (output error where it converged)" if how == "written" else "WLS (--output-error off)"
        )
        per = g.groupby("seed")["inside"].mean().round(2).tolist()
        print(
            f"  {label}: truth within the 95 % bound {g['inside'].mean():.3f} of {len(g)}, rms z "
            f"{np.sqrt(np.mean(g['z'] ** 2)):.3f}; per seed {per}"
        )
        # the tail: the parameters least often covered over the seeds, with their mean z (a bias)
        by = g.groupby("name").agg(inside=("inside", "mean"), z=("z", "mean")).sort_values("inside")
        worst = ", ".join(f"{n} {r.inside:.2f} (mean z {r.z:+.2f})" for n, r in by.head(3).iterrows())
        print(f"    least covered parameters over the seeds: {worst}")
    w, o = (d[d["how"] == h].set_index(["seed", "name"]) for h in ("wls", "written"))
    ratio = np.sqrt(((o["estimate"] - o["truth"]) ** 2).sum() / ((w["estimate"] - w["truth"]) ** 2).sum())
    print(f"  rms error, written / WLS: {ratio:.3f}")


if __name__ == "__main__":
    main()
