"""Draw ``docs/shipped_ratios.png``: adaptive_ct against its floor on every shipped N-joint scenario.

Runs ``adaptive-dd benchmark FILE --seeds N --controllers ct_nominal adaptive_ct --out
OUT/NAME`` for each scenario of the table "Every shipped scenario" on the results page (a run
whose ``per_seed.csv`` is already in ``OUT/NAME`` is not run again), then draws, per scenario, the
per-seed ratio of ``adaptive_ct``'s RMS tracking error to ``ct_oracle``'s in each payload segment:
every seed a dot, the mean with its 95 % interval a bar. From the repository's root::

    python docs/figures/shipped_ratios.py --seeds 50

prints, per scenario and segment, the mean ratio and its interval, and writes the figure.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = {
    "UR5, drawn": "adaptive_dd/scenarios/ur5_tool_swap.toml",
    "UR5, exact": "adaptive_dd/scenarios/ur5_tool_swap_exact.toml",
    "Panda, drawn": "adaptive_dd/scenarios/panda_payload.toml",
    "iiwa 14, drawn": "adaptive_dd/scenarios/iiwa14_payload.toml",
    "vertical3, drawn": "adaptive_dd/scenarios/vertical3_payload.toml",
    "vertical3, exact": "adaptive_dd/scenarios/vertical3_payload_exact.toml",
    "the paper's arm, drawn": "benchmarks/scenarios/sice_drawn.toml",
}


def run(file: str, seeds: int, out: Path) -> pd.DataFrame:
    """The ``per_seed.csv`` of one scenario's run (run now unless ``out`` holds it)."""
    table = out / "per_seed.csv"
    if not table.is_file():
        cmd = [sys.executable, "-m", "adaptive_dd.cli", "benchmark", file, "--seeds", str(seeds),
               "--controllers", "ct_nominal", "adaptive_ct", "--out", str(out), "--no-progress"]  # fmt: skip
        env = os.environ | {"PYTHONPATH": str(ROOT)}
        subprocess.run(cmd, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
    return pd.read_csv(table)


def draw(frames: dict[str, pd.DataFrame], path: Path) -> None:
    """One panel per scenario: adaptive_ct's per-seed ratio to the floor per payload segment."""
    fig, axes = plt.subplots(2, 4, figsize=(13, 6.2), sharey=True)
    for ax, (label, df) in zip(axes.flat, frames.items(), strict=False):
        sub = df[df["controller"] == "adaptive_ct"]
        segs = sub.drop_duplicates("segment").sort_values("segment")
        for x, seg in enumerate(segs["segment"]):
            r = sub.loc[sub["segment"] == seg, "ratio_to_floor"].to_numpy(dtype=float)
            r = r[np.isfinite(r)]
            jitter = np.random.default_rng(seg).uniform(-0.15, 0.15, r.size)
            ax.plot(x + jitter, r, ".", color="tab:blue", ms=3, alpha=0.5)
            mean, half = r.mean(), 1.96 * r.std(ddof=1) / np.sqrt(r.size)
            ax.errorbar(x, mean, yerr=half, fmt="_", ms=18, mew=2, capsize=4, color="k")
            print(
                f"{label:24s} segment {seg}: mean {mean:.3f} "
                f"(95 % interval {mean - half:.3f}-{mean + half:.3f})"
            )
        ax.axhline(1.0, color="k", lw=0.6)
        ax.axhline(1.1, color="tab:red", lw=0.6, ls="--")
        ax.set_yscale("log")
        labels = [f"{a:g}-{b:g} s\n{m:g} kg" for a, b, m in segs[["start_s", "end_s", "mass_kg"]].to_numpy()]
        ax.set_xticks(range(len(labels)), labels, fontsize=7)
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3, which="both", axis="y")
    for ax in axes[:, 0]:
        ax.set_ylabel("adaptive_ct / ct_oracle RMS error [-]")
    for ax in axes[-1]:
        ax.set_xlabel("payload segment [s, kg]")
    axes.flat[-1].axis("off")
    axes.flat[-1].text(
        0.0, 0.5,
        "dots: one seed each\nblack bar: mean with its 95 % interval\n"
        "black line: the floor (ratio 1)\nred dashed: the target mean 1.1",
        transform=axes.flat[-1].transAxes, fontsize=9,
    )  # fmt: skip
    fig.suptitle(
        "Ratio of adaptive_ct's RMS tracking error to ct_oracle's, per seed and payload segment "
        "[-], on every shipped N-joint scenario (log scale)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path.relative_to(ROOT)}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "shipped_ratios")
    ap.add_argument("--figure", type=Path, default=ROOT / "docs" / "shipped_ratios.png")
    args = ap.parse_args(argv)
    frames = {label: run(file, args.seeds, args.out / Path(file).stem) for label, file in SCENARIOS.items()}
    draw(frames, args.figure)


if __name__ == "__main__":
    main()
