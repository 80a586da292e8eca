"""After an identification (mode "arm" with ``arm_prior_cov``) the model control uses takes the
payload block as a payload: the centred and compact priors and the projection onto physically
consistent payloads (``OnlineConfig.payload_priors``), as in payload mode. From a stated
uncertainty it does not (the payload block also carries the arm's error along the payload's
directions).

A pick-up's first tens of milliseconds, as random:14 on the drawn population had them after its
excitation phase: a mass half known and first moments that put its centre of mass 0.7 m from
the flange with an inertia that is not positive semidefinite.
"""

from __future__ import annotations

import numpy as np

from adaptive_dd.identification.online import OnlineConfig, est_init, est_payload_trial
from adaptive_dd.identification.online_config import payload_prior
from adaptive_dd.plant.arm import Arm

WILD = np.array([3.0, 0.1, 2.1, 0.4, -0.4, 0.5, 0.4, -0.4, 0.0, -0.5])
"""[kg, kg m, kg m^2] mass, first moments, inertia (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) about the frame."""


def _pseudo_inertia_eigs(pay):
    ixx, ixy, iyy, ixz, iyz, izz = pay[4:]
    half = 0.5 * (ixx + iyy + izz)
    J = np.empty((4, 4))
    J[:3, :3] = half * np.eye(3) - np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    J[:3, 3] = J[3, :3] = pay[1:4]
    J[3, 3] = pay[0]
    return np.linalg.eigvalsh(J)


def _control_payload(**kw):
    arm = Arm.sice()
    pb = arm.base.count
    cfg = OnlineConfig(**kw)
    c, s = est_init(cfg, arm, 1)
    s.theta[0] = 0.0
    s.theta[0, pb:] = WILD
    s.P[0] = 0.0
    s.P[0][:pb, :pb] = 1e-8 * np.eye(pb)
    s.P[0][pb:, pb:] = payload_prior(3.0, arm.payload_offset)  # a re-opened payload block
    pay = np.empty(10)
    est_payload_trial(c, s, 0, pay)
    return cfg, pay


def test_after_an_identification_the_control_model_holds_a_payload():
    pb = Arm.sice().base.count
    cfg, pay = _control_payload(arm_prior_cov=(1e-6 * np.eye(pb)).tolist())
    assert _pseudo_inertia_eigs(pay).min() >= -1e-9  # physically consistent
    assert np.linalg.norm(pay[1:4]) <= cfg.bound_radius * pay[0] + 1e-9  # its centre within the ball
    assert abs(pay[2]) < 0.5 * abs(WILD[2])  # the centred prior drew the first moment in
    assert cfg.mode == "arm" and cfg.payload_priors and cfg.project


def test_from_a_stated_uncertainty_the_payload_block_is_taken_as_it_is():
    cfg, pay = _control_payload(arm_uncertainty={"mass": 0.1})
    assert cfg.mode == "arm" and not cfg.payload_priors and not cfg.project
    np.testing.assert_array_equal(pay, WILD)
