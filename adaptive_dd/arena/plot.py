"""The leaderboard's figure: the mean per-seed ratio to the floor per controller and scenario
segment, a heat map (plotting only; the table is :func:`adaptive_dd.arena.leaderboard`). Uses
``matplotlib.figure.Figure`` directly (no pyplot, no backend set at import)."""

from __future__ import annotations

import numpy as np

from adaptive_dd.arena.leaderboard import contenders

__all__ = ["FLOOR_SATURATED_PCT", "plot_leaderboard"]

FLOOR_SATURATED_PCT = 1.0
"""[%] A cell whose floor saturates more often than this is marked (its ratio flatters the law)."""


def plot_leaderboard(df):
    """A heat map of ``ratio_mean`` (log colour scale): rows the controllers with a floor, columns
    each scenario's segments (``name:segment (kg)``); each cell prints the mean and, below it, the
    seeds' p90; ``x`` marks failures, ``*`` a floor saturated beyond :data:`FLOOR_SATURATED_PCT`.
    Returns the ``matplotlib.figure.Figure``."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    ranked = df[contenders(df)]
    cols = list(dict.fromkeys(zip(ranked["scenario"], ranked["segment"], ranked["payload_kg"], strict=True)))
    rows = list(dict.fromkeys(ranked["controller"]))
    z = np.full((len(rows), len(cols)), np.nan)
    fig = Figure(figsize=(1.0 * len(cols) + 3.5, 0.55 * len(rows) + 2.5), layout="constrained")
    ax = fig.subplots()
    for _, r in ranked.iterrows():
        i, j = rows.index(r["controller"]), cols.index((r["scenario"], r["segment"], r["payload_kg"]))
        z[i, j] = r["ratio_mean"]
        text = "" if not np.isfinite(r["ratio_mean"]) else f"{r['ratio_mean']:.2f}\n{r['ratio_p90']:.2f}"
        if r["failures"]:
            text += f"\nx{int(r['failures'])}"
        if r["floor_saturation_pct"] > FLOOR_SATURATED_PCT:
            text += "*"
        ax.text(j, i, text, ha="center", va="center", fontsize=6)
    finite = z[np.isfinite(z)]
    norm = LogNorm(max(finite.min(), 1e-3), max(finite.max(), 1.01)) if finite.size else None
    im = ax.imshow(z, cmap="RdYlGn_r", norm=norm, aspect="auto")
    ax.set_xticks(range(len(cols)), [f"{s}:{g} ({m:g} kg)" for s, g, m in cols], rotation=60, ha="right")
    ax.set_yticks(
        range(len(rows)),
        [f"{c} / {f}" for c, f in dict.fromkeys(zip(ranked["controller"], ranked["floor"], strict=True))],
    )
    ax.set_title("RMS error / floor's, per seed: mean (p90 below); x failures, * floor saturated", fontsize=8)
    fig.colorbar(im, ax=ax, label="mean ratio to the floor [-]")
    return fig
