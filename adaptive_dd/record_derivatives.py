"""Velocities and accelerations of logged positions: a Savitzky-Golay differentiator (cubic, a
window of about 0.1 s), the one :mod:`adaptive_dd.record` derives a log's velocities with and
``predict`` its accelerations."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["DERIVATIVE_WINDOW", "derivative_samples", "derivatives"]

Array = NDArray[np.float64]

DERIVATIVE_WINDOW = 0.1
"""Savitzky-Golay window [s] of derived velocities and accelerations."""


def derivative_samples(T: float, n: int, window: float = DERIVATIVE_WINDOW) -> int:
    """The odd number of samples of :func:`derivatives`' window on ``n`` samples at ``T``."""
    return min(max(7, 2 * round(window / T / 2) + 1), n - (1 - n % 2))


def derivatives(q: Array, T: float, window: float = DERIVATIVE_WINDOW) -> tuple[Array, Array]:
    """Velocity and acceleration ``(N, n)`` of uniformly sampled positions (Savitzky-Golay, cubic).

    The window is ``window`` seconds rounded to an odd number of samples (at least 7): a
    zero-phase smoothing differentiator whose gain falls off above about ``1 / window`` Hz.
    """
    from scipy.signal import savgol_filter

    m = derivative_samples(T, q.shape[0], window)
    qd = savgol_filter(q, m, 3, deriv=1, delta=T, axis=0, mode="interp")
    qdd = savgol_filter(q, m, 3, deriv=2, delta=T, axis=0, mode="interp")
    return qd, qdd
