"""The detection limit of a payload swap: when an optimal test could know that the mass changed.

Beside the detector's measured delay the benchmark prints the time at which the best possible
test would detect the swap at the same false-alarm rate. The test is the generalized likelihood
ratio (GLR) of a change of the tip mass, the rest of the arm known (identified before the swap),
on the measurements of ``q`` and ``qd`` (the sensor noise of the scenario) after the swap. Its
statistic, with a known onset, has the non-centrality

    lambda(t) = dm^2 I_m(t),   I_m(t) = sum_{k = k_s + 1}^{t} s_k^T R^-1 s_k,

``s_k`` the sensitivity of the measured outputs to the mass along the trajectory (forward
sensitivity equations through the stick-slip dynamics,
:func:`~adaptive_dd.identification.sensitivity.local_sensitivities`), ``R`` the noise covariance.
The GLR detects with probability ``p`` once ``sqrt(lambda) >= z_(1 - alpha / 2) + z_p``. The
false-alarm rate is the detector's target, ``rate`` per trial (1 %); a trial of ``N`` samples
makes ``N`` tests, so ``alpha = rate / N`` (Bonferroni: the limit is, if anything, late, since the
tests are correlated). Defaults: ``p = 0.5`` (the median detection time, compared with the
median measured delay).

This is the information the data hold; the on-line detector also meets friction its model
lacks, does not know the onset and works on filtered equations, so it cannot reach it exactly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ndtri  # the normal quantile (scipy.stats.norm.ppf's), without importing stats

from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import TABLE2
from adaptive_dd.identification.fisher import SIGNALS, output_variances
from adaptive_dd.identification.sensitivity import chain_sensitivities, local_sensitivities
from adaptive_dd.plant.parameters import validate_sigma

__all__ = ["detection_threshold", "two_link_detection_limit"]


def detection_threshold(n_tests: int, rate: float = 0.01, prob: float = 0.5) -> float:
    """``z_(1 - alpha / 2) + z_p`` with ``alpha = rate / n_tests``: the ``sqrt(lambda)`` a GLR on one
    parameter needs to detect with probability ``prob`` at ``rate`` false alarms over ``n_tests``."""
    if not (n_tests >= 1 and 0 < rate < 1 and 0 < prob < 1):
        raise ParameterError(f"need n_tests >= 1, 0 < rate < 1, 0 < prob < 1; got {n_tests}, {rate}, {prob}")
    alpha = rate / n_tests
    return float(-ndtri(alpha / 2) + ndtri(prob))  # norm.isf(alpha / 2) + norm.ppf(prob)


def two_link_detection_limit(
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    k_swap: int,
    sample_period: float,
    sigma_after: ArrayLike,
    payload_direction: ArrayLike,
    delta_mass: float,
    position_variance: ArrayLike = TABLE2["position_variance"],
    velocity_variance: ArrayLike = TABLE2["velocity_variance"],
    *,
    n_tests: int,
    rate: float = 0.01,
    prob: float = 0.5,
    substeps: int = 2,
) -> float | None:
    """Time [s] after a swap at which the optimal GLR detects it (module docstring).

    Parameters
    ----------
    q, qd : array_like (N, 2)
        Recorded *true* trajectory (e.g. the oracle's), [rad], [rad/s].
    tau : array_like (N, 2)
        Applied torque [N m].
    k_swap : int
        First sample with the new payload.
    sample_period : float
        T [s].
    sigma_after : array_like (7,)
        Base parameters after the swap.
    payload_direction : array_like (7,)
        ``d sigma / d m`` [per kg].
    delta_mass : float
        ``|m_after - m_before|`` [kg], > 0.
    position_variance, velocity_variance : array_like (2,)
        Sensor noise.
    n_tests : int
        Tests a trial makes (its number of samples).
    rate, prob : float
        False alarms per trial; detection probability.

    Returns
    -------
    float or None
        Seconds after the swap, None if the record ends first.
    """
    if not delta_mass > 0:
        raise ParameterError(f"delta_mass must be > 0 kg, got {delta_mass!r}")
    q, qd, tau = (np.asarray(x, dtype=float) for x in (q, qd, tau))
    n = q.shape[0]
    if not 0 <= k_swap < n - 1:
        raise ParameterError(f"k_swap must lie in [0, {n - 2}] for a record of {n} samples, got {k_swap}")
    sg = validate_sigma(sigma_after)
    w = 1.0 / output_variances(position_variance, velocity_variance, SIGNALS)
    a, _, p = local_sensitivities(q[k_swap:], qd[k_swap:], tau[k_swap:], sg, sample_period, substeps)
    s = chain_sensitivities(a, p @ np.asarray(payload_direction, float)[:, None])[..., 0]
    info = np.cumsum(np.einsum("ki,i,ki->k", s, w, s))
    need = detection_threshold(n_tests, rate, prob)
    hit = np.flatnonzero(delta_mass * np.sqrt(info) >= need)
    return None if hit.size == 0 else float(hit[0] * sample_period)
