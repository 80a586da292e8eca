"""The N-joint detector's level follows the sensors' noise at the arm's posture, its noise share only
(``online_detector._noise_variance``, ``_noise_rise``; ``docs/change_detection.md``, "The noise at
the posture").

A row's noise is the measured velocity's through the inertia, which follows the posture (a drawn
arm's base row: its variance swings about 60x over a trial) faster than the 1 s level does; the
level's noise share (the mean of the predicted noise variance over the level's samples, at most the
level) is scaled up to the noise predicted now, the rest of it (the model's error on a drawn plant)
is not.
"""

import numpy as np
import pytest
from detector_steps import detector_sample

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import OnlineConfig, est_init
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf

LEARN = 3_000  # samples learnt at the first posture
J = 1  # the row whose noise the posture raises


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _drive(c, s, err, nvar):
    """The detector over the rows' prior errors ``err (N, n)``, every row in use and fast, with the
    predicted noise variance ``nvar (N, n)``: the alarm samples."""
    s.since_crawl[0, :] = K.BIG
    s.eout[0, :] = np.nan
    act = np.ones(err.shape[1], dtype=np.bool_)
    hits = []
    for k in range(err.shape[0]):
        s.nvar[0, :] = nvar[k]
        if detector_sample(c, s, err[k].copy(), act):
            hits.append(int(s.cnt[0, K.C_K]) - 1)
    return hits


def _run(ur5, seed, share, rise, step):
    """Every row learns errors of variance 1 for 3 s, ``share`` of it the predicted noise; then row
    J's predicted noise rises ``rise`` times and its errors with it (its noise share only), plus a
    constant ``step``, for 0.5 s. The alarm samples after the learning."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(seed)
    err = rng.standard_normal((LEARN + 500, n))
    nvar = np.full((LEARN + 500, n), share)
    nvar[LEARN:, J] = share * rise
    err[LEARN:, J] *= np.sqrt(1.0 - share + share * rise)
    err[LEARN:, J] += step
    hits = _drive(c, s, err, nvar)
    assert [h for h in hits if h < LEARN] == []
    return [h for h in hits if h >= LEARN]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_posture_that_raises_the_noise_raises_no_alarm(ur5, seed):
    """The level all noise, the noise 9x at the new posture for 0.5 s: no alarm (judged against the
    level learnt at the first posture, the one-sample test alarms within a few samples)."""
    assert _run(ur5, seed, share=1.0, rise=9.0, step=0.0) == []


@pytest.mark.parametrize("seed", [0, 1])
def test_a_change_at_a_noisier_posture_is_found(ur5, seed):
    """The same noise rise with a change of 8x the threshold's RMS on top of the raised noise's: an
    alarm within the short average's window."""
    hits = _run(ur5, seed, share=1.0, rise=9.0, step=8.0 * 4.0 * 3.0)  # threshold 4, noise 3
    assert hits and hits[0] < LEARN + 20, hits


@pytest.mark.parametrize("seed", [0, 1])
def test_only_the_noise_share_of_the_level_is_scaled(ur5, seed):
    """A level a tenth noise (the rest the model's error), the noise 9x: the level is 1.8, not 9; an
    error of 6 (36 in variance, above 16 x 1.8, below 16 x 9) is an alarm."""
    hits = _run(ur5, seed, share=0.1, rise=9.0, step=6.0)
    assert hits and hits[0] < LEARN + 60, hits
