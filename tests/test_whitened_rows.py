"""The N-joint estimator's rows whitened by the velocity noise they share through the inertia
(``OnlineConfig.whiten``, :func:`~adaptive_dd.identification.online_kernel._whitened_update`).

One sample's whitened updates equal the batch Kalman update of the rows in use with the error
covariance ``M diag(vn^2) M^T`` over them (a row out of use contributes nothing, whatever its
value); the detector's errors are each row's own prior error over its weight. Whitening is an
option, off by default (``docs/any_arm.md``, "The Gen3's wrist").
"""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import (
    OnlineConfig,
    derived_row_weights,
    est_init,
    est_work,
    whitening_noise,
)
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def test_whitening_is_an_option_off_by_default(ur5):
    assert OnlineConfig().whiten is False
    assert OnlineConfig(row_weights=(1.0,) * 6, whiten=True).whiten is True
    c, _ = est_init(OnlineConfig(whiten=True), ur5, 1)
    assert c.vn.shape == (6,) and np.all(c.vn > 0)
    c, _ = est_init(OnlineConfig(), ur5, 1)
    assert c.vn.shape == (0,)
    with pytest.raises(Exception, match="whiten"):
        OnlineConfig(whiten="yes")


def test_the_whitening_scale_keeps_the_heaviest_row_in_newton_metres(ur5):
    vn = whitening_noise(ur5)
    assert np.allclose(vn, 1.0 / np.max(ur5.nominal_inertia()))  # the same noise on every joint


@pytest.mark.parametrize("mode", ["payload", "arm"])
@pytest.mark.parametrize("out_of_use", [None, 2])
def test_one_sample_of_whitened_rows_is_the_batch_update_with_their_joint_covariance(ur5, mode, out_of_use):
    rng = np.random.default_rng(5)
    cfg = OnlineConfig(mode=mode, lam0=1.0, detector=None, whiten=True)
    c, s = est_init(cfg, ur5, 1)
    n, p = 6, s.theta.shape[1]
    s.theta[0] = rng.normal(size=p) * 0.1
    A = rng.normal(size=(p, p)) * 0.05
    s.P[0] = s.P[0] + A @ A.T  # a covariance with correlations
    th0, P0 = s.theta[0].copy(), s.P[0].copy()
    q = rng.uniform(-1.5, 1.5, size=n)
    phi = rng.normal(size=(n, p))
    y = rng.normal(size=n) * 3.0
    act = np.ones(n, dtype=np.bool_)
    if out_of_use is not None:
        act[out_of_use] = False
        y[out_of_use] = 1e6  # never read
    w = est_work(n, p)
    assert not K._whitened_update(c, s, 0, q, phi, y, act, n, w)  # rows were used
    use = np.flatnonzero(act)
    M = ur5.mass_matrix(q)
    R = (M * c.vn**2) @ M.T
    Ra = R[np.ix_(use, use)]
    H = phi[use]
    gain = np.linalg.solve(H @ P0 @ H.T + Ra, H @ P0).T  # the Kalman gain of the rows at once
    tha = th0 + gain @ (y[use] - H @ th0)
    Pa = P0 - gain @ H @ P0
    assert np.allclose(s.theta[0], tha, rtol=1e-6, atol=1e-8 * np.abs(tha).max())
    assert np.allclose(s.P[0], Pa, rtol=1e-5, atol=1e-8 * np.abs(Pa).max())
    assert not np.allclose(s.theta[0], th0, rtol=1e-3)  # it did move
    # the detector's errors: each row's own prior error over its weight; NaN out of use
    wts = derived_row_weights(ur5)
    assert np.allclose(s.eps[0, use], (y[use] - phi[use] @ th0) / wts[use], rtol=1e-12)
    if out_of_use is not None:
        assert np.isnan(s.eps[0, out_of_use])


def test_no_row_in_use_changes_nothing(ur5):
    c, s = est_init(OnlineConfig(lam0=0.999, whiten=True), ur5, 1)
    th0, P0, lam0 = s.theta[0].copy(), s.P[0].copy(), s.lam[0]
    w = est_work(6, 10)
    assert K._whitened_update(c, s, 0, np.zeros(6), np.ones((6, 10)), np.ones(6), np.zeros(6, np.bool_), 6, w)
    assert np.array_equal(s.theta[0], th0) and np.array_equal(s.P[0], P0) and s.lam[0] == lam0
