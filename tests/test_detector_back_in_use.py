"""A row back in use after an alarm, with no level of its own since (``online_detector._detect``;
``docs/change_detection.md``, "Rows out of use").

While a row is out of use after an alarm it leaves its averages alone; the estimate meanwhile
re-learns the payload from the other rows, and the row's first prior error back in use is the
error that estimate has along it, which the row's own update takes out at once (random:14 seed 3:
900 in weighted units, 17 times what the covariance predicted, the next ones below 12). Read into
its 20 ms average it raised a second alarm as the re-arm window opened (4.214 s, after the
pick-up's at 4.007 s). That first sample is not read.
"""

import numpy as np
import pytest
from detector_steps import detector_sample

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import OnlineConfig, est_init
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf

LEARN = 3_000  # samples of unit noise on every row: a level of 1 each
J = 1  # the row out of use after the alarm


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _run(ur5, seed, first, after, back=100, n_after=600):
    """Unit noise on every row for 3 s; an alarm; row J out of use for ``back`` samples, then in use
    again: its first prior error ``first``, then ``after`` plus its noise. The alarm samples after
    the forced one."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    mem = int(c.ints[K.I_SEL_MEMORY])
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((LEARN + n_after, n))
    s.since_crawl[0, :] = K.BIG
    s.since_slow[0, :] = K.BIG
    s.eout[0, :] = np.nan
    act = np.ones(n, dtype=np.bool_)
    for k in range(LEARN):
        assert not detector_sample(c, s, noise[k].copy(), act), k
    K.est_force_alarm_trial(c, s, 0)
    hits = []
    for k in range(LEARN, LEARN + n_after):
        t = k - LEARN
        eps = noise[k].copy()
        a = act.copy()
        if t < back:  # out of use (slow), no level of its own: nothing read
            a[J] = False
            eps[J] = np.nan
            s.since_slow[0, J] = 0
        else:
            s.since_slow[0, J] = mem + 1 + (t - back)
            eps[J] = first if t == back else after + noise[k, J]
        if detector_sample(c, s, eps, a):
            hits.append(t)
    return hits


@pytest.mark.parametrize("seed", [0, 1])
def test_the_first_error_back_in_use_raises_no_alarm(ur5, seed):
    """The row's first error back 900 (the estimate's, taken out by its update), then its noise: no
    alarm (read, its short average stays above the threshold past the hold-off)."""
    assert _run(ur5, seed, first=900.0, after=0.0) == []


@pytest.mark.parametrize("seed", [0, 1])
def test_a_change_on_a_row_back_in_use_is_found(ur5, seed):
    """The same row back with an error that stays (20 times the threshold's RMS, as a change makes):
    an alarm once the hold-off ends."""
    hits = _run(ur5, seed, first=120.0, after=120.0)
    assert hits and hits[0] <= 201 + 5, hits
