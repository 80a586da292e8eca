"""The N-joint detector judges each row's prior error against its level plus the variance the
estimate's covariance predicts for it (``online_detector._prior_variance``, ``EstState.pvar``;
``docs/change_detection.md``, "The estimate's own uncertainty"). The identity that recovers
``phi^T P phi`` from the update's scratch, and the detector alone on synthetic prior errors
(``est_detect_trial``) with a row that comes back into use after an alarm."""

import numpy as np
import pytest

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import (
    OnlineConfig,
    est_detect_trial,
    est_force_alarm_trial,
    est_init,
)
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


@pytest.mark.parametrize("p", [10, 40])
@pytest.mark.parametrize("scale", [1e-4, 1.0, 300.0])
@pytest.mark.parametrize("lam", [1.0, 0.999])
def test_the_prior_variance_is_phi_p_phi_before_the_update(p, scale, lam):
    """``_prior_variance`` of what ``_rls_row`` leaves in its scratch is ``phi^T P phi`` of the
    covariance before the update, whatever its size and the forgetting factor (a row with zeros,
    as the payload's rows have)."""
    rng = np.random.default_rng(p)
    A = rng.standard_normal((p, p))
    P = scale * (A @ A.T) / p
    phi = rng.standard_normal(p)
    phi[::3] = 0.0
    expect = phi @ P @ phi
    g, nz = np.zeros(p), np.zeros(p, dtype=np.int64)
    eps = K._rls_row(np.zeros(p), P.copy(), phi, 1.0, lam, g, nz)
    assert np.isfinite(eps)
    assert K._prior_variance(phi, g, lam) == pytest.approx(expect, rel=1e-12)
    assert K._prior_variance(np.zeros(p), np.zeros(p), lam) == 0.0


def _replay(arm, eps, act, pvar, alarm_at):
    """The default detector over prior errors ``eps``, rows in use ``act`` and predicted variances
    ``pvar`` (each (n_samples, n)), every joint moving, an alarm forced at sample ``alarm_at``
    (the swap's): the samples at which it alarmed."""
    c, s = est_init(OnlineConfig(), arm, 1)
    s.since_crawl[:] = K.BIG
    alarms = []
    for k in range(eps.shape[0]):
        s.pvar[0] = pvar[k]
        if est_detect_trial(c, s, 0, eps[k], act[k]):
            alarms.append(k)
        if k == alarm_at:
            est_force_alarm_trial(c, s, 0)
    return alarms


def _row_back_in_use(n, seed=0):
    """Unit noise on every row; an alarm at 2 s; row 3 out of use from 0.1 s before it to 0.3 s
    after it (a slow joint), back with one error of 40x its RMS while the covariance along its
    regressor is still the re-opened prior's (``phi^T P phi`` 200, then 1 / k: random:108 at
    8.3 s, ``docs/changelog.md``); the others' 0.003."""
    N, alarm_at, back = 3_000, 2_000, 2_300
    rng = np.random.default_rng(seed)
    eps = rng.standard_normal((N, n))
    act = np.ones((N, n), dtype=np.bool_)
    act[alarm_at - 100 : back, 3] = False
    eps[back, 3] = 40.0
    pvar = np.full((N, n), 0.003)
    pvar[back:, 3] = 200.0 / (1.0 + 200.0 * np.arange(N - back))
    return eps, act, pvar, alarm_at, back


def test_a_row_back_in_use_after_an_alarm_is_judged_with_the_estimates_uncertainty(ur5):
    """The row back in use after the swap's alarm: no second alarm with the predicted variance;
    judged against its noise level alone (the predicted variance left out), an alarm at the
    sample it comes back."""
    eps, act, pvar, alarm_at, back = _row_back_in_use(ur5.n_joints)
    assert _replay(ur5, eps, act, pvar, alarm_at) == []
    assert _replay(ur5, eps, act, np.zeros_like(pvar), alarm_at) == [back]


def test_a_change_along_the_row_back_in_use_is_still_detected(ur5):
    """The same row, then an error of 8x its RMS that persists from 0.1 s after it is back (the
    estimate's variance along it by then 0.005): an alarm within the short average's rise."""
    eps, act, pvar, alarm_at, back = _row_back_in_use(ur5.n_joints)
    start = back + 100
    eps[start:, 3] += 8.0
    alarms = _replay(ur5, eps, act, pvar, alarm_at)
    assert len(alarms) >= 1 and start <= alarms[0] <= start + 40, alarms


def test_a_steady_predicted_variance_leaves_the_detector_as_it_was(ur5):
    """The level learns the squared errors, which hold the predicted variance of their time: a
    row's predicted variance that stays where it was while the level learnt adds nothing. The same
    errors (unit noise, then a step of 6x on row 0 at 2.5 s) with a steady 3 on every row alarm at
    the same sample as with none; a predicted variance that rises to 3 with the step (not learnt
    by the level) raises the threshold: a later alarm, or none."""
    n, N, start = ur5.n_joints, 3_000, 2_500
    eps = np.random.default_rng(1).standard_normal((N, n))
    eps[start:, 0] += 6.0
    act = np.ones((N, n), dtype=np.bool_)
    none = _replay(ur5, eps, act, np.zeros((N, n)), alarm_at=None)
    assert len(none) == 1 and start <= none[0] <= start + 40, none
    assert _replay(ur5, eps, act, np.full((N, n), 3.0), alarm_at=None) == none
    late = _replay(ur5, eps, act, np.concatenate((np.zeros((start, n)), np.full((N - start, n), 3.0))), None)
    assert late == [] or late[0] > none[0], late
