"""The N-joint change detector's speed against the detection limit, and its silence on friction
the model lacks (``docs/change_detection.md``, "The N-joint detector's speed").

Records are prescribed motions of the shipped vertical arm (torques by inverse dynamics, the
shipped sensor noise), so the detector meets exactly the payload and friction planted in them.
"""

import numpy as np
import pytest

from adaptive_dd.identification.detection_limit import detection_limit
from adaptive_dd.identification.online import Detector, OnlineConfig, run_online
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
NONE = payload_parameters(0.0, [0.0, 0.0, 0.0], radius=0.05)
ONE_KG = payload_parameters(1.0, [0.03, 0.0, 0.05], radius=0.05)


@pytest.fixture(scope="module")
def arm():
    return Arm.from_urdf(robot_urdf("vertical3"), ROBOTS["vertical3"].payload_frame)


def _record(arm, seed, n, payloads, swaps=()):
    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    return prescribed_record(arm, t, exciting_motion(arm, t, rng, speed=0.5), payloads, swaps, rng=rng)


def test_a_planted_payload_is_detected_within_five_samples_of_the_limit(arm):
    """1 kg picked up at 4 s of a 6 s record (four records): the detector alarms once, within
    5 samples of the detection limit computed on the same record (the optimal test's time: 1-4
    ms on these). The level raised by the noise the posture adds (``_posture_noise``) costs seed
    3's record one sample (7 -> 8 ms against a 3 ms limit; the other 19 of seeds 2-21 unchanged);
    a fast test slower than the one-sample one, the 4 ms average of before, took as long there
    and is caught by the next test. On a fifth record (seed 1, limit 8 ms) neither the one-sample
    test at 7x nor the 4 ms average fires and the 20 ms test alarms after 26 ms
    (``docs/change_detection.md``)."""
    ks = 4_000
    for seed in (2, 3, 4, 5):
        r = _record(arm, seed, 6_000, [NONE, ONE_KG], [ks])
        limit = detection_limit(arm, r.q, r.qd, r.tau, ks, T, NONE, ONE_KG, n_tests=r.tau.shape[0])
        assert limit is not None and 0.0 < limit <= 0.005, (seed, limit)
        rec = run_online(arm, OnlineConfig(), r.q_meas, r.qd_meas, r.tau)
        (alarms,) = np.nonzero(rec.alarm[0])
        assert len(alarms) == 1, (seed, alarms)  # one alarm: the swap's
        assert 0 <= alarms[0] - ks <= round(limit / T) + 5, (seed, alarms[0] - ks, limit)


def test_the_one_sample_test_is_faster_than_the_averages(arm):
    """On three records the default detector alarms no later than with the 4 ms fast average or
    without any fast average, and sooner on at least one."""
    ks = 4_000
    sooner = 0
    for seed in (1, 2, 3):
        r = _record(arm, seed, 6_000, [NONE, ONE_KG], [ks])
        first = {}
        variants = (("one", Detector()), ("4ms", Detector(fast_window=0.004)))
        variants += (("off", Detector(fast_window=None)),)
        for name, det in variants:
            rec = run_online(arm, OnlineConfig(detector=det), r.q_meas, r.qd_meas, r.tau)
            a = np.flatnonzero(rec.alarm[0])
            assert a.size and a[0] >= ks, (seed, name, a)
            first[name] = a[0]
        assert first["one"] <= first["4ms"] <= first["off"], (seed, first)
        sooner += first["one"] < first["4ms"]
    assert sooner >= 1


def _stribeck(qd, level, v):
    """Friction the model lacks: a Stribeck bump, ``level`` N m at rest falling off over ``v`` rad/s."""
    return level * np.exp(-((qd / v) ** 2)) * np.tanh(qd / 0.002)


def test_no_alarm_without_a_swap_on_friction_the_model_lacks(arm):
    """20 s at constant payload (1 kg) on a plant with a Stribeck bump the model lacks (half of
    each joint's Coulomb level at rest, over 0.05 rad/s) and 30 % more viscous friction: no alarm
    at all. The one-sample test at 3x (a planted fault) alarms on this record (at 4x it does
    not: the record bounds the threshold from below only loosely)."""
    n = 20_000
    r = _record(arm, 4, n, [ONE_KG])
    qd = r.qd
    tau = r.tau + _stribeck(qd, 0.5 * arm.coulomb, 0.05) + 0.3 * arm.viscous * qd
    rec = run_online(arm, OnlineConfig(), r.q_meas, r.qd_meas, tau)
    assert rec.alarm_times() == [[]], rec.alarm_times()
    low = run_online(arm, OnlineConfig(detector=Detector(fast_threshold=3.0)), r.q_meas, r.qd_meas, tau)
    assert len(low.alarm_times()[0]) >= 1  # the record does test the fast test's threshold


@pytest.fixture(scope="module")
def sice():
    return Arm.from_urdf(robot_urdf("sice_arm"), ROBOTS["sice_arm"].payload_frame)


def test_the_level_does_not_learn_a_change_as_it_rises(sice):
    """The paper's arm puts 1 kg down at 4 s of a 6 s prescribed record (three records). The
    change's error rises over the filters' time in samples each below the learning gate (8x);
    without the hold the rows' levels learnt it as it rose: the alarm came 35 and 85 ms after the
    swap on two records and never on the third. Held (``hold_above`` 0.5: judged against the
    level of before the rise for the rise time) the alarm is sooner on every record, within 75
    ms, and one alarm each (the fault this test catches: a row judged against a level that learnt
    the change as it rose)."""
    ks = 4_000
    one = payload_parameters(1.0, [0.0, 0.0, 0.0], radius=0.05)
    variants = {
        "held": Detector(hold_above=0.5),
        "ungated": Detector(hold_above=0.0),
    }
    for seed in (0, 2, 7):
        t = np.arange(6_000) * T
        rng = np.random.default_rng(seed)
        r = prescribed_record(sice, t, exciting_motion(sice, t, rng, speed=0.5), [one, NONE], [ks], rng=rng)
        first = {}
        for name, det in variants.items():
            rec = run_online(sice, OnlineConfig(detector=det), r.q_meas, r.qd_meas, r.tau)
            a = np.flatnonzero(rec.alarm[0])
            assert a.size <= 1 and (a.size == 0 or a[0] >= ks), (seed, name, a)
            first[name] = a[0] - ks if a.size else 10**9
        assert first["held"] <= 75, (seed, first)
        assert first["held"] < first["ungated"], (seed, first)


def test_a_removed_detector_setting_is_named():
    """``learn_below`` (measured, not kept) is no longer a setting: giving it is an error that
    names it, not a silent no-op."""
    with pytest.raises(TypeError, match="learn_below"):
        Detector(learn_below=0.5)
