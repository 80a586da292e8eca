"""The payload the control model uses may be absent: the presence weight of the N-joint estimator.

An unloaded arm's payload estimate is noise about zero; projected onto consistent bodies it is a
body of some mass nobody carries, which the computed torque then lifts. The control model scales
the projected payload by the posterior probability that one is carried
(:func:`~adaptive_dd.identification.online_kernel.presence_weight`).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from adaptive_dd.identification import online_kernel as K
from adaptive_dd.identification.online import (
    OnlineConfig,
    est_init,
    est_payload_trial,
    project_payload,
    reopen_mass_std,
)
from adaptive_dd.identification.online_kernel import presence_weight
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
POSTURE = [0.0, -1.2, 1.2, -1.5, -1.5, 0.0]


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame).with_(payload_capacity=5.0)


@pytest.mark.parametrize("m", [0.0, 0.003, -0.01, 0.05, 0.4, 2.0])
@pytest.mark.parametrize("var", [1e-6, 1e-4, 0.04, 25.0])
@pytest.mark.parametrize("present_var", [0.36, 9.0])
def test_the_weight_is_the_posterior_of_a_carried_payload(m, var, present_var):
    """Even odds of no payload (mass 0) and one of mass ~ N(0, present_var); m ~ N(mass, var)."""
    none = norm.pdf(m, 0.0, np.sqrt(var))
    carried = norm.pdf(m, 0.0, np.sqrt(var + present_var))
    expect = carried / (none + carried)
    assert presence_weight(m, var, present_var) == pytest.approx(expect, rel=1e-9, abs=1e-300)


def test_the_weight_limits():
    assert presence_weight(0.0, 1e-6, 1.0) == pytest.approx(1e-3, rel=1e-2)  # noise about 0: sqrt(var / S^2)
    assert presence_weight(0.5, 1e-6, 1.0) == 1.0  # 500 standard deviations: carried
    assert presence_weight(0.0, 1e6, 1.0) == pytest.approx(0.5, abs=1e-6)  # no data: even odds
    for var, pv in ((0.0, 1.0), (1.0, 0.0), (float("nan"), 1.0)):
        assert presence_weight(0.1, var, pv) == 1.0  # nothing to weigh by


def _state(arm, pay, mass_std, cfg=None):
    c, s = est_init(cfg or OnlineConfig(), arm, 1)
    c = c._replace(com_size=0.0)  # the weight alone (the centred prior: tests/test_centred_prior.py)
    s.theta[0] = pay
    s.P[0] *= (mass_std / s.P[0, 0, 0] ** 0.5) ** 2  # the estimate's covariance, mass std as given
    return c, s


def _control(arm, raw, mass_std, present=True):
    """The control model's payload of an estimate ``raw`` whose mass has the standard deviation
    ``mass_std``, with the presence weight (``present``) or without it."""
    c, s = _state(arm, raw, mass_std)
    if not present:
        c = c._replace(present2=0.0)
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    return pay


def test_an_estimate_that_is_noise_about_zero_is_not_carried(ur5):
    """A raw payload of 20 g, first moments and inertia of noise, the mass known within 10 g: the
    projection makes a body of it; the control model carries a small share of it."""
    raw = np.array([0.02, 0.004, -0.003, 0.006, 2e-4, 1e-5, -1e-4, 2e-5, 1e-5, 3e-4])
    S2 = reopen_mass_std(OnlineConfig().detector, ur5) ** 2
    assert S2 == pytest.approx((0.6 * 5.0) ** 2)  # the re-opened prior's, from the capacity
    w = presence_weight(raw[0], 1e-4, S2)
    assert w < 0.1
    alone = _control(ur5, raw, 0.01, present=False)
    assert alone[0] > 0.01  # the projection alone: a body of the estimate's mass
    assert np.allclose(_control(ur5, raw, 0.01), w * alone, rtol=1e-12, atol=0)


def test_a_payload_the_data_show_is_carried_whole(ur5):
    pay1 = payload_parameters(1.0, [0.0, 0.0, 0.05], radius=0.05)
    assert np.allclose(_control(ur5, pay1, 0.01), _control(ur5, pay1, 0.01, present=False), rtol=1e-12)
    # a projected body is the projection of what it was given (the weight 1 to the last bits)
    projected = np.empty(10)
    project_payload(pay1, projected, 0.0, OnlineConfig().bound_radius)
    assert _control(ur5, pay1, 0.01)[0] == pytest.approx(projected[0], rel=1e-12)


def test_the_weight_follows_the_stated_capacity(ur5):
    """The same 50 g +- 20 g is more plausibly carried by an arm rated for 0.5 kg than for 5 kg."""
    raw = payload_parameters(0.05, [0.0, 0.0, 0.05], radius=0.05)
    masses = []
    for cap in (0.5, 5.0):
        c, s = _state(ur5.with_(payload_capacity=cap), raw, 0.02)
        pay = np.empty(10)
        est_payload_trial(c, s, 0, pay)
        masses.append(pay[0])
    assert masses[0] > 1.5 * masses[1]


def test_no_weight_in_mode_arm_or_unprojected(ur5):
    raw = np.array([0.02, 0.004, -0.003, 0.006, 2e-4, 1e-5, -1e-4, 2e-5, 1e-5, 3e-4])
    c, s = _state(ur5, raw, 0.01, OnlineConfig(project=False, prior_radius=None))
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    assert np.array_equal(pay, raw)
    c, _ = est_init(OnlineConfig(arm_uncertainty={}), ur5, 1)
    assert c.mode == K.MODE_ARM


def _control_mass(arm, rec, present):
    """The control model's payload mass along a record, with (present) or without the weight."""
    c, s = est_init(OnlineConfig(), arm, 1)
    if not present:
        c = c._replace(present2=0.0)
    N, n = rec.q_meas.shape
    theta, payload, eps = np.empty((N, s.theta.shape[1])), np.empty((N, 10)), np.empty((N, n))
    alarm, lam = np.zeros(N, dtype=np.int64), np.empty(N)
    K.est_run_trial(c, s, 0, rec.q_meas, rec.qd_meas, rec.tau, theta, payload, eps, alarm, lam)
    return payload[:, 0], alarm


@pytest.mark.slow  # a kernel no other default test compiles (about 20-60 CPU-s cold)
def test_the_unloaded_arm_carries_less_phantom_payload(ur5):
    """An unloaded UR5 for 2 s with the shipped sensor noise: the control model's payload mass stays
    below 10 g with the weight, and is at least halved against the projection alone over the first
    second (the estimate's transients from little data)."""
    t = np.arange(2000) * T
    rng = np.random.default_rng(3)
    motion = exciting_motion(ur5, t, rng, offset=POSTURE, speed=0.5)
    rec = prescribed_record(ur5, t, motion, [np.zeros(10)], (), rng=rng)
    with_w, alarm = _control_mass(ur5, rec, True)
    without, _ = _control_mass(ur5, rec, False)
    assert not alarm.any()
    assert with_w.max() < 0.01, with_w.max()
    assert np.sqrt(np.mean(with_w[:1000] ** 2)) < 0.5 * np.sqrt(np.mean(without[:1000] ** 2))
