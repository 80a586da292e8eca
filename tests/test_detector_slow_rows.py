"""The N-joint detector reads the rows out of use because their joint is slow (``EstState.eout``;
``online_kernel._slow_rows``, ``online_detector._detect``; ``docs/change_detection.md``, "Rows out
of use").

A payload swapped while the joints carrying it reverse shows first in their rows, and those rows
are out of the data selection: the detector waited until they came back (random:111's swap to
30 % at 8 s, alarmed 57 ms after it). A row out of use is now judged against its own level plus
what the model's Coulomb friction turned over can err by, ``(2 + creep_margin) fc / w``, added to
the bound's RMS.
"""

import numpy as np
import pytest
from detector_steps import detector_sample

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import OnlineConfig, est_init
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import ROBOTS, robot_urdf

LEARN = 3_000  # samples of unit noise on every row in use: a level of 1 each


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _drive(c, s, noise, k0, k1, slow_row=None, slow_error=0.0):
    """The detector over samples ``k0 .. k1 - 1``: unit noise on every row; from ``k0`` on, row
    ``slow_row`` is out of use (slow) with its prior error ``slow_error`` plus its noise. The
    alarm samples."""
    n = s.eps.shape[1]
    s.since_crawl[0, :] = K.BIG
    hits = []
    for k in range(k0, k1):
        act = np.ones(n, dtype=np.bool_)
        eps = noise[k].copy()
        s.eout[0, :] = np.nan
        if slow_row is not None:
            act[slow_row] = False
            s.eout[0, slow_row] = slow_error + noise[k, slow_row]
            s.since_crawl[0, slow_row] = 0
            eps[slow_row] = np.nan
        if detector_sample(c, s, eps, act):
            hits.append(k)
    return hits


def _flip(c, j, n):
    """What the model's Coulomb friction turned over, and what it lacks near rest, can err by on
    row j (weighted units)."""
    return (2.0 + c.creep_margin) * c.pi0[11 * n + j] / c.w[j]


@pytest.mark.parametrize("seed", [0, 1])
def test_a_change_on_a_row_out_of_use_is_found_while_it_is_out(ur5, seed):
    """Every row learns unit noise for 3 s; then the shoulder's row goes out of use and its prior
    error steps to its friction allowance plus 8 times the threshold's RMS: an alarm within 20
    samples, while the row is still out of use (without the rows out of use read, none until it
    comes back)."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((LEARN + 300, n))
    assert _drive(c, s, noise, 0, LEARN) == []
    j = 1
    thr = np.sqrt(c.threshold2)
    hits = _drive(c, s, noise, LEARN, LEARN + 300, slow_row=j, slow_error=_flip(c, j, n) + 8.0 * thr)
    assert hits and hits[0] < LEARN + 20, hits


@pytest.mark.parametrize("seed", [0, 1])
def test_a_row_out_of_use_within_its_friction_allowance_raises_no_alarm(ur5, seed):
    """The same, the slow row's error 0.9 times what its Coulomb friction turned over can make
    (a reversal with the measured speed's sign wrong), held for 0.3 s: no alarm."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((LEARN + 300, n))
    assert _drive(c, s, noise, 0, LEARN) == []
    for j in range(n):
        flip = _flip(c, j, n)
        assert flip > 0.0
        assert _drive(c, s, noise, LEARN, LEARN + 300, slow_row=j, slow_error=0.9 * flip) == [], j
        s.short[0, j] = s.fast[0, j] = 1.0  # back in use: the kernel restarts them at the level


def test_a_row_out_of_use_before_it_learnt_a_level_keeps_its_averages(ur5):
    """Right after an alarm no row has a level of its own (``learned`` 0), so a row out of use
    cannot alarm, and it must not fill its averages with the reversal's errors either: back in use
    the kernel restarts a row's averages only if it has learnt a level, and a row without would
    carry them into use (random:14 alarmed 0.44 s after its put-down with them)."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(2)
    noise = rng.standard_normal((LEARN + 300, n))
    assert _drive(c, s, noise, 0, LEARN) == []
    K._alarm(c, s, 0, s.cnt[0, K.C_K])
    j = 1
    s.learned[0, j] = 0
    before = (s.short[0, j], s.fast[0, j], s.pshort[0, j], s.pfast[0, j])
    _drive(c, s, noise, LEARN, LEARN + 100, slow_row=j, slow_error=5.0 * _flip(c, j, n))
    assert (s.short[0, j], s.fast[0, j], s.pshort[0, j], s.pfast[0, j]) == before


@pytest.mark.parametrize("seed", [0, 1])
def test_a_change_on_a_row_in_use_is_found_at_the_same_threshold_while_another_is_out_of_use(ur5, seed):
    """Every row learns unit noise for 3 s; then the shoulder's row goes out of use (its error
    within its friction allowance) while the base's row, in use, steps to 1.2 times the threshold
    in RMS: an alarm within 60 samples. A joint's friction enters its own equation only, so a slow
    joint does not raise the others' threshold (with it 1.5 times higher, as it once was, none
    within 300 samples)."""
    c, s = est_init(OnlineConfig(), ur5, 1)
    n = ur5.n_joints
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((LEARN + 300, n))
    assert _drive(c, s, noise, 0, LEARN) == []
    step = np.sqrt(1.2**2 * c.threshold2 - 1.0)  # the short average at 1.2^2 times the threshold
    noise[LEARN:, 0] += step
    hits = _drive(c, s, noise, LEARN, LEARN + 300, slow_row=1, slow_error=0.0)
    assert hits and hits[0] < LEARN + 60, hits
