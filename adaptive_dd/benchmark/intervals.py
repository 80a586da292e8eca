"""The 95 % interval of a mean per-seed ratio: one method for the report, its figure, the
Gymnasium score and the arena's leaderboard.

Per-seed ratios to a floor are skewed (bounded below near 1, a long tail of bad seeds), so the
interval is the percentile bootstrap of the mean (Efron and Tibshirani, *An Introduction to the
Bootstrap*, 1993, ch. 13): the seeds resampled with replacement :data:`BOOTSTRAP_RESAMPLES`
times, the 2.5 and 97.5 percentiles of the resampled means. Its draws come from a generator
passed in, by default one seeded with 0, so an interval is reproducible from the ratios alone.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BOOTSTRAP_RESAMPLES", "mean_interval"]

BOOTSTRAP_RESAMPLES = 2000
"""Resamples of the seeds for the 95 % interval of the mean ratio (percentile bootstrap)."""


def mean_interval(ratio, rng: np.random.Generator | None = None) -> tuple[float, float] | None:
    """The percentile-bootstrap 95 % interval of the mean of ``ratio`` (module docstring).

    Parameters
    ----------
    ratio : array_like (n,)
        Per-seed ratios; non-finite entries (failed trials) are left out, in order.
    rng : numpy.random.Generator, optional
        Where the resamples are drawn (default ``numpy.random.default_rng(0)``: the same ratios
        give the same interval).

    Returns
    -------
    tuple of float or None
        ``(low, high)``; None with fewer than two finite ratios (no interval).

    Examples
    --------
    >>> from adaptive_dd.benchmark.intervals import mean_interval
    >>> lo, hi = mean_interval([1.0, 1.1, 1.2, 1.05, 1.3])
    >>> bool(lo < 1.13 < hi)
    True
    >>> mean_interval([2.0]) is None
    True
    """
    r = np.asarray(ratio, dtype=float).ravel()
    r = r[np.isfinite(r)]
    if r.size < 2:
        return None
    rng = np.random.default_rng(0) if rng is None else rng
    boot = r[rng.integers(0, r.size, (BOOTSTRAP_RESAMPLES, r.size))].mean(axis=1)
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return float(lo), float(hi)
