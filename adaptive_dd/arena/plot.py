"""The leaderboard's figure: the mean per-seed ratio to the floor per controller and scenario
segment, a heat map (plotting only; the table is :func:`adaptive_dd.arena.leaderboard`). Uses
``matplotlib.figure.Figure`` directly (no pyplot, no backend set at import)."""

from __future__ import annotations

import numpy as np

from adaptive_dd.arena.columns import contenders, references

__all__ = ["FLOOR_SATURATED_PCT", "RATIO_SCALE", "plot_leaderboard"]

FLOOR_SATURATED_PCT = 1.0
"""[%] A cell whose floor saturates more often than this is marked (its ratio flatters the law)."""


RATIO_SCALE = (0.5, 10.0)
"""The colour scale's range of the mean ratio (log; widened to the figure's own extremes): one
colour means one ratio in every leaderboard's figure."""


def plot_leaderboard(df):
    """A heat map of ``ratio_mean`` (log colour scale over at least :data:`RATIO_SCALE`): rows the
    controllers with a floor (a law told the true model, as ``ct_oracle_late``, marked as a
    reference), columns each scenario's segments (``name:segment (kg)``); each cell prints the mean
    and, below it, the seeds' p90; ``x`` marks failures, ``*`` a floor saturated beyond
    :data:`FLOOR_SATURATED_PCT`. Returns the ``matplotlib.figure.Figure``."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    told = references(df)
    ranked = df[contenders(df) | told]
    cols = list(dict.fromkeys(zip(ranked["scenario"], ranked["segment"], ranked["payload_kg"], strict=True)))
    rows = list(dict.fromkeys(zip(ranked["controller"], ranked["floor"], strict=True)))  # a law per floor
    z = np.full((len(rows), len(cols)), np.nan)
    fig = Figure(figsize=(1.0 * len(cols) + 3.5, 0.55 * len(rows) + 2.5), layout="constrained")
    ax = fig.subplots()
    for _, r in ranked.iterrows():
        i = rows.index((r["controller"], r["floor"]))
        j = cols.index((r["scenario"], r["segment"], r["payload_kg"]))
        z[i, j] = r["ratio_mean"]
        text = "" if not np.isfinite(r["ratio_mean"]) else f"{r['ratio_mean']:.2f}\n{r['ratio_p90']:.2f}"
        if r["failures"]:
            text += f"\nx{int(r['failures'])}"
        if r["floor_saturation_pct"] > FLOOR_SATURATED_PCT:
            text += "*"
        ax.text(j, i, text, ha="center", va="center", fontsize=6)
    finite = z[np.isfinite(z)]
    lo, hi = RATIO_SCALE
    if finite.size:
        lo, hi = min(lo, max(finite.min(), 1e-3)), max(hi, finite.max())
    im = ax.imshow(z, cmap="RdYlGn_r", norm=LogNorm(lo, hi), aspect="auto")
    ax.set_xticks(range(len(cols)), [f"{s}:{g} ({m:g} kg)" for s, g, m in cols], rotation=60, ha="right")
    reference = set(df.loc[told, "controller"])
    ax.set_yticks(
        range(len(rows)),
        [f"{c} / {f}" + (" (told the model; a reference)" if c in reference else "") for c, f in rows],
    )
    ax.set_title("RMS error / floor's, per seed: mean (p90 below); x failures, * floor saturated", fontsize=8)
    bar = fig.colorbar(im, ax=ax, label="mean ratio to floor")
    ticks = [x for x in (0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000) if lo <= x <= hi]
    bar.ax.yaxis.set_major_locator(FixedLocator(ticks))
    bar.ax.yaxis.set_minor_locator(NullLocator())
    bar.ax.yaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    return fig
