"""Actuator (saturation, D/A) and sensor (encoder, noise) models of an arm."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.sampling import actuate_batch, measure_batch

__all__ = ["ActuatorConfig", "SensorConfig"]

Array = NDArray[np.float64]


# ------------------------------------------------------------------ actuators
@dataclass(frozen=True)
class ActuatorConfig:
    """Torque path from command to joint.

    Attributes
    ----------
    torque_limit : (float, float)
        Saturation torques [N m] of joints 1, 2 (70, 15 for the SICE arm:
        :meth:`adaptive_dd.plant.two_link.ClosedFormTwoLink.sice`).
    saturate : bool
        Clip commands to +-torque_limit.
    quantize : bool
        Model the 12-bit D/A over +-8 V: the torque is rounded to a step of
        ``2 * torque_limit / 2**dac_bits``.
    dac_bits : int
        D/A resolution.
    """

    torque_limit: tuple[float, float]
    saturate: bool = True
    quantize: bool = True
    dac_bits: int = 12

    def __post_init__(self) -> None:
        lim = self.torque_limit
        if not 1 <= len(lim) <= 62 or not all(np.isfinite(lim)) or min(lim) <= 0:
            raise ParameterError(
                f"torque_limit must be one positive value per joint, got {self.torque_limit}"
            )
        if self.dac_bits < 1:
            raise ParameterError(f"dac_bits must be >= 1, got {self.dac_bits}")

    @cached_property
    def _lim(self) -> Array:
        return np.asarray(self.torque_limit, dtype=float)

    @cached_property
    def _lsb(self) -> Array:
        return 2.0 * self._lim / 2**self.dac_bits

    def apply(self, tau_cmd: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Return the applied torque and a per-joint flag of saturation (``tau_cmd (n, 2)``).

        The compiled :func:`adaptive_dd.plant.sampling.actuate_trial` does the work (the
        compiled closed loop calls the same function)."""
        cmd = np.array(tau_cmd, dtype=float, order="C").reshape(-1, len(self.torque_limit))  # writable
        tau = np.empty_like(cmd)
        sat = np.empty(cmd.shape, dtype=np.bool_)
        actuate_batch(cmd, self._lim, self._lsb, self.saturate, self.quantize, tau, sat)
        return tau.reshape(np.shape(tau_cmd)), sat.reshape(np.shape(tau_cmd))


# --------------------------------------------------------------------- sensors
@dataclass(frozen=True)
class SensorConfig:
    """Measurement of q (encoder) and qd (F/V conversion).

    Attributes
    ----------
    encoder_counts : (int, int)
        Pulses per revolution (614400 and 507904 on the SICE arm).
    quantize : bool
        Round the position to the encoder resolution before adding noise.
    position_variance : (float, float)
        Variance [rad^2] of additive white noise on q (Table 2).
    velocity_variance : (float, float)
        Variance [(rad/s)^2] of additive white noise on qd (Table 4).
    """

    encoder_counts: tuple[int, int] = (614400, 507904)
    quantize: bool = True
    position_variance: tuple[float, float] = (1e-8, 1e-7)
    velocity_variance: tuple[float, float] = (5e-5, 1e-4)

    def __post_init__(self) -> None:
        n = len(self.encoder_counts)
        for name in ("encoder_counts", "position_variance", "velocity_variance"):
            v = getattr(self, name)
            if len(v) != n or n < 1 or not all(np.isfinite(v)):
                raise ParameterError(
                    f"SensorConfig.{name} must hold one finite value per joint ({n}), got {v}"
                )
        if min(self.encoder_counts) <= 0:
            raise ParameterError(f"encoder_counts must be > 0, got {self.encoder_counts}")
        if min(self.position_variance) < 0 or min(self.velocity_variance) < 0:
            raise ParameterError(
                f"noise variances must be >= 0, got position {self.position_variance}, "
                f"velocity {self.velocity_variance}"
            )

    @cached_property
    def resolution(self) -> Array:
        """Encoder step [rad] of each joint."""
        return 2.0 * np.pi / np.asarray(self.encoder_counts, dtype=float)

    @cached_property
    def noise_std(self) -> Array:
        """Standard deviations ``[sq_1 .. sq_n, sqd_1 .. sqd_n]``."""
        return np.sqrt(np.concatenate((self.position_variance, self.velocity_variance)))

    def measure(self, q: Array, qd: Array, noise: Array) -> tuple[Array, Array]:
        """Measured ``(q, qd)`` from true values ``(m, n)`` and standard normal ``noise (m, 2n)``
        (:func:`adaptive_dd.plant.sampling.measure_trial`)."""
        qm, qdm = np.empty_like(q), np.empty_like(qd)
        measure_batch(
            np.ascontiguousarray(q),
            np.ascontiguousarray(qd),
            np.ascontiguousarray(noise),
            self.resolution,
            self.noise_std,
            self.quantize,
            qm,
            qdm,
        )
        return qm, qdm


SICE_SENSOR = SensorConfig(
    encoder_counts=(614400, 507904), position_variance=(1e-8, 1e-7), velocity_variance=(5e-5, 1e-4)
)
"""The SICE arm's encoders (counts per revolution) and noise variances (Tables 2 and 4 of the paper)."""
