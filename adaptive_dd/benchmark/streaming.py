"""Metrics accumulated while a run streams: per trial and payload segment, nothing per sample
but the error norm (float32, for recovery times) and, for the first few seeds, trajectories.

Both the Python runner and the compiled closed loop call :func:`accumulate_trial`, so the
two paths accumulate the same sums in the same order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from adaptive_dd.plant.sampling import first_sample

__all__ = ["ACC_FIELDS", "accumulate_trial", "segment_bounds"]

ACC_FIELDS = (
    "sum_e2",
    "sum_e2_joint1",
    "sum_e2_joint2",
    "max_e",
    "sum_tau2",
    "n_saturated",
    "sum_e2_settled",
)
"""Per trial and segment: sums of |e|^2 (both joints and per joint), max |e|, sum of |tau|^2,
samples with a saturated joint, sum of |e|^2 after the settling time."""
N_ACC = len(ACC_FIELDS)


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


@njit(cache=True)
def accumulate_trial(acc, e_norm, k, seg_start, seg_settled, e1, e2, tau, sat_mask):  # pragma: no cover
    """Add sample k of one trial (error ``e1, e2`` [rad], applied ``tau (2,)``) to ``acc (n_seg, 7)``."""
    s = 0
    while s + 1 < seg_start.shape[0] and k >= seg_start[s + 1]:
        s += 1
    en2 = e1 * e1 + e2 * e2
    en = np.sqrt(en2)
    acc[s, 0] += en2
    acc[s, 1] += e1 * e1
    acc[s, 2] += e2 * e2
    if en > acc[s, 3]:
        acc[s, 3] = en
    acc[s, 4] += tau[0] * tau[0] + tau[1] * tau[1]
    if sat_mask != 0:
        acc[s, 5] += 1.0
    if k >= seg_settled[s]:
        acc[s, 6] += en2
    e_norm[k] = en
    return s


@njit(cache=True)
def accumulate_batch(acc, e_norm, k, seg_start, seg_settled, err, tau, sat):  # pragma: no cover
    """:func:`accumulate_trial` for every trial: ``err, tau (n, 2)``, ``sat (n, 2)`` bool."""
    for i in range(err.shape[0]):
        m = (1 if sat[i, 0] else 0) | (2 if sat[i, 1] else 0)
        accumulate_trial(acc[i], e_norm[i], k, seg_start, seg_settled, err[i, 0], err[i, 1], tau[i], m)
