"""Heatmaps of a sweep over two grid axes: the adaptive/floor RMS ratio, and the adaptive law's
delay from the swap to its first alarm.

Plotting only; the ratios come from :func:`adaptive_dd.sweep.ratio_medians`. Uses
``matplotlib.figure.Figure`` directly (no pyplot, no backend set at import).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["AXIS_UNITS", "axis_label", "plot_delay_heatmaps", "plot_ratio_heatmaps"]


AXIS_UNITS = {
    "payload_mass": "payload mass [kg]",
    "swap_time": "swap time [s]",
    "bandwidth": "bandwidth [rad/s]",
    "noise_scale": "sensor noise scale [-]",
    "controller": "controller",
    "seed": "seed",
}
"""Axis labels, with units, of the grid fields a sweep may vary."""


def axis_label(field: str) -> str:
    """The axis label of a sweep's grid field, with its unit.

    Parameters
    ----------
    field : str
        A grid axis (``payload_mass``, ``swap_time``, ``bandwidth``, ``noise_scale``, ...).

    Returns
    -------
    str
        The label from :data:`AXIS_UNITS`, or the field's name with ``_`` as spaces when it has
        none.

    Examples
    --------
    >>> from adaptive_dd.sweep_plot import axis_label
    >>> axis_label("payload_mass"), axis_label("swap_time")
    ('payload mass [kg]', 'swap time [s]')
    """
    return AXIS_UNITS.get(field, field.replace("_", " "))


def _grid(
    ratios: pd.DataFrame, x: str, y: str | None, value: str = "ratio", count: str = "n_seeds"
) -> tuple[list, list, np.ndarray, np.ndarray, np.ndarray]:
    """x values, y values (``[None]``: one row, a sweep of one varied axis), the ``value`` column
    (ratios), the ``count`` column (seeds; NA as 0), marks."""
    if y is None:
        ratios = ratios.assign(_row=None)
        y = "_row"
    xs = list(dict.fromkeys(ratios[x]))
    ys = list(dict.fromkeys(ratios[y]))
    z = np.full((len(ys), len(xs)), np.nan)
    n = np.zeros((len(ys), len(xs)), dtype=int)
    marked = np.zeros((len(ys), len(xs)), dtype=bool)
    for _, r in ratios.iterrows():
        i, j = ys.index(r[y]), xs.index(r[x])
        z[i, j], n[i, j] = r[value], 0 if pd.isna(r[count]) else r[count]
        marked[i, j] = bool(r.get("marked", ""))
    return xs, ys, z, n, marked


def _image(z: np.ndarray, xs: list, ys: list, x: str, y: str | None, cmap: str):
    """A heat map's figure of the cells ``z`` (rows ``ys``, columns ``xs``, grid axes ``x`` and
    ``y``; NaN grey), on a log scale when the finite values span a decade: ``(fig, ax, image,
    finite values, log)``."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1.2 * len(xs) + 3, 0.8 * len(ys) + 2.5), layout="constrained")
    ax = fig.subplots()
    finite = z[np.isfinite(z)]
    log = finite.size > 0 and finite.min() > 0 and finite.max() > 10 * finite.min()
    norm = LogNorm(finite.min(), finite.max()) if log else None
    im = ax.imshow(np.ma.masked_invalid(z), origin="lower", aspect="auto", cmap=cmap, norm=norm)
    ax.set_facecolor("0.85")
    ax.set_xticks(range(len(xs)), [f"{v:g}" if isinstance(v, float) else str(v) for v in xs])
    ax.set_xlabel(axis_label(x))
    if y is None:  # one varied axis: one row
        ax.set_yticks([])
    else:
        ax.set_yticks(range(len(ys)), [f"{v:g}" if isinstance(v, float) else str(v) for v in ys])
        ax.set_ylabel(axis_label(y))
    return fig, ax, im, finite, log


def _figure(ratios: pd.DataFrame, heatmap: Mapping[str, Any], title: str):
    """The heat map of one combination of the other axes (a ``matplotlib.figure.Figure``); the
    marked cells carry a hatched patch whose ``gid`` is ``"marked"``."""
    from matplotlib.patches import Rectangle

    x, y = heatmap["x"], heatmap["y"]
    xs, ys, z, n, marked = _grid(ratios, x, y)
    fig, ax, im, finite, log = _image(z, xs, ys, x, y, "viridis")
    mid = np.sqrt(finite.min() * finite.max()) if log else (np.mean(finite) if finite.size else 0.0)
    for i, j in itertools.product(range(len(ys)), range(len(xs))):
        ok = np.isfinite(z[i, j])
        label = f"{z[i, j]:.3g}\n({n[i, j]})" if ok else "n/a"
        color = "k" if ok and z[i, j] > mid else "w" if ok else "k"
        ax.text(j, i, label, ha="center", va="center", fontsize=8, color=color)
    for i, j in zip(*np.nonzero(marked), strict=True):  # the floor is no floor there: hatched
        ax.add_patch(
            Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, hatch="///", edgecolor="r", lw=0, gid="marked")
        )
    if marked.any():
        title += (
            f"\nhatched ({int(marked.sum())}): {heatmap['floor']} saturated "
            "or far from its own error before the swap"
        )
    label = f"median RMS error ratio\n{heatmap['adaptive']} / {heatmap['floor']} [-]"  # a short bar
    fig.colorbar(im, ax=ax, label=label)
    ax.set_title(title, fontsize=9)
    return fig


def plot_ratio_heatmaps(
    ratios: pd.DataFrame, heatmap: Mapping[str, Any], axes: Sequence[str], out: str | Path
) -> list[Path]:
    """One heatmap PNG per combination of the grid axes other than x and y.

    Parameters
    ----------
    ratios : DataFrame
        From :func:`adaptive_dd.sweep.ratio_medians`; its cells with a non-empty ``marked`` (the
        floor saturated or far from its own nominal error) are hatched.
    heatmap : mapping
        ``x``, ``y``, ``adaptive``, ``floor``, ``segment``.
    axes : sequence of str
        All grid axes.
    out : path
        Folder: writes ``heatmap.png`` (or ``heatmap_<i>.png``, one per combination).

    Returns
    -------
    list of Path
        The PNG files written.

    Examples
    --------
    >>> import tempfile
    >>> import pandas as pd
    >>> from adaptive_dd.sweep_plot import plot_ratio_heatmaps
    >>> ratios = pd.DataFrame({"payload_mass": [1.0, 3.0, 1.0, 3.0], "swap_time": [5.0, 5.0, 7.5, 7.5],
    ...                        "ratio": [1.02, 1.21, 1.03, 1.25], "n_seeds": [4, 4, 4, 4]})
    >>> heatmap = {"x": "payload_mass", "y": "swap_time", "adaptive": "adaptive_ct",
    ...            "floor": "ct_oracle", "segment": 1}
    >>> [p.name for p in plot_ratio_heatmaps(ratios, heatmap, ["payload_mass", "swap_time"],
    ...                                      tempfile.mkdtemp())]
    ['heatmap.png']
    """
    base = f"segment {heatmap['segment']}, per-seed ratio, median over seeds (count)"
    return _per_combination(ratios, heatmap, axes, Path(out), "heatmap", base, _figure)


def _per_combination(ratios, heatmap, axes, out: Path, stem: str, base: str, figure) -> list[Path]:
    """``figure(cells, heatmap, title)`` saved as ``OUT/<stem>.png``, or one ``<stem>_<i>.png`` per
    combination of the grid axes other than x and y (the combination in the title)."""
    others = [a for a in axes if a not in (heatmap["x"], heatmap["y"])]
    groups = list(ratios.groupby(others, sort=False)) if others else [((), ratios)]
    paths = []
    for i, (vals, sub) in enumerate(groups):
        vals = vals if isinstance(vals, tuple) else (vals,)
        extra = ", ".join(f"{a} = {v}" for a, v in zip(others, vals, strict=True))
        path = out / (f"{stem}.png" if len(groups) == 1 else f"{stem}_{i}.png")
        figure(sub, heatmap, base + (f"\n{extra}" if extra else "")).savefig(path, dpi=110)
        paths.append(path)
    return paths


def _delay_figure(ratios: pd.DataFrame, heatmap: Mapping[str, Any], title: str):
    """The heat map of the adaptive law's median delay to its first alarm [ms] in one combination
    of the other axes (a ``matplotlib.figure.Figure``); a cell whose seeds raised no alarm reads
    ``none``, and each cell names its seeds without one."""
    x, y = heatmap["x"], heatmap["y"]
    xs, ys, z, missed, _ = _grid(ratios.assign(_ms=1e3 * ratios["delay_median"]), x, y, "_ms", "missed")
    fig, ax, im, finite, log = _image(z, xs, ys, x, y, "magma_r")
    # white on the darker half of the scale
    lo, hi = (finite.min(), finite.max()) if finite.size else (0.0, 0.0)
    mid = np.sqrt(lo * hi) if log else 0.5 * (lo + hi)
    for i, j in itertools.product(range(len(ys)), range(len(xs))):
        ok = np.isfinite(z[i, j])
        label = (f"{z[i, j]:.0f}" if ok else "none") + (f"\n({missed[i, j]} missed)" if missed[i, j] else "")
        ax.text(j, i, label, ha="center", va="center", fontsize=8, color="w" if ok and z[i, j] > mid else "k")
    fig.colorbar(im, ax=ax, label=f"median delay to\n{heatmap['adaptive']}'s first alarm [ms]")
    ax.set_title(title, fontsize=9)
    return fig


def plot_delay_heatmaps(
    ratios: pd.DataFrame, heatmap: Mapping[str, Any], axes: Sequence[str], out: str | Path
) -> list[Path]:
    """The adaptive law's median delay from the swap to its first alarm, one PNG per combination of
    the grid axes other than x and y (as :func:`plot_ratio_heatmaps`); none when the law has no
    change detector (``missed`` NA in every cell).

    Parameters
    ----------
    ratios : DataFrame
        From :func:`adaptive_dd.sweep.ratio_medians` (``delay_median`` [s], ``missed``).
    heatmap : mapping
        ``x``, ``y``, ``adaptive``, ``segment``.
    axes : sequence of str
        All grid axes.
    out : path
        Folder: writes ``delays.png`` (or ``delays_<i>.png``, one per combination).

    Returns
    -------
    list of Path
        The PNG files written (empty without a detector).
    """
    if "missed" not in ratios or ratios["missed"].isna().all():
        return []
    base = f"segment {heatmap['segment']}: delay from the swap to the first alarm, median over seeds"
    return _per_combination(ratios, heatmap, axes, Path(out), "delays", base, _delay_figure)
