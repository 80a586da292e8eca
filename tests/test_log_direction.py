"""The sandwich's small-sample correction per direction (adaptive_dd.identification.log_covariance)."""

from __future__ import annotations

import numpy as np
import pytest


def _regression(N: int = 1500):
    """Two channels: a column that barely moves (it trades with channel 0's offset), three that do,
    and a constant offset per channel; two pieces."""
    t = np.arange(N) * 0.01
    phi = np.zeros((N, 2, 6))
    phi[:, 0, 0] = 1.0 + 0.1 * np.sin(0.3 * t)
    phi[:, 0, 1] = np.sin(2.1 * t)
    phi[:, 1, 2] = np.cos(1.3 * t)
    phi[:, 1, 3] = np.sin(0.2 * t)
    phi[:, 0, 4] = phi[:, 1, 5] = 1.0
    return t, phi, [(0, 700), (700, N)]


def test_the_expected_sandwich_predicts_the_newey_west_bias_per_direction():
    """AR(1) errors of coefficient 0.9 whose level changes over the record: over 400 draws the
    Newey-West variance falls short of the estimates' spread by 20-50 % per parameter, most on the
    column that trades with an offset and on the offsets. The working model (an autoregression of the
    residual, its level smoothed) from one draw predicts the truth ``D`` and the sandwich's mean ``E``
    within 15 %, and the correction ``M`` (``M E M^T = D``) brings the mean variance within 12 % of
    the spread along every parameter and along a combination of them."""
    import scipy.signal

    from adaptive_dd.identification.log_covariance import (
        direction_correction,
        expected_sandwich,
        newey_west,
    )

    rng = np.random.default_rng(3)
    t, phi, bounds = _regression()
    N, m, k = phi.shape
    X = phi.reshape(-1, k)
    scale = np.linalg.norm(X, axis=0)
    w = np.ones(m)
    level = (1.0 + 0.5 * np.abs(np.sin(0.5 * t)))[:, None]
    est, covs, corrected, predicted = [], [], [], []
    for it in range(400):
        z = rng.standard_normal((N, m)) * np.sqrt(1 - 0.81)
        e = level * scipy.signal.lfilter([1.0], [1.0, -0.9], z, axis=0)
        x = np.linalg.lstsq(X, e.reshape(-1), rcond=None)[0]
        res = e - phi @ x
        cov, lag = newey_west(phi, res, w, scale, bounds)
        cs = cov * np.outer(scale, scale)  # the scaled columns' covariance
        xs = phi / scale
        if it < 40:  # the working model's prediction on 40 draws (its cost)
            D, E = expected_sandwich(xs, xs, res, lag, bounds)
            M = direction_correction(D, E)
            corrected.append(np.diag(M @ cs @ M.T))
            predicted.append(np.diag(D) / np.diag(E))
        est.append(x * scale)
        covs.append(np.diag(cs))
    est, covs = np.array(est), np.array(covs)
    spread = est.var(axis=0)
    ratio = spread / covs.mean(axis=0)
    assert np.all(ratio > 1.15) and ratio[0] > 1.35 and ratio[4] > 1.35, ratio
    print(ratio, np.mean(predicted, axis=0), np.mean(corrected, axis=0) / spread)
    np.testing.assert_allclose(np.mean(predicted, axis=0) / ratio, 1.0, atol=0.15)
    np.testing.assert_allclose(np.mean(corrected, axis=0) / spread, 1.0, atol=0.15)


def test_direction_correction_matches_every_direction_and_never_shrinks():
    """``M E M^T = D`` when ``D >= E``; a direction where ``D < E`` is left as it is (the ratio held
    at 1), as is one outside ``E``'s range; ``matrix=False`` scales each parameter alone."""
    from adaptive_dd.identification.log_covariance import direction_correction

    rng = np.random.default_rng(0)
    B = rng.standard_normal((4, 4))
    E = B @ B.T + 0.1 * np.eye(4)
    C = rng.standard_normal((4, 4))
    D = E + 0.2 * C @ C.T  # D >= E in every direction (by less than the cap, 4)
    M = direction_correction(D, E)
    np.testing.assert_allclose(M @ E @ M.T, D, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(direction_correction(0.5 * E, E), np.eye(4), atol=1e-10)
    Md = direction_correction(D, E, matrix=False)
    np.testing.assert_allclose(np.diag(Md @ E @ Md.T), np.diag(D), rtol=1e-10)
    E0 = np.diag([1.0, 2.0, 0.0])
    M0 = direction_correction(np.diag([2.0, 2.0, 0.0]), E0)
    np.testing.assert_allclose(M0 @ E0 @ M0.T, np.diag([2.0, 2.0, 0.0]), atol=1e-12)
    assert M0[2, 2] == pytest.approx(1.0)
