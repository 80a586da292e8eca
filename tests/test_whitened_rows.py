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
from adaptive_dd.identification.filters import filter_record
from adaptive_dd.identification.online import (
    OnlineConfig,
    derived_row_weights,
    est_init,
    est_work,
    row_floors,
    run_online,
    whitening_noise,
    whitening_scale,
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
    cfg = OnlineConfig(mode=mode, lam0=1.0, detector=None, whiten=True, row_floor="none")
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


# ------------------------------------------------------------------------ the rows' floors
@pytest.mark.parametrize("floor", ["stated", "level"])
def test_a_floor_adds_to_each_rows_variance_in_the_batch_update(ur5, floor):
    """With a floor, one sample's whitened updates are the batch Kalman update with the covariance
    ``M diag(vn^2) M^T + D`` over the rows in use: ``D`` the stated floor (``(floor w_j)^2`` N m^2
    over the whitening's scale), or each row's variance raised to the detector's learnt level (read
    from its state: the long-run average once learnt, the level of before an alarm while it
    re-learns)."""
    rng = np.random.default_rng(7)
    cfg = OnlineConfig(lam0=1.0, whiten=True, row_floor=floor)
    c, s = est_init(cfg, ur5, 1)
    n, p = 6, s.theta.shape[1]
    q = rng.uniform(-1.5, 1.5, size=n)
    phi = rng.normal(size=(n, p))
    y = rng.normal(size=n) * 3.0
    act = np.ones(n, dtype=np.bool_)
    wts = derived_row_weights(ur5)
    scale = whitening_scale(cfg, ur5)
    level = np.array([0.08, 0.3, 0.06, 0.2, 0.5, 0.05]) ** 2  # the detector's, of e_j / w_j
    if floor == "level":  # rows 0-3 learnt since the last alarm, rows 4-5 re-learning (their ref)
        a_l = c.floats[K.F_ALPHA_LONG]
        nl = 500
        s.learned[0, :4] = nl
        s.long[0, :4] = level[:4] * (1.0 - (1.0 - a_l) ** nl)
        s.learned[0, 4:] = 3
        s.long[0, 4:] = 1e3  # not yet trusted: not read
        s.ref[0, 4:] = level[4:]
    th0, P0 = s.theta[0].copy(), s.P[0].copy()
    w = est_work(n, p)
    assert not K._whitened_update(c, s, 0, q, phi, y, act, n, w)
    M = ur5.mass_matrix(q)
    R = (M * c.vn**2) @ M.T
    if floor == "stated":
        D = (c.floats[K.F_FLOOR2] ** 0.5 * wts) ** 2 / scale
        assert np.allclose(np.sqrt(D * scale), 0.05 * wts)
        R = R + np.diag(D)
    else:  # each row's variance at least its level, in N m^2 over the scale
        want = np.maximum(np.diag(R), level * wts**2 / scale)
        R = R + np.diag(want - np.diag(R))
        assert np.any(np.diag(R) > (M * c.vn**2 @ M.T).diagonal() * 1.5)  # some row was raised
    gain = np.linalg.solve(phi @ P0 @ phi.T + R, phi @ P0).T
    tha = th0 + gain @ (y - phi @ th0)
    assert np.allclose(s.theta[0], tha, rtol=1e-6, atol=1e-8 * np.abs(tha).max())
    assert np.allclose(s.P[0], P0 - gain @ phi @ P0, rtol=1e-5, atol=1e-8 * np.abs(P0).max())


def test_the_whitening_scale_is_the_noise_the_momentum_form_sees(ur5):
    """:func:`whitening_scale` turns the whitening's covariance into N m^2: the largest velocity
    noise variance times the filters' ``G1`` power gain (the sum of its squared impulse response)
    times the largest nominal inertia squared."""
    cfg = OnlineConfig(whiten=True)
    imp = np.zeros(4_000)
    imp[0] = 1.0
    g1 = np.sum(filter_record(cfg.bank, imp)[:, 1] ** 2)
    var = np.max(ur5.sensor.velocity_variance)
    assert np.isclose(whitening_scale(cfg, ur5), var * g1 * np.max(ur5.nominal_inertia()) ** 2, rtol=1e-9)
    vfloor, vlevel = row_floors(OnlineConfig(whiten=True, row_floor="none"), ur5)
    assert not vfloor.any() and not vlevel.any()
    with pytest.raises(Exception, match="row_floor"):
        OnlineConfig(row_floor="max")
    with pytest.raises(Exception, match="row_floor = 'level' reads the detector"):
        OnlineConfig(row_floor="level", detector=None)
    assert OnlineConfig().row_floor == OnlineConfig(detector=None).row_floor == "stated"


def test_the_floor_bounds_the_trust_in_a_nearly_noise_free_wrist(ur5):
    """The creeping-wrist record of ``tests/test_online.py`` (its wrist rows nearly noise-free: the
    UR5's URDF wrist carries 1e-4 to 4e-3 kg m^2), 1 kg -> 2.5 kg at 3 s: whitened with no floor
    the estimate trusts the wrist's rows beyond their equation error (the centre of mass 9 cm off
    250 ms after the swap; before the detector's kept level rose with the payload's noise,
    ``_ref_rise``, also a second alarm 0.24 s after the swap); with the floor (learnt level or
    stated) one alarm and the centre of mass within 2 cm 250 ms after the swap."""
    from test_online import PAY_A, PAY_B, _com, _slow_wrist_record

    r = _slow_wrist_record(ur5, 3, 4_000, [PAY_A, PAY_B], [3_000])
    out = {}
    for floor in ("none", "stated", "level"):
        rec = run_online(ur5, OnlineConfig(whiten=True, row_floor=floor), r.q_meas, r.qd_meas, r.tau)
        out[floor] = (rec.alarm_times()[0], np.linalg.norm(rec.com[0, 3_250] - _com(PAY_B)))
    assert out["none"][1] > 0.05, out  # the failure the floor fixes
    for floor in ("stated", "level"):
        (alarms, err) = out[floor]
        assert len(alarms) == 1 and 3.0 <= alarms[0] < 3.05 and err < 0.02, (floor, out[floor])
