"""Draw ``docs/shipped_ratios.png`` and ``docs/shipped_time_to_floor.png``: adaptive_ct against its
floor on every shipped N-joint scenario.

Runs ``adaptive-dd benchmark FILE --seeds N --controllers ct_nominal adaptive_ct --out
OUT/NAME`` for each scenario of the table "Every shipped scenario" on the results page (a run
whose ``per_seed.csv`` is already in ``OUT/NAME`` is not run again), then draws, per scenario, the
per-seed ratio of ``adaptive_ct``'s RMS tracking error to ``ct_oracle``'s in each payload segment:
every seed a dot, the mean with its 95 % interval a bar; and the first segment's time until
``adaptive_ct``'s error comes to stay within 1.2x the floor's, per seed (the report's ``time to
1.2x floor``; "never" drawn above the segment's end). From the repository's root::

    python docs/figures/shipped_ratios.py --seeds 50 [--scenarios ur5_tool_swap ...]

prints, per scenario and segment, the mean ratio and its interval, per scenario the time to the
floor's median and its count of "never", and writes the two figures.
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
    cols = min(4, len(frames) + 1)  # a panel per scenario and one for the legend
    rows = -(-(len(frames) + 1) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 3.1 * rows + 0.4), sharey=True, squeeze=False)
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
    for ax in axes.flat[len(frames) :]:
        ax.axis("off")
    axes.flat[-1].text(
        0.0, 0.5,
        "dots: one seed each\nblack bar: mean with its 95 % interval\n"
        "black line: the floor (ratio 1)\nred dashed: the target mean 1.1",
        transform=axes.flat[-1].transAxes, fontsize=9,
    )  # fmt: skip
    fig.suptitle(
        "Ratio of adaptive_ct's RMS tracking error to ct_oracle's, per seed and payload segment [-], "
        + ("every shipped N-joint scenario, " if len(frames) == len(SCENARIOS) else "")
        + f"{next(iter(frames.values()))['seed'].nunique()} seeds"
        + " (log scale)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def draw_time_to_floor(frames: dict[str, pd.DataFrame], path: Path) -> None:
    """Per scenario: the first segment's time to come within 1.2x the floor, one dot per seed."""
    fig, ax = plt.subplots(figsize=(9, 4))
    for x, (label, df) in enumerate(frames.items()):
        first = df[(df["controller"] == "adaptive_ct") & (df["segment"] == 0)]
        t = first["time_to_floor_s"].to_numpy(dtype=float)
        end = float(first["end_s"].iloc[0])
        never = ~np.isfinite(t)
        shown = np.where(never, end * 1.08, t)
        jitter = np.random.default_rng(x).uniform(-0.2, 0.2, t.size)
        ax.plot(x + jitter[~never], shown[~never], ".", color="tab:blue", ms=4, alpha=0.6)
        ax.plot(x + jitter[never], shown[never], "x", color="tab:red", ms=4, alpha=0.6)
        ax.plot([x - 0.3, x + 0.3], [end, end], color="k", lw=1)
        med = np.median(np.where(never, np.inf, t))
        med_s = "never" if not np.isfinite(med) else f"{med:.2f} s"
        print(f"{label:24s} time to 1.2x floor: median {med_s}, never in {never.sum()} of {t.size}")
    ax.set_xticks(range(len(frames)), list(frames), rotation=20, ha="right", fontsize=8)
    ax.set_ylabel("time to stay within 1.2x the floor [s]")
    ax.grid(alpha=0.3, axis="y")
    fig.suptitle(
        "First segment: time [s] until adaptive_ct's 0.25 s RMS error stays within 1.2x ct_oracle's, "
        "per seed (black line: the first swap; red x: never before it)",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "shipped_ratios")
    ap.add_argument("--figure", type=Path, default=ROOT / "docs" / "shipped_ratios.png")
    ap.add_argument(
        "--scenarios", nargs="+", metavar="STEM", help="only these scenarios, by file stem (default: all)"
    )
    args = ap.parse_args(argv)
    stems = {Path(file).stem: label for label, file in SCENARIOS.items()}
    unknown = sorted(set(args.scenarios or ()) - set(stems))
    if unknown:
        ap.error(f"--scenarios: no shipped scenario {', '.join(unknown)}; choose from {', '.join(stems)}")
    chosen = {
        label: file
        for label, file in SCENARIOS.items()
        if not args.scenarios or Path(file).stem in args.scenarios
    }
    frames = {label: run(file, args.seeds, args.out / Path(file).stem) for label, file in chosen.items()}
    draw(frames, args.figure)
    draw_time_to_floor(frames, args.figure.with_name("shipped_time_to_floor.png"))


if __name__ == "__main__":
    main()
