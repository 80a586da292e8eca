"""Compiled actuator and sensor models of one sample (the D/A and encoder side of the plant).

The only implementations: :class:`~adaptive_dd.plant.simulator.ActuatorConfig` and
:class:`~adaptive_dd.plant.simulator.SensorConfig` call the batched wrappers, the compiled
closed loop the per-trial functions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["actuate_trial", "first_sample", "measure_trial", "project_trial"]


def first_sample(t: float, sample_period: float) -> int:
    """Index of the first sample ``k T >= t`` [s -> samples]: the one conversion of a time to a sample.

    A payload change at ``t`` acts on the plant from this sample on, and the metrics' segment
    starts there; ``1e-9`` of a sample absorbs the rounding of ``t / T`` (``2.0 / 0.001``).
    """
    return math.ceil(t / sample_period - 1e-9)


@njit(cache=True)
def actuate_trial(tau_cmd, lim, lsb, saturate, quantize, out):  # pragma: no cover - compiled
    """Applied torque ``out (n,)`` from the command; returns a bit mask of saturated joints.

    Saturation at ``+-lim``; a D/A of step ``lsb`` whose top code is ``lim - lsb``.
    """
    mask = 0
    for j in range(tau_cmd.shape[0]):
        t = tau_cmd[j]
        if abs(t) > lim[j]:
            mask |= 1 << j
        if saturate:
            t = min(max(t, -lim[j]), lim[j])
        if quantize:
            t = np.round(t / lsb[j]) * lsb[j]
            if saturate:
                t = min(t, lim[j] - lsb[j])
        out[j] = t
    return mask


@njit(cache=True)
def measure_trial(q, qd, noise, res, std, quantize, qm, qdm):  # pragma: no cover - compiled
    """Measured ``qm, qdm (n,)``: encoder quantization of q, then additive noise ``noise (2n,) * std``."""
    n = q.shape[0]
    for j in range(n):
        p = np.round(q[j] / res[j]) * res[j] if quantize else q[j]
        qm[j] = p + noise[j] * std[j]
        qdm[j] = qd[j] + noise[n + j] * std[n + j]


@njit(cache=True)
def actuate_batch(tau_cmd, lim, lsb, saturate, quantize, out, sat):  # pragma: no cover - compiled
    for i in range(tau_cmd.shape[0]):
        m = actuate_trial(tau_cmd[i], lim, lsb, saturate, quantize, out[i])
        for j in range(tau_cmd.shape[1]):
            sat[i, j] = (m & (1 << j)) != 0


@njit(cache=True)
def measure_batch(q, qd, noise, res, std, quantize, qm, qdm):  # pragma: no cover - compiled
    for i in range(q.shape[0]):
        measure_trial(q[i], qd[i], noise[i], res, std, quantize, qm[i], qdm[i])


@njit(cache=True)
def project_trial(src, dst, j_min, margin, r_min):  # pragma: no cover - compiled
    """Nearest physically consistent sigma (as :func:`adaptive_dd.plant.project_sigma`) into ``dst``."""
    for j in range(7):
        dst[j] = src[j]
    dst[0] = max(dst[0], j_min)
    dst[1] = max(dst[1], j_min)
    for j in range(3, 7):
        dst[j] = max(dst[j], 0.0)
    r_max = np.sqrt((1.0 - margin) * dst[0] * dst[1])
    dst[2] = min(max(dst[2], r_min), r_max)


@njit(cache=True)
def limit_crossings(a, b, c, x_max, xs, n):  # pragma: no cover - compiled
    """Append to ``xs`` (from index ``n``) the roots of ``a x^2 + b x = c`` in ``(0, x_max)``;
    return the new count: where a command plus a boost growing as ``a x^2 + b x`` meets a torque
    limit ``c`` away (both runtimes' boost within the limits)."""
    if a == 0.0:
        if b != 0.0 and 0.0 < c / b < x_max:
            xs[n] = c / b
            n += 1
        return n
    disc = b * b + 4.0 * a * c
    if disc < 0.0:
        return n
    h = -0.5 * (b + np.copysign(np.sqrt(disc), b))  # the roots h / a and -c / h, stably
    if h == 0.0:
        return n
    for x in (h / a, -c / h):
        if 0.0 < x < x_max:
            xs[n] = x
            n += 1
    return n
