"""Metrics accumulated while a run streams: per trial and payload segment, nothing per sample
but the error norm (float32, for recovery times) and, for the first few seeds, trajectories.

The sums are the closed loop's :class:`~adaptive_dd.closed_loop.types.StreamedSums` (the
N-joint runs hold the same record). Both two-link paths, the Python runner and the compiled
closed loop, call :func:`accumulate_trial`, so they accumulate the same sums in the same order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.sampling import first_sample

SETTLE = 0.5
"""[s] left out at the start of each segment for ``rms_error_settled``."""

__all__ = ["SETTLE", "accumulate_trial", "segment_bounds"]


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


@njit(cache=True, inline="always")
def accumulate_trial(acc, i, k, seg_start, seg_settled, e1, e2, tau, sat_mask):  # pragma: no cover
    """Add sample k of trial i (error ``e1, e2`` [rad], applied ``tau (2,)``, ``sat_mask`` bit j set
    if joint j saturated) to ``acc`` (:class:`~adaptive_dd.closed_loop.types.StreamedSums`);
    returns the sample's segment."""
    s = 0
    while s + 1 < seg_start.shape[0] and k >= seg_start[s + 1]:
        s += 1
    en2 = e1 * e1 + e2 * e2
    en = np.sqrt(en2)
    acc.sum_e2[i, s] += en2
    acc.sum_e2_joint[i, s, 0] += e1 * e1
    acc.sum_e2_joint[i, s, 1] += e2 * e2
    if en > acc.max_e[i, s]:
        acc.max_e[i, s] = en
    acc.sum_tau2[i, s] += tau[0] * tau[0] + tau[1] * tau[1]
    if sat_mask != 0:
        acc.n_saturated[i, s] += 1.0
    if k >= seg_settled[s]:
        acc.sum_e2_settled[i, s] += en2
    acc.e_norm[i, k] = en
    return s
