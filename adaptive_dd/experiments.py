"""The paper's experiments as reusable inputs (Table 2, Table 4)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import ParameterError

__all__ = ["TABLE2", "table2_torque", "trial_rngs"]

TABLE2 = {
    "amplitude": (12.5, 3.75),  # N m, joints 1 and 2
    "frequency": 1.0,  # Hz
    "sample_period": 1e-3,  # s
    "n_samples": 10_000,
    "position_variance": (1e-8, 1e-7),  # rad^2
    "velocity_variance": (5e-5, 1e-4),  # (rad/s)^2, Table 4
}
"""Conditions of Table 2 (plus the Table 4 velocity noise), read as in docs/paper_reading.md."""


def table2_torque(
    n_trials: int = 1,
    n_samples: int = TABLE2["n_samples"],
    sample_period: float = TABLE2["sample_period"],
    amplitude: tuple[float, float] = TABLE2["amplitude"],
    frequency: float = TABLE2["frequency"],
) -> NDArray[np.float64]:
    """Open-loop torques ``tau_i = A_i sin(2 pi f k T)``, shape ``(n_trials, n_samples, 2)``."""
    if n_trials < 1 or n_samples < 1 or sample_period <= 0:
        raise ParameterError(
            f"need n_trials >= 1, n_samples >= 1, sample_period > 0; got "
            f"{n_trials}, {n_samples}, {sample_period}"
        )
    k = np.arange(n_samples)
    s = np.sin(2 * np.pi * frequency * k * sample_period)
    tau = s[:, None] * np.asarray(amplitude, dtype=float)
    return np.broadcast_to(tau, (n_trials, n_samples, 2)).copy()


def trial_rngs(seed: int, n_trials: int) -> list[np.random.Generator]:
    """One generator per trial, seeded by ``(seed, i)``: trial i's noise does not
    depend on how many other trials run beside it."""
    return [np.random.default_rng([int(seed), i]) for i in range(int(n_trials))]
