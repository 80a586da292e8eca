"""Records of a serial arm on a prescribed motion (torques by inverse dynamics), for estimator tests.

The joints follow a smooth sum of sines; the torque that produces that motion is
computed exactly by the compiled RNEA (:func:`adaptive_dd.plant.chain_batch.rnea_batch`)
with friction ``fv qd + fc sgn(qd)``, armature and the payload of each segment; the
measurements ``q, qd`` get the sensor's white noise. No integration is involved, so
the record is exactly consistent with the model (the estimator's errors are its own).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.arm import Arm
from adaptive_dd.plant.chain import rnea_batch

__all__ = ["PrescribedRecord", "exciting_motion", "multisine", "prescribed_record"]

Array = NDArray[np.float64]


def multisine(
    t: ArrayLike, offset: ArrayLike, amplitude: ArrayLike, frequency: ArrayLike, phase: ArrayLike
) -> tuple[Array, Array, Array]:
    """``q = offset + sum_k a_jk sin(2 pi f_jk t + phi_jk)`` and its two derivatives, each ``(N, n)``.

    ``offset (n,)``, ``amplitude, frequency, phase (n, K)`` [rad, Hz, rad].
    """
    t = np.asarray(t, dtype=float)[:, None, None]
    a, f, ph = (np.asarray(x, dtype=float) for x in (amplitude, frequency, phase))
    w = 2 * np.pi * f
    arg = w * t + ph
    q = np.asarray(offset, dtype=float) + np.sum(a * np.sin(arg), axis=-1)
    qd = np.sum(a * w * np.cos(arg), axis=-1)
    qdd = -np.sum(a * w * w * np.sin(arg), axis=-1)
    return q, qd, qdd


def exciting_motion(
    arm: Arm,
    t: ArrayLike,
    rng: np.random.Generator,
    offset: ArrayLike | None = None,
    speed: float = 0.5,
    frequency: tuple[float, float] = (0.2, 1.2),
    n_terms: int = 2,
) -> tuple[Array, Array, Array]:
    """A random multisine per joint whose peak speed is ``speed`` times the joint's velocity limit.

    Frequencies uniform in ``frequency`` [Hz], random phases; ``offset`` (default the middle
    of finite position limits, else 0). Returns ``(q, qd, qdd)``, each ``(N, n)``.
    """
    n = arm.n_joints
    f = rng.uniform(*frequency, (n, n_terms))
    ph = rng.uniform(0.0, 2 * np.pi, (n, n_terms))
    a = rng.uniform(0.5, 1.0, (n, n_terms))
    a *= speed * arm.velocity_limits[:, None] / np.sum(a * 2 * np.pi * f, axis=1, keepdims=True)
    if offset is None:
        lim = arm.position_limits
        offset = np.where(np.isfinite(lim).all(axis=1), lim.mean(axis=1), 0.0)
    return multisine(t, offset, a, f, ph)


@dataclass(frozen=True)
class PrescribedRecord:
    """A record on a prescribed motion.

    Attributes
    ----------
    t : (N,) [s]
    q, qd, qdd : (N, n) true motion
    tau : (N, n) torque producing it [N m]
    q_meas, qd_meas : (N, n) measurements (with noise)
    payloads : (S, 10) payload parameters of each segment, about the payload frame
    segment : (N,) int, segment index of each sample
    """

    t: Array
    q: Array
    qd: Array
    qdd: Array
    tau: Array
    q_meas: Array
    qd_meas: Array
    payloads: Array
    segment: NDArray[np.int64]


def prescribed_record(
    arm: Arm,
    t: ArrayLike,
    motion: tuple[Array, Array, Array],
    payloads: ArrayLike,
    swap_samples: ArrayLike = (),
    rng: np.random.Generator | None = None,
    noise_scale: float = 1.0,
) -> PrescribedRecord:
    """Torques and noisy measurements of ``arm`` on a prescribed ``motion = (q, qd, qdd)``.

    Parameters
    ----------
    arm : Arm
        Standard parameters ``arm.pi`` (links, friction, armature), sensor noise variances.
    t : (N,)
    motion : three (N, n) arrays
    payloads : (S, 10)
        Payload parameters about the payload frame per segment
        (:func:`~adaptive_dd.plant.arm.payload_parameters`).
    swap_samples : (S - 1,) int
        First sample of segments 1 .. S-1.
    rng : numpy.random.Generator, optional
        Noise source; None: no noise.
    noise_scale : float
        Multiplies the sensor's standard deviations.
    """
    q, qd, qdd = (np.asarray(x, dtype=float) for x in motion)
    pays = np.atleast_2d(np.asarray(payloads, dtype=float))
    swaps = np.asarray(swap_samples, dtype=np.int64)
    N, n = q.shape
    if pays.shape[1] != 10 or len(swaps) != len(pays) - 1 or np.any(np.diff(swaps) <= 0):
        raise ParameterError(
            f"payloads must be (S, 10) with S - 1 increasing swap samples, got {pays.shape}, {swaps}"
        )
    seg = np.searchsorted(swaps, np.arange(N), side="right")
    tau = np.empty((N, n))
    j = arm.payload_joint
    for s in range(len(pays)):
        pi = arm.pi_links.copy()
        pi[10 * j : 10 * j + 10] += arm.payload_map @ pays[s]
        k = seg == s
        if k.any():
            tau[k] = rnea_batch(arm.chain, pi, q[k], qd[k], qdd[k])
    tau += arm.viscous * qd + arm.coulomb * np.sign(qd) + arm.armature * qdd
    qm, qdm = q.copy(), qd.copy()
    if rng is not None:
        qm += noise_scale * np.sqrt(arm.sensor.position_variance) * rng.standard_normal((N, n))
        qdm += noise_scale * np.sqrt(arm.sensor.velocity_variance) * rng.standard_normal((N, n))
    return PrescribedRecord(np.asarray(t, dtype=float), q, qd, qdd, tau, qm, qdm, pays, seg)
