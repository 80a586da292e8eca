"""The payload segments' sample bounds of a two-link run, over which its metrics stream.

The sums are the closed loop's :class:`~adaptive_dd.closed_loop.types.StreamedSums`, added to at
every sample by the one per-sample glue (:func:`~adaptive_dd.closed_loop.glue.apply_sample`).
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.plant.sampling import first_sample

MAX_ALARMS = 256
"""Alarm times kept per trial on the compiled path (the count goes on)."""

SETTLE = 0.5
"""[s] left out at the start of each segment for ``rms_error_settled``."""

__all__ = ["SETTLE", "segment_bounds"]


def segment_bounds(
    segments, sample_period: float, settle: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(start, end, settled_start)`` sample indices of each ``(t0, t1, mass)`` segment.

    A segment starts at :func:`~adaptive_dd.plant.sampling.first_sample` of its start time (the
    sample at which the plant's payload changes); the last one ends at ``round(duration / T)``."""
    start = np.array([first_sample(a, sample_period) for a, _, _ in segments], dtype=np.int64)
    n = round(segments[-1][1] / sample_period)
    end = np.array([*start[1:], n], dtype=np.int64)
    settled = np.minimum(end - 1, start + round(settle / sample_period))
    return start, end, settled
