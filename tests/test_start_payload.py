"""The model control uses keeps the starting payload until the payload changes
(``online_kernel._keep_start``): on the unloaded arm it is the exact model while the estimate
wanders; it follows the estimate from the first alarm on, or once the estimated mass has moved
beyond the detector's threshold after the warm-up (a payload carried from the start)."""

import numpy as np
import pytest

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import (
    OnlineConfig,
    est_force_alarm_trial,
    est_init,
    est_model,
    est_payload_trial,
    est_step,
    state_alarms,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
POSTURE = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]  # UR5: elbow up, wrist down
NONE = np.zeros(10)
PAY = payload_parameters(2.0, [0.0, 0.0, 0.05], radius=0.05)


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


def _record(arm, seed, n, payloads, swaps=()):
    t = np.arange(n) * T
    rng = np.random.default_rng(seed)
    motion = exciting_motion(arm, t, rng, offset=POSTURE, speed=0.5)
    return prescribed_record(arm, t, motion, payloads, swaps, rng=rng)


def _run(arm, rec, n, hold=True):
    """Step the default estimator through ``rec``: the control model's payload mass (from the
    model's link, minus the arm's), the estimate's mass and the alarm count, per sample."""
    c, s = est_init(OnlineConfig(), arm, 1)
    if not hold:  # the planted fault: control follows the estimate from the first sample
        # and without the centred prior, which alone keeps most of the wander out
        c = c._replace(keep_start=False, com_size=0.0)
    j = 10 * arm.payload_joint
    model = np.empty((n, 13 * arm.n_joints))
    est = np.empty(n)
    alarms = np.empty(n, dtype=np.int64)
    for k in range(n):
        est_step(c, s, rec.q_meas[k : k + 1], rec.qd_meas[k : k + 1], rec.tau[k : k + 1])
        model[k] = est_model(c, s)[0]
        est[k] = s.theta[0, 0]
        alarms[k] = state_alarms(s)[0]
    return model, model[:, j] - arm.pi[j], est, alarms, (c, s)


def test_the_unloaded_arm_keeps_its_exact_model_while_the_estimate_wanders(ur5):
    n = 3_000
    rec = _record(ur5, 3, n, [NONE])
    model, _, est, alarms, _ = _run(ur5, rec, n)
    assert alarms[-1] == 0
    assert np.abs(est).max() > 1e-3  # the estimate moved: there was something to keep out
    assert np.array_equal(model, np.broadcast_to(ur5.pi, model.shape))
    # the planted fault (control follows the estimate from the start) moves the model
    moved, _, est_f, _, _ = _run(ur5, rec, n, hold=False)
    assert np.array_equal(est_f, est)
    assert np.abs(moved - ur5.pi).max() > 1e-4


def test_the_model_follows_from_the_swaps_alarm(ur5):
    n, swap = 4_000, 1_500
    rec = _record(ur5, 4, n, [NONE, PAY], [swap])
    model, mass, _, alarms, _ = _run(ur5, rec, n)
    first = int(np.argmax(alarms > 0))
    assert alarms[-1] >= 1 and swap <= first < swap + 50, first
    assert np.array_equal(model[:first], np.broadcast_to(ur5.pi, (first, model.shape[1])))
    assert abs(mass[-1] - PAY[0]) < 0.05 * PAY[0], mass[-1]


def test_a_payload_carried_from_the_start_is_taken_up_after_the_warm_up(ur5):
    n = 2_000
    rec = _record(ur5, 5, n, [PAY])
    _, mass, est, alarms, (c, s) = _run(ur5, rec, n)
    warm = c.warmup
    assert alarms[-1] == 0  # no change to detect: the mass's move alone releases the model
    assert np.all(mass[:warm] == 0.0)
    assert abs(est[warm] - PAY[0]) < 0.1 * PAY[0]
    assert s.cnt[0, K.C_FOLLOWS] == 1
    assert abs(mass[-1] - PAY[0]) < 0.05 * PAY[0], mass[-1]


def test_a_forced_alarm_releases_the_model_at_once(ur5):
    n = 300
    rec = _record(ur5, 6, n, [NONE])
    c, s = est_init(OnlineConfig(), ur5, 1)
    est_step(c, s, rec.q_meas[:1], rec.qd_meas[:1], rec.tau[:1])
    s.theta[0] = PAY  # the estimate holds a payload; the model still the start's
    assert np.array_equal(est_model(c, s)[0], ur5.pi)
    est_force_alarm_trial(c, s, 0)
    s.theta[0] = PAY  # (the alarm re-opens the covariance only)
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)  # the estimate's payload as control uses it
    assert pay[0] > 0.1
    j = 10 * ur5.payload_joint
    expect = ur5.pi.copy()
    expect[j : j + 10] += ur5.payload_map @ pay
    assert np.allclose(est_model(c, s)[0], expect, rtol=0, atol=1e-12)


def test_without_a_detector_the_model_follows_from_the_start(ur5):
    c, _ = est_init(OnlineConfig(detector=None), ur5, 1)
    assert c.keep_start == 0
    c_arm, _ = est_init(OnlineConfig(mode="arm"), ur5, 1)
    assert c_arm.keep_start == 0
