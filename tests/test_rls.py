"""Recursive least squares (eq. 14) against batch least squares and filterpy."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.kalman import KalmanParameterEstimator
from adaptive_dd.identification.rls import (
    RecursiveLeastSquares,
    RLSConfig,
    batch_least_squares,
    rls_init,
    rls_step,
)


def regression(rng, n=400, p=4, noise=0.1):
    phi = rng.normal(size=(n, p))
    theta = rng.normal(size=p)
    return phi, phi @ theta + noise * rng.normal(size=n), theta


def test_rls_with_lambda_one_equals_batch_least_squares(rng):
    phi, y, _ = regression(rng)
    cfg = RLSConfig(lam0=1.0, mu=0.0, p0=50.0, max_trace=1e12)
    est = RecursiveLeastSquares(4, cfg)
    for k in range(len(y)):
        est.update(phi[k], y[k])
    ref = batch_least_squares(phi, y, ridge=1 / cfg.p0)
    np.testing.assert_allclose(est.theta, ref, rtol=1e-8)
    # with a weak prior the regularised solution is the plain least-squares one
    np.testing.assert_allclose(ref, np.linalg.lstsq(phi, y, rcond=None)[0], rtol=1e-3)
    np.testing.assert_allclose(est.P, np.linalg.inv(phi.T @ phi + np.eye(4) / cfg.p0), rtol=1e-8)


def test_batched_rls_equals_one_by_one(rng):
    phi = rng.normal(size=(3, 200, 4))
    y = rng.normal(size=(3, 200))
    cfg = RLSConfig()
    s = rls_init(4, cfg, (3,))
    for k in range(200):
        s, _ = rls_step(s, phi[:, k], y[:, k], cfg)
    for b in range(3):
        e = RecursiveLeastSquares(4, cfg)
        for k in range(200):
            e.update(phi[b, k], y[b, k])
        np.testing.assert_allclose(s.theta[b], e.theta, rtol=1e-12)


@pytest.mark.parametrize("lam0, mu", [(0.98, 0.0), (0.98, 0.01)])
def test_rls_with_forgetting_equals_filterpy_fading_memory(rng, lam0, mu):
    """Eq. (14) == Kalman filter with F = I, Q = 0, R = 1 and alpha = 1/sqrt(lambda(t))."""
    phi, y, _ = regression(rng, n=300)
    cfg = RLSConfig(lam0=lam0, mu=mu, p0=10.0, max_trace=1e12)
    est = RecursiveLeastSquares(4, cfg)
    kf = KalmanFilter(dim_x=4, dim_z=1)
    kf.x, kf.F, kf.Q, kf.R, kf.P = np.zeros(4), np.eye(4), np.zeros((4, 4)), np.eye(1), 10.0 * np.eye(4)
    lam = lam0
    for k in range(len(y)):
        est.update(phi[k], y[k])
        lam = (1 - mu) * lam + mu
        kf.alpha = 1 / np.sqrt(lam)
        kf.predict()
        kf.update(np.array([y[k]]), H=phi[k][None])
    np.testing.assert_allclose(est.theta, kf.x, rtol=1e-8)
    np.testing.assert_allclose(est.P, kf.P, rtol=1e-8)


def test_kalman_estimator_with_q_zero_is_rls_with_lambda_one(rng):
    phi = rng.normal(size=(200, 2, 3))
    y = phi @ np.array([1.0, -2.0, 0.5]) + 0.01 * rng.normal(size=(200, 2))
    kal = KalmanParameterEstimator(3, 2, q=0.0, p0=100.0).run(phi, y)[-1]
    ref = batch_least_squares(phi.reshape(-1, 3), y.reshape(-1), ridge=1 / 100.0)
    np.testing.assert_allclose(kal, ref, rtol=1e-8)


def test_non_finite_samples_are_skipped_and_counted(rng):
    phi, y, _ = regression(rng, n=50)
    cfg = RLSConfig()
    s = rls_init(4, cfg)
    for k in range(20):
        s, _ = rls_step(s, phi[k], y[k], cfg)
    before = s
    for bad_phi, bad_y in ((phi[20] * np.nan, y[20]), (phi[21], np.inf), (phi[22], np.nan)):
        s, info = rls_step(s, bad_phi, np.asarray(bad_y), cfg)
        assert info["skipped"]
    np.testing.assert_array_equal(s.theta, before.theta)
    np.testing.assert_array_equal(s.P, before.P)
    assert s.lam == before.lam and s.n_skipped == 3
    assert np.all(np.isfinite(s.P))


def test_covariance_stays_spd_and_bounded_at_rest(rng):
    """lambda < 1 and no excitation: P would grow as lambda^-t without the trace cap."""
    cfg = RLSConfig(lam0=0.98, mu=0.0, p0=10.0)
    s = rls_init(3, cfg)
    for _k in range(200):
        s, _ = rls_step(s, rng.normal(size=3), np.asarray(1.0), cfg)
    for _ in range(20_000):  # arm at rest: phi = 0
        s, _ = rls_step(s, np.zeros(3), np.asarray(0.0), cfg)
    assert np.trace(s.P) <= 3 * cfg.p0 * (1 + 1e-12)
    np.testing.assert_allclose(s.P, s.P.T)
    assert np.linalg.eigvalsh(s.P).min() > 0
    # without the cap it really would blow up
    raw = RLSConfig(lam0=0.98, mu=0.0, p0=10.0, max_trace=1e300)
    s2 = rls_init(3, raw)
    for _ in range(2_000):
        s2, _ = rls_step(s2, np.zeros(3), np.asarray(0.0), raw)
    assert np.trace(s2.P) > 1e15


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"lam0": 0.0}, "lam0"),
        ({"lam0": 1.5}, "lam0"),
        ({"mu": -0.1}, "mu"),
        ({"mu": 2.0}, "mu"),
        ({"p0": 0.0}, "p0"),
        ({"max_trace": -1.0}, "max_trace"),
    ],
)
def test_bad_rls_config(kw, match):
    with pytest.raises(ParameterError, match=match):
        RLSConfig(**kw)


def test_kalman_fading_memory_does_not_wind_up_unexcited():
    """RLS's trace cap on the Kalman form: 20 s of zero regressor (an arm at rest) under
    alpha = 1/sqrt(0.99) grew P as 0.99^-k to 1e87 (NaN after 75 s); capped, it stays at n p0 and
    the next excitation is used."""
    kf = KalmanParameterEstimator(7, 2, alpha=1 / np.sqrt(0.99))
    phi = np.random.default_rng(0).standard_normal((2, 7))
    theta = np.arange(1, 8.0)
    for _ in range(200):
        kf.update(phi, phi @ theta)
    for _ in range(20000):
        kf.update(np.zeros((2, 7)), np.zeros(2))
    assert np.trace(kf.P) <= 7 * 100.0 * (1 + 1e-12)
    kf.update(phi, phi @ theta)
    assert np.all(np.isfinite(kf.theta)) and np.all(np.isfinite(kf.P))


def test_kalman_random_walk_is_filterpys_without_fading_memory():
    """The trace cap applies to fading memory only: with Q > 0 and alpha 1 the random-walk filter's
    covariance is filterpy's own (capped, trace 3.0 where filterpy's was 21.4)."""
    kf = KalmanParameterEstimator(3, 1, q=5.0, p0=1.0)
    ref = KalmanFilter(dim_x=3, dim_z=1)
    ref.F, ref.Q, ref.R, ref.P, ref.x = np.eye(3), 5.0 * np.eye(3), np.eye(1), np.eye(3), np.zeros(3)
    phi = np.random.default_rng(1).standard_normal((50, 1, 3))
    for k in range(50):
        kf.update(phi[k], np.zeros(1))
        ref.predict()
        ref.update(np.zeros(1), H=phi[k])
    np.testing.assert_allclose(kf.P, ref.P, rtol=1e-10)
