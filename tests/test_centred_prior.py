"""The centred prior on the model control uses: a payload's first moments given its mass.

Where the data tell a payload's mass apart from its first moments only slowly (the paper's planar
arm: a mass at the payload joint's axis moves only joint 1's inertia), the estimate lies on a
ridge ``m c_x + d m = const`` for most of a second after a swap. The control model combines it with
``m c_k = 0 +- r sqrt(E[m^2])`` (:func:`~adaptive_dd.identification.online_control_model.centred_prior`),
weighed against the estimator's covariance as the recursive least squares state it, which moves it
along that ridge, and leaves an estimate whose mass the data fix alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.identification.online import OnlineConfig, est_init, est_payload_trial
from adaptive_dd.identification.online_control_model import centred_prior
from adaptive_dd.plant.arm import Arm

D = 0.2  # the payload frame's distance from the payload joint's axis on the paper's arm [m]
R = 0.1  # Arm.payload_offset


def _ridge(m_true, prior_m, mass_var=9.0, com_var=0.09, pinned=1e-8):
    """The posterior of (m, m c_x) when the data fix m c_x + D m exactly and nothing else, from a
    prior N((prior_m, 0), diag(mass_var, com_var)); m c_y, m c_z known (0)."""
    S = np.diag([mass_var, com_var, pinned, pinned])
    a = np.array([D, 1.0, 0.0, 0.0])  # the one combination the data see
    y = D * m_true
    x0 = np.array([prior_m, 0.0, 0.0, 0.0])
    k = S @ a / (a @ S @ a + 1e-12)
    x = x0 + k * (y - a @ x0)
    P = S - np.outer(k, a @ S)
    return x, P


@pytest.mark.parametrize("m_true, prior_m", [(1.0, 3.0), (3.0, 0.0), (1.0, 0.0)])
def test_the_prior_moves_the_mass_along_the_ridge_towards_the_payload(m_true, prior_m):
    x, P = _ridge(m_true, prior_m)
    raw = np.concatenate((x, np.zeros(6)))
    Pc = np.zeros((10, 10))
    Pc[:4, :4] = P
    before = abs(raw[0] - m_true)
    assert before > 0.15 * m_true  # the ridge's posterior is far off the payload's mass
    # the same as one joint update with the pseudo-measurements H = [0 1], variance r^2 E[m^2]
    H = np.hstack((np.zeros((3, 1)), np.eye(3)))
    V = R * R * (max(x[0], 0.0) ** 2 + P[0, 0]) * np.eye(3)
    G = P @ H.T @ np.linalg.inv(H @ P @ H.T + V)
    expect, expect_P = x - G @ (H @ x), P - G @ H @ P
    centred_prior(raw, Pc, R)
    np.testing.assert_allclose(raw[:4], expect, atol=1e-9)
    np.testing.assert_allclose(Pc[:4, :4], expect_P, atol=1e-9)
    assert abs(raw[0] - m_true) < 2 / 3 * before  # a third of the way or more
    assert raw[1] + D * raw[0] == pytest.approx(D * m_true, abs=1e-6)  # what the data saw is kept
    assert Pc[0, 0] < 0.6 * P[0, 0]  # and the mass is better known
    assert np.all(raw[4:] == 0.0)  # the inertias are not touched


def test_a_mass_the_data_fix_alone_does_not_move():
    """Mass and first moments uncorrelated: the first moments shrink towards the frame, the mass
    stays."""
    raw = np.zeros(10)
    raw[:4] = [2.0, 0.05, -0.02, 0.01]
    Pc = np.zeros((10, 10))
    Pc[:4, :4] = np.diag([1e-4, 1e-3, 1e-3, 1e-3])
    centred_prior(raw, Pc, R)
    assert raw[0] == 2.0
    assert 0.0 < raw[1] < 0.05 and -0.02 < raw[2] < 0.0 and 0.0 < raw[3] < 0.01
    # the pseudo-measurements' variance is r^2 E[m^2] = 0.01 (4 + 1e-4): each moment keeps ~99.99 %
    assert raw[1] == pytest.approx(0.05 * 0.040001 / (0.040001 + 1e-3), rel=1e-9)


def test_no_size_no_prior():
    x, P = _ridge(1.0, 3.0)
    raw = np.concatenate((x, np.zeros(6)))
    Pc = np.zeros((10, 10))
    Pc[:4, :4] = P
    centred_prior(raw, Pc, 0.0)
    assert np.array_equal(raw[:4], x) and np.array_equal(Pc[:4, :4], P)


def test_the_estimator_packs_the_prior_size_in_payload_mode_only():
    arm = Arm.sice()
    c, _ = est_init(OnlineConfig(), arm.with_(payload_offset=0.07), 1)
    assert c.com_size == 0.07
    c, _ = est_init(OnlineConfig(mode="arm"), arm, 1)
    assert c.com_size == 0.0


def _control_mass(level, centred=True):
    """The control model's payload mass (no projection) of a state on the ridge after a 1 kg swap
    from 3 kg, every row having learnt the noise level ``level``."""
    c, s = est_init(OnlineConfig(project=False), Arm.sice().with_(payload_offset=R), 1)
    if not centred:
        c = c._replace(com_size=0.0)
    x, P = _ridge(1.0, 3.0)
    s.theta[0] = 0.0
    s.theta[0, :4] = x
    s.P[0] = np.diag(np.full(10, 1e-8))
    s.P[0][:4, :4] = P
    s.learned[0, :] = 100_000
    s.long[0, :] = level
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    return x[0], pay[0]


def test_the_control_model_weighs_the_prior_against_the_covariance_as_stated():
    """Not scaled by the rows' noise level: on a noisy arm the scaled covariance let the prior
    override first moments the data know (random:19's 30 % segment)."""
    raw, quiet = _control_mass(1e-6)
    _, noisy = _control_mass(1e6)
    _, off = _control_mass(1.0, centred=False)
    assert off == raw  # no size, no prior
    assert abs(quiet - 1.0) < 2 / 3 * abs(raw - 1.0)  # moved along the ridge towards the payload
    assert noisy == pytest.approx(quiet, rel=1e-12)  # whatever noise the rows learnt
