"""Per-segment pieces every metric shares: the one failure rule of a trial and the causal moving
RMS (used by :mod:`~adaptive_dd.benchmark.metrics`, :mod:`~adaptive_dd.benchmark.time_to_floor`
and the plots)."""

from __future__ import annotations

import numpy as np

__all__ = ["moving_rms", "nonfinite_estimates", "segment_failed"]


def moving_rms(x: np.ndarray, n: int, axis: int = -1) -> np.ndarray:
    """Causal moving RMS over n samples along an axis."""
    x2 = np.moveaxis(np.asarray(x, float) ** 2, axis, -1)
    c = np.cumsum(x2, axis=-1)
    c = np.concatenate((np.zeros((*c.shape[:-1], 1)), c), axis=-1)
    k = np.arange(x2.shape[-1])
    lo = np.maximum(k + 1 - n, 0)
    out = np.sqrt((c[..., k + 1] - c[..., lo]) / (k + 1 - lo))
    return np.moveaxis(out, -1, axis)


def segment_failed(failed: np.ndarray, failed_at: np.ndarray, end: np.ndarray) -> np.ndarray:
    """``(n_seeds, n_segments)`` bool: the trial failed before the segment's end sample.

    The one failure rule of the benchmark and the sweep: a diverged trial (``failed_at >= 0``,
    the sample it was stopped at) is left out of the segments that end after its failure; a
    trial failed without a sample (its controller raised: ``failed_at < 0``) everywhere.
    """
    failed = np.asarray(failed, bool)[:, None]
    at = np.asarray(failed_at)[:, None]
    return failed & ((at < 0) | (at < np.asarray(end)[None, :]))


def nonfinite_estimates(sigma_end: np.ndarray | None, failed: np.ndarray, error: bool, seeds) -> list | None:
    """``[[seed, segment], ...]`` where a trial that did not fail ends a segment with an estimate
    that is not finite (a NaN from the controller's own estimator, left out of the mass and centre
    of mass columns: said, not dropped in silence); None for a controller without an estimate."""
    if sigma_end is None:
        return None
    bad = ~np.isfinite(sigma_end).all(axis=-1) & ~(failed | error)[:, None]
    return [[int(seeds[i]), int(g)] for i, g in zip(*np.nonzero(bad), strict=True)]
