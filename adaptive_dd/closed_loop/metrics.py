"""Per-seed metrics of an N-joint run from its :class:`~adaptive_dd.closed_loop.types.StreamedSums`,
and the payload an estimating controller holds at the end of each segment."""

from __future__ import annotations

import numpy as np

from adaptive_dd.closed_loop.types import StreamedSums, sample_bounds

__all__ = ["MIN_COM_MASS", "payload_at_segment_ends", "segment_metrics"]

MIN_COM_MASS = 0.1
"""[kg]: below this estimated mass the centre of mass (first moment / mass) is not reported."""


def _counts(res) -> tuple[np.ndarray, np.ndarray]:
    """Samples per segment and per settled part, ``(G,)`` each (the bounds the loop used)."""
    start, end, settled = sample_bounds(res.scenario)
    return (end - start).astype(float), (end - settled).astype(float)


def segment_metrics(res, run) -> dict[str, np.ndarray]:
    """``(n_seeds, n_segments)`` arrays (the caller blanks failed trials by the benchmark's one
    rule, :func:`~adaptive_dd.benchmark.metrics.segment_failed`): ``rms_error``, ``rms_error_joint{j}``
    (j = 1 .. n), ``max_error``, ``rms_torque``, ``saturation_fraction``, ``rms_error_settled``,
    and for controllers with an estimate ``mass_estimate`` [kg] and ``com_estimate_{x,y,z}`` [m]
    (:meth:`Arm.payload_from_sigma` of the estimate at the segment's last sample; the
    centre of mass NaN below :data:`MIN_COM_MASS`)."""
    acc: StreamedSums = run.acc
    n, n_set = _counts(res)
    out = {"rms_error": np.sqrt(acc.sum_e2 / n)}
    for j in range(acc.sum_e2_joint.shape[-1]):
        out[f"rms_error_joint{j + 1}"] = np.sqrt(acc.sum_e2_joint[..., j] / n)
    out.update(
        max_error=acc.max_e.copy(),
        rms_torque=np.sqrt(acc.sum_tau2 / n),
        saturation_fraction=acc.n_saturated / n,
        rms_error_settled=np.sqrt(acc.sum_e2_settled / n_set),
    )
    if run.sigma_end is not None:
        est = payload_at_segment_ends(res.scenario.arm, run.sigma_end)
        out["mass_estimate"] = est.mass
        small = ~(np.abs(est.mass) >= MIN_COM_MASS)
        for c, axis in enumerate("xyz"):
            out[f"com_estimate_{axis}"] = np.where(small, np.nan, est.com[..., c])
    return out


def payload_at_segment_ends(arm, sigma_end: np.ndarray):
    """The payload (mass, com, ...) implied by the estimates ``(..., p)``."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return arm.payload_from_sigma(sigma_end)
