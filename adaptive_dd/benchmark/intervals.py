"""The 95 % interval of a mean per-seed ratio: one method for the report, its figure, the
Gymnasium score and the arena's leaderboard.

Per-seed ratios to a floor are skewed (bounded below near 1, a long tail of bad seeds), so the
interval is the percentile bootstrap of the mean (Efron and Tibshirani, *An Introduction to the
Bootstrap*, 1993, ch. 13): the seeds resampled with replacement :data:`BOOTSTRAP_RESAMPLES`
times, the 2.5 and 97.5 percentiles of the resampled means. The ratios are sorted first and the
draws come from a generator seeded with ``seed`` (default 0), so the interval is a function of
the set of ratios and the seed alone: the same trials in another order, or in another table (the
report, its figure, the score, a leaderboard's row), give the same interval.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BOOTSTRAP_RESAMPLES", "mean_interval"]

BOOTSTRAP_RESAMPLES = 2000
"""Resamples of the seeds for the 95 % interval of the mean ratio (percentile bootstrap)."""


def mean_interval(ratio, seed: int = 0) -> tuple[float, float] | None:
    """The percentile-bootstrap 95 % interval of the mean of ``ratio`` (module docstring).

    Parameters
    ----------
    ratio : array_like (n,)
        Per-seed ratios, in any order; non-finite entries (failed trials) are left out.
    seed : int
        Seed of the generator the resamples are drawn from (``numpy.random.default_rng(seed)``).

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
    >>> mean_interval([1.3, 1.0, 1.2, 1.05, 1.1]) == (lo, hi)  # the same set in another order
    True
    >>> mean_interval([2.0]) is None
    True
    """
    r = np.asarray(ratio, dtype=float).ravel()
    r = np.sort(r[np.isfinite(r)])  # the set of ratios, not their order
    if r.size < 2:
        return None
    draws = np.random.default_rng(seed).integers(0, r.size, (BOOTSTRAP_RESAMPLES, r.size))
    boot = r[draws].mean(axis=1)
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return float(lo), float(hi)
