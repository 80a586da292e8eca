"""The bound's quantile: the fixed-b bandwidth fraction from the scores' changing level and the
residual's correlation (:func:`adaptive_dd.identification.log_covariance.bandwidth_fraction`)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from adaptive_dd.identification.log_covariance import bandwidth_fraction, newey_west_parts


def _relative_variances(level, rng, draws=300, a=0.9):
    """Over ``draws`` records of AR(``a``) noise of level ``level (N,)`` fitted by a constant and a slow
    sine: the Newey-West variance's relative variance (mean over the two parameters), and the mean
    ``(4 / 3) b`` of :func:`bandwidth_fraction` and of the lag's ``(lag + 1) / N``."""
    N = level.size
    t = np.arange(N)
    phi = np.stack([np.ones(N), np.sin(2 * np.pi * t / 1300)], axis=1)[:, None, :]
    V, b, lagb = [], [], []
    for _ in range(draws):
        e = level * scipy.signal.lfilter([1.0], [1.0, -a], rng.standard_normal(N))
        x = np.linalg.lstsq(phi[:, 0], e, rcond=None)[0]
        res = (e - phi[:, 0] @ x)[:, None]
        cov, lag, influence = newey_west_parts(phi, res, np.ones(1), np.ones(2))
        V.append(np.diag(cov))
        b.append(bandwidth_fraction(influence, res[:, 0], lag))
        lagb.append((lag + 1) / N)
    V = np.array(V)
    return np.mean(V.var(axis=0) / V.mean(axis=0) ** 2), 4 / 3 * np.mean(b), 4 / 3 * np.mean(lagb)


def test_bandwidth_fraction_follows_the_variance_s_own_spread():
    """Planted AR(0.9) records of 4000 rows, 300 draws: the Newey-West variance's relative variance is
    about ``(4 / 3) b``, ``b`` the fixed-b bandwidth fraction the bound's quantile takes. On a steady
    record :func:`bandwidth_fraction` says a little less than the draws show (the lag's own
    randomness is not in it), the lag's fraction ``(lag + 1) / N`` less still (the residual's
    correlation reaches over the lag); on a record whose noise comes in bursts (level 1 a quarter
    of the time, 0.15 the rest: a few hundred rows carry the variance) the variance is more than
    twice as variable, which :func:`bandwidth_fraction` follows and the lag's fraction (what the
    quantile took before) misses by a factor above 3."""
    rng = np.random.default_rng(3)
    t = np.arange(4000)
    observed, predicted, lag_only = _relative_variances(np.ones(t.size), rng)
    assert 0.5 * observed < predicted < 1.3 * observed, (observed, predicted)
    assert predicted > 1.3 * lag_only, (predicted, lag_only)
    level = np.where((t // 500) % 4 == 0, 1.0, 0.15)
    observed_b, predicted_b, lag_only_b = _relative_variances(level, rng)
    assert observed_b > 2 * observed
    assert 0.6 * observed_b < predicted_b < 1.3 * observed_b, (observed_b, predicted_b)
    assert lag_only_b < observed_b / 3, (observed_b, lag_only_b)


def test_bandwidth_fraction_of_white_steady_scores_is_the_lag_s():
    """White scores of a steady level: ``b`` is the lag's fraction ``(lag + 1) / N`` of the rows, as
    Kiefer and Vogelsang's fixed-b theory has it, on one record and on three pieces; at most 1."""
    rng = np.random.default_rng(4)
    N, lag = 20000, 30
    u = rng.standard_normal(N)
    influence = u[:, None] * np.array([1.0, -2.0])
    assert bandwidth_fraction(influence, u, lag) == pytest.approx((lag + 1) / N, rel=0.1)
    pieces = [(0, 5000), (5000, 12000), (12000, N)]
    assert bandwidth_fraction(influence, u, lag, pieces) == pytest.approx((lag + 1) / N, rel=0.1)
    assert bandwidth_fraction(influence[:40], u[:40], 30) == 1.0
