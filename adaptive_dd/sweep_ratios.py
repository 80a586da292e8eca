"""The per-cell ratio of a sweep's law to its floor, and why a cell's floor is not one (the marks):
:func:`ratio_medians`, read by :func:`adaptive_dd.sweep.run_sweep` for ``OUT/ratios.csv`` and the
heat maps."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["FLOOR_FAR", "SEEDS_FAILED", "ratio_medians"]

SEEDS_FAILED = "seeds' trials failed"
"""The words of a cell's mark when some of its seeds' trials failed (the command counts them)."""

FLOOR_FAR = 5.0
"""A cell whose floor's median RMS error in the heat map's segment exceeds this many times its own
in the first segment (before any swap, the same grid point and seeds) is marked: the floor is
not tracking as the law with the true model does, and a ratio to it says little."""


def ratio_medians(table: pd.DataFrame, heatmap: Mapping[str, Any], axes: Sequence[str]) -> pd.DataFrame:
    """Per grid point: the median over seeds of ``rms(adaptive) / rms(floor)`` in one segment,
    and whether the floor there is a floor.

    The ratio is formed per seed (both controllers ran on that seed's noise), then the
    median is taken over the seeds where both trials finished the segment. A cell is marked
    (``marked`` says why; empty when not) when its floor saturates (its saturation fraction in
    the segment, the mean over seeds, beyond :data:`~adaptive_dd.benchmark.metrics.SATURATION_LIMIT`:
    the benchmark's rule) or is far from its own nominal error (its median RMS error more than
    :data:`FLOOR_FAR` times its median in the first segment, before any swap), or when some of its
    seeds have no ratio (a trial of the law or of its floor failed: the median is over the others).

    Parameters
    ----------
    table : DataFrame
        The sweep's table (:func:`run_sweep`).
    heatmap : mapping
        ``adaptive``, ``floor`` (controller names) and ``segment`` (index).
    axes : sequence of str
        The grid axes (columns of the table).

    Returns
    -------
    DataFrame
        One row per grid point: ``point``, the axes, ``ratio`` (NaN if no seed
        finished), ``n_seeds`` (seeds in the median), the floor's median ``floor_rms`` [rad] in
        the segment, ``floor_nominal_rms`` [rad] in the first segment, ``floor_saturation``
        [fraction of samples, the mean over seeds] in the segment (NaN where the table has none),
        ``marked``, and for an adaptive controller with a change detector, over its seeds that
        finished the segment: ``delay_median`` [s], the median delay from the swap that starts the
        segment to the first alarm over the seeds that raised one, and ``missed``, the seeds that
        raised none (both NA without a detector, in the first segment, or where the table has no
        ``detection_delay``).

    Examples
    --------
    >>> import pandas as pd
    >>> from adaptive_dd.sweep import ratio_medians
    >>> table = pd.DataFrame({
    ...     "point": [0] * 6, "payload_mass": [3.0] * 6, "segment": [1, 1, 1, 1, 0, 0],
    ...     "seed": [0, 0, 1, 1, 0, 1], "controller": ["adaptive_ct", "ct_oracle"] * 2 + ["ct_oracle"] * 2,
    ...     "rms_error": [1.2e-4, 1e-4, 1.1e-4, 1e-4, 1e-4, 1e-4]})
    >>> heatmap = {"adaptive": "adaptive_ct", "floor": "ct_oracle", "segment": 1}
    >>> ratio_medians(table, heatmap, ["payload_mass"])[["payload_mass", "ratio", "n_seeds", "marked"]]
       payload_mass  ratio  n_seeds marked
    0           3.0   1.15        2
    """
    from adaptive_dd.benchmark.metrics import SATURATION_LIMIT

    seg = table[table["segment"] == heatmap["segment"]]
    cols = ["point", "seed"]
    a = seg[seg["controller"] == heatmap["adaptive"]].set_index(cols)["rms_error"]
    f = seg[seg["controller"] == heatmap["floor"]].set_index(cols)["rms_error"]
    per_seed = (a / f).rename("ratio").reset_index()
    per_seed = per_seed[np.isfinite(per_seed["ratio"])]
    med = per_seed.groupby("point")["ratio"].agg(["median", "count"])
    points = table.drop_duplicates("point").set_index("point")[list(axes)]
    out = points.join(med).rename(columns={"median": "ratio", "count": "n_seeds"})
    out["n_seeds"] = out["n_seeds"].fillna(0).astype(int)
    total = seg.groupby("point")["seed"].nunique().reindex(out.index).fillna(0).astype(int)
    lost = (total - out["n_seeds"]).clip(lower=0)
    floor = table[table["controller"] == heatmap["floor"]]
    here = floor[floor["segment"] == heatmap["segment"]].groupby("point")
    out["floor_rms"] = here["rms_error"].median()
    out["floor_nominal_rms"] = floor[floor["segment"] == 0].groupby("point")["rms_error"].median()
    if "saturation_fraction" in floor:
        out["floor_saturation"] = here["saturation_fraction"].mean()  # the report's: a mean over seeds
    else:
        out["floor_saturation"] = np.nan
    out["marked"] = [
        "; ".join(filter(None, (
            _mark(r, heatmap["floor"], heatmap["segment"], SATURATION_LIMIT),
            _failed_seeds(k, n),
        )))
        for (_, r), k, n in zip(out.iterrows(), lost, total, strict=True)
    ]  # fmt: skip
    out["delay_median"], out["missed"] = _delays(seg, heatmap["adaptive"], out.index)
    return out.reset_index()


def _delays(seg: pd.DataFrame, adaptive: str, points) -> tuple[pd.Series, pd.Series]:
    """Per grid point: the median detection delay [s] of ``adaptive`` in the segment's rows ``seg``
    over its seeds with an alarm, and the count of its finished seeds without one (NA where it has
    no detector: :func:`ratio_medians`)."""
    a = seg[seg["controller"] == adaptive]
    if "detection_delay" not in a or "detector" not in a or (a["segment"] == 0).any():
        # a table of before the columns; or the first segment, which no swap starts
        return pd.Series(np.nan, index=points), pd.Series(pd.NA, index=points, dtype="Int64")
    a = a[a["detector"].astype(bool) & ~a["failed"].astype(bool)]
    g = a.groupby("point")["detection_delay"]
    median = g.median().reindex(points)
    missed = g.apply(lambda d: int(d.isna().sum())).reindex(points).astype("Int64")
    return median, missed


def _mark(r, floor: str, segment: int, sat_limit: float) -> str:
    """Why a cell's ratio is not against a floor (:func:`ratio_medians`); empty when it is."""
    why = []
    if r["floor_saturation"] > sat_limit:
        why.append(
            f"{floor} saturated in {100 * r['floor_saturation']:.3g} % of the segment's samples "
            f"(limit {100 * sat_limit:g} %)"
        )
    far = r["floor_rms"] / r["floor_nominal_rms"]
    if segment != 0 and far > FLOOR_FAR:
        why.append(
            f"{floor} at {1e3 * r['floor_rms']:.3g} mrad, {far:.3g} x its {1e3 * r['floor_nominal_rms']:.3g} "
            f"mrad before the swap (limit {FLOOR_FAR:g} x)"
        )
    return "; ".join(why)


def _failed_seeds(k: int, n: int) -> str:
    """A cell's mark when ``k`` of its ``n`` seeds have no ratio; empty when none lacks one."""
    if not k:
        return ""
    rest = "no ratio" if k >= n else "the median is over the others"
    return f"{k} of {n} {SEEDS_FAILED} (or their floor's did): {rest}"
