"""The N-joint detector's level follows the posture (``online_detector._posture_noise``,
``EstState.nvar``; ``docs/change_detection.md``, "The level follows the posture").

A row's noise is the measured velocity's through the inertia the row carries, ``G1 (M v)``, and a
base joint's inertia grows with the arm's reach, squared. The level a row learnt over the last
second is too low where the arm reaches further than it did then: on fifty drawn arms the base
row's noise rose 3.1-3.5x over its level within 20 ms at each of five false alarms. The detector
now adds to the level what the posture adds to the row's noise over the postures it was learnt at.
"""

import numpy as np
import pytest
from detector_steps import detector_sample
from scipy.signal import lfilter

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import OnlineConfig, est_init, est_step
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf

POSTURE = np.array([0.0, -1.2, 1.2, -1.5, -1.5, 0.0])


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


@pytest.mark.parametrize("mode", ["payload", "arm"])
def test_the_posture_noise_is_the_velocity_noise_through_the_inertia_and_the_filter(ur5, mode):
    """``nvar_j = gain (M V M^T)_jj / w_j^2`` after a step of the estimator at ``q``: ``M`` the arm's
    own mass matrix (armature included; the step builds it from what its momentum form left in its
    scratch, in either mode), ``V`` the sensor's velocity noise, ``gain`` the sum of the squared
    impulse response of the bank's ``G1`` (here from its transfer function, not the realisation the
    kernel runs), ``w`` the row weights. An outstretched arm's base row carries more than a folded
    one's."""
    cfg = OnlineConfig(mode=mode)
    c, s = est_init(cfg, ur5, 1)
    n = ur5.n_joints
    bank = cfg.bank
    impulse = np.zeros(20_000)
    impulse[0] = 1.0
    gain = float(np.sum(lfilter(bank.num[1], bank.den[1], impulse) ** 2))
    V = np.asarray(ur5.sensor.velocity_variance, dtype=float)
    qd, tau = np.full((1, n), 0.3), np.zeros((1, n))
    outstretched = np.array([0.0, 0.0, 0.0, -1.5, -1.5, 0.0])
    for q in (POSTURE, outstretched):
        est_step(c, s, q[None], qd, tau)
        M = ur5.mass_matrix(q)
        expect = gain * np.diag((M * V) @ M.T) / c.w**2
        assert np.allclose(s.nvar[0], expect, rtol=1e-6), (s.nvar[0], expect)
    est_step(c, s, POSTURE[None], qd, tau)
    folded = s.nvar[0, 0]
    est_step(c, s, outstretched[None], qd, tau)
    assert s.nvar[0, 0] > 2.0 * folded


def _drive(c, s, eps_of, nvar_of, k1, tell=True):
    """The detector over samples ``0 .. k1 - 1``, every row in use and moving, the rows' prior
    errors ``eps_of(k)``; ``nvar_of(k)`` the posture's noise, set as the step's
    ``_posture_noise`` would (``tell=False``: kept at its first value, the detector not told of the
    posture: the fault). The alarm samples."""
    n = s.eps.shape[1]
    act = np.ones(n, dtype=np.bool_)
    s.since_crawl[0, :] = K.BIG
    hits = []
    for k in range(k1):
        s.nvar[0] = nvar_of(k if tell else 0)
        if detector_sample(c, s, eps_of(k), act):
            hits.append(k)
    return hits


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_reach_that_raises_a_rows_noise_raises_no_alarm_and_a_change_is_still_found(ur5, seed):
    """Unit noise on every row, all of it the posture's; over 20 ms at 3 s a reach raises row 0's
    variance 12x (its inertia 3.5x) and holds it for 0.3 s. No alarm; with the detector not told
    of the posture (the fault) the single-sample test trips on row 0 as the reach rises. An error
    6x the raised noise on row 0 during the reach is found within 30 ms."""
    n = ur5.n_joints
    rng = np.random.default_rng(seed)
    k_rise, k_end = 3_000, 3_320
    noise = rng.standard_normal((k_end, n))

    def part(k):  # each row's noise variance, all of it the posture's
        v = np.ones(n)
        v[0] += 11.0 * np.clip((k - k_rise) / 20.0, 0.0, 1.0)
        return v

    def eps(k):
        return noise[k] * np.sqrt(part(k))

    c, s = est_init(OnlineConfig(), ur5, 1)
    assert _drive(c, s, eps, part, k_end) == []
    c, s = est_init(OnlineConfig(), ur5, 1)
    hits = _drive(c, s, eps, part, k_end, tell=False)
    assert hits and k_rise <= hits[0] < k_rise + 100, hits
    c, s = est_init(OnlineConfig(), ur5, 1)
    k_change = k_rise + 150

    def changed(k):
        e = eps(k)
        if k >= k_change:
            e[0] += 6.0 * np.sqrt(part(k)[0])
        return e

    hits = _drive(c, s, changed, part, k_end)
    assert hits and k_change <= hits[0] < k_change + 30, hits


def test_the_level_kept_over_an_alarm_carries_its_postures_noise(ur5):
    """At an alarm the mean posture noise of the level kept as ``ref`` is kept with it
    (``nref``), and the level restarts its own (``nlong`` 0)."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(4)
    part = np.linspace(0.2, 0.7, n)
    _drive(c, s, lambda k: rng.standard_normal(n), lambda k: part, 2_000)
    assert np.all(s.nlong[0] > 0.0)
    K._alarm(c, s, 0, 2_000)
    assert np.allclose(s.nref[0], part, rtol=1e-9)
    assert np.all(s.nlong[0] == 0.0)
