"""Draw ``docs/payload_schedules.png``: the payload schedule of every shipped scenario.

Reads each scenario file (no simulation) and draws the mass the arm carries against time, as a
step per ``[[payload]]`` table,. From the repository's root::

    python docs/figures/payload_schedules.py

prints each schedule as ``(start [s], end [s], mass [kg])`` segments and writes the figure.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from adaptive_dd import load_scenario

ROOT = Path(__file__).resolve().parents[2]
FILES = {
    "paper's arm (default)": "adaptive_dd/scenarios/payload_swap.toml",
    "UR5 tool swap": "adaptive_dd/scenarios/ur5_tool_swap.toml",
    "Panda": "adaptive_dd/scenarios/panda_payload.toml",
    "iiwa 14": "adaptive_dd/scenarios/iiwa14_payload.toml",
    "vertical3": "adaptive_dd/scenarios/vertical3_payload.toml",
    "UR5 tool change (how-to)": "examples/tool_change.toml",
}


def main() -> None:
    fig, axes = plt.subplots(len(FILES), 1, figsize=(8, 6.5), sharex=True, sharey=True)
    for i, (ax, (label, file)) in enumerate(zip(axes, FILES.items(), strict=True)):
        segments = load_scenario(ROOT / file).segments()
        print(f"{file}: {segments}")
        t = [a for a, _, _ in segments] + [segments[-1][1]]
        m = [mass for _, _, mass in segments]
        ax.stairs(m, t, fill=True, color=f"C{i}", alpha=0.6)
        for a, b, mass in segments:
            ax.text(0.5 * (a + b), mass + 0.2, f"{mass:g} kg", ha="center", va="bottom", fontsize=7)
        ax.set_title(f"{label} ({Path(file).name})", fontsize=8, loc="left")
        ax.set_ylim(0, 6.5)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[len(FILES) // 2].set_ylabel("payload mass [kg]")
    fig.suptitle("Payload mass [kg] the arm carries against time [s] in each shipped scenario", fontsize=9)
    fig.tight_layout()
    path = ROOT / "docs" / "payload_schedules.png"
    fig.savefig(path, dpi=100)
    print(f"wrote {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
