"""The width of the identification's Coulomb law, from the record: one rule for every route.

The identification writes Coulomb friction as ``fc tanh(qd / v)``
(:mod:`adaptive_dd.identification.model`). A plant whose law has a sign (stick-slip, Stribeck: the
shipped arms') gives, of a measured velocity with noise of std ``s``, ``E[sgn(qd) | qd_measured] =
erf(qd / (sqrt(2) s))``, about ``tanh(qd / s)``: the width that fits is the measured velocity's
noise, not the arm's ``friction_velocity`` (0.02 rad/s by default; on the drawn iiwa's excitation
that wider law made three fifths of the identified model's torque error along the task's path,
``studies/excitation_diagnosis.py``). A plant whose law is that ``tanh`` keeps its own width.

The noise is measured on the record itself (:func:`velocity_noise_std`), so ``adaptive-dd
identify`` (a log, no stated noise) and the excitation phase of ``[run] excite`` (a simulated
record) give the same model on the same record (``[model] from = "model.json"`` and ``[run]
excite`` hand on the same friction).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

__all__ = ["MIN_WIDTH", "coulomb_width", "identification_model", "velocity_noise_std"]

Array = NDArray[np.float64]

MIN_WIDTH = 1e-9
"""[rad/s] The width of a noise-free record (the sign itself, kept finite)."""


def velocity_noise_std(qd: Array) -> float:
    """[rad/s] The white noise std of the velocities ``qd (N, n)`` of a record, rms over the joints:
    each joint's second difference's spread over ``sqrt(6)``, the spread read robustly (``1.4826``
    times the median absolute deviation: a stick-slip plant's velocity jumps at sticking would
    inflate a standard deviation; on the paper's arm by up to 40 %). A smooth motion sampled at a
    millisecond adds a negligible ``T^2 d^3 qd / dt^3``. Velocities derived from positions carry
    the derivative's noise, which this measures the same way."""
    qd = np.asarray(qd, dtype=float)
    if qd.ndim != 2 or qd.shape[0] < 3:
        raise ValueError(f"velocity_noise_std: expected a record (N >= 3, n), got shape {qd.shape}")
    d2 = np.diff(qd, 2, axis=0)
    s = 1.4826 * np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0) / np.sqrt(6.0)
    return float(np.sqrt(np.mean(s**2)))


def coulomb_width(qd: Array, friction: str = "stick-slip", friction_velocity: float = 0.02) -> float:
    """[rad/s] The width ``v`` of the identification's ``fc tanh(qd / v)`` on the record of
    velocities ``qd (N, n)``: ``friction_velocity`` when the arm's law is ``"tanh"``, else the
    record's velocity noise (:func:`velocity_noise_std`, at least :data:`MIN_WIDTH`)."""
    if friction == "tanh":
        return float(friction_velocity)
    return max(velocity_noise_std(qd), MIN_WIDTH)


def identification_model(arm, qd: Array):
    """The :class:`~adaptive_dd.identification.model.Model` a record with velocities ``qd (N, n)``
    of ``arm`` is identified with: the arm's, its Coulomb law's width :func:`coulomb_width`."""
    from adaptive_dd.identification.model import arm_model

    v = coulomb_width(qd, getattr(arm, "friction", "stick-slip"), arm.friction_velocity)
    return dataclasses.replace(arm_model(arm), friction_velocity=v)
