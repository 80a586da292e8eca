"""The N-joint detection limit: its sensitivities against whole trajectories simulated by
Pinocchio and numpy, its threshold crossing, and its errors."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.detection_limit import (
    detection_limit,
    detection_sensitivity,
)
from adaptive_dd.identification.two_link_detection_limit import detection_threshold
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
BEFORE = payload_parameters(2.0, [0.04, 0.0, 0.06], [0.004, 0.004, 0.003, 0, 0, 0])
AFTER = payload_parameters(5.0, [0.0, 0.03, 0.08], [0.015, 0.015, 0.01, 0, 0, 0])
POSTURE = np.array([0.0, -1.3, 1.5, -1.8, -1.57, 0.0])


@pytest.fixture(scope="module")
def ur5():
    arm = Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)
    return arm.with_(armature=np.array([0.5, 0.5, 0.3, 0.1, 0.1, 0.1]))


def _simulate(arm, payload, x0, tau, substeps=2):
    """Pinocchio + numpy: RK4 of (M + armature) qdd = tau - bias - viscous - Coulomb (the sign of
    the speed at each sample's start held), the payload on the payload link."""
    model = arm.model.copy()
    data = model.createData()
    j = arm.payload_joint
    model.inertias[j + 1] = pin.Inertia.FromDynamicParameters(
        arm.pi_links[10 * j : 10 * j + 10] + arm.payload_map @ payload
    )
    n = arm.n_joints

    def f(x, u, sgn):
        q, v = x[:n], x[n:]
        pq = arm.pin_configuration(q)
        m = np.atleast_2d(pin.crba(model, data, pq))
        m = np.triu(m) + np.triu(m, 1).T + np.diag(arm.armature)
        b = pin.rnea(model, data, pq, v, np.zeros(n))
        return np.r_[v, np.linalg.solve(m, u - b - arm.viscous * v - arm.coulomb * sgn)]

    X = [np.asarray(x0, float)]
    h = T / substeps
    for u in tau[:-1]:
        y = X[-1].copy()
        sgn = np.sign(y[n:])
        for _ in range(substeps):
            k1 = f(y, u, sgn)
            k2 = f(y + 0.5 * h * k1, u, sgn)
            k3 = f(y + 0.5 * h * k2, u, sgn)
            k4 = f(y + h * k3, u, sgn)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X.append(y)
    return np.array(X)


@pytest.fixture(scope="module")
def record(ur5):
    """40 samples of the UR5 with the new payload, under gravity compensation of the old one
    plus a torque that moves every joint: the swap at sample 0."""
    n, N = 6, 40
    model = ur5.model
    x0 = np.r_[POSTURE, [0.3, -0.2, 0.25, 0.4, -0.3, 0.5]]
    g = pin.computeGeneralizedGravity(model, model.createData(), ur5.pin_configuration(POSTURE))
    k = np.arange(N)[:, None]
    tau = g + 2.0 * np.sin(0.05 * k + np.arange(n)) + ur5.coulomb * np.sign(x0[n:])
    X = _simulate(ur5, AFTER, x0, tau)
    return X[:, :n], X[:, n:], tau, x0


def test_sensitivities_equal_differences_of_whole_simulated_trajectories(ur5, record):
    """S_k = dx_k/ds along the trajectory, against central differences of trajectories simulated
    independently (Pinocchio's crba/rnea, numpy RK4) with the payload before + s (after - before),
    s = 1 +- h. A wrong sign, a missing armature or a shifted sample index fails this."""
    q, qd, tau, x0 = record
    S = detection_sensitivity(ur5, q, qd, tau, 0, T, BEFORE, AFTER)
    h = 1e-4
    Xp = _simulate(ur5, BEFORE + (1 + h) * (AFTER - BEFORE), x0, tau)
    Xm = _simulate(ur5, BEFORE + (1 - h) * (AFTER - BEFORE), x0, tau)
    D = (Xp - Xm) / (2 * h)
    assert S.shape == D.shape == (40, 12)
    assert np.all(S[0] == 0.0)
    scale = np.abs(D).max(axis=0)
    assert np.all(scale[6:] > 1e-3)  # every joint's speed feels the change
    np.testing.assert_allclose(S / scale, D / scale, atol=1e-5)


def test_the_limit_is_the_first_sample_the_glr_statistic_crosses_its_threshold(ur5, record):
    q, qd, tau, x0 = record
    pv, vv = np.full(6, 1e-8), np.full(6, 5e-5)
    h = 1e-4
    D = (
        _simulate(ur5, BEFORE + (1 + h) * (AFTER - BEFORE), x0, tau)
        - _simulate(ur5, BEFORE + (1 - h) * (AFTER - BEFORE), x0, tau)
    ) / (2 * h)
    lam = np.cumsum((D[:, :6] ** 2 / pv).sum(1) + (D[:, 6:] ** 2 / vv).sum(1))
    for n_tests, noise in ((20_000, 1.0), (20_000, 30.0), (10, 30.0)):
        need = detection_threshold(n_tests)
        k = int(np.flatnonzero(np.sqrt(lam / noise) >= need)[0])
        t = detection_limit(ur5, q, qd, tau, 0, T, BEFORE, AFTER, noise * pv, noise * vv, n_tests=n_tests)
        assert t == pytest.approx(k * T), (n_tests, noise, t, k)
    # more noise or more tests: later; a record too short for it: None
    t1 = detection_limit(ur5, q, qd, tau, 0, T, BEFORE, AFTER, pv, vv, n_tests=20_000)
    t30 = detection_limit(ur5, q, qd, tau, 0, T, BEFORE, AFTER, 30 * pv, 30 * vv, n_tests=20_000)
    assert 0 < t1 < t30
    assert detection_limit(ur5, q[:3], qd[:3], tau[:3], 0, T, BEFORE, AFTER, 1e6 * pv, 1e6 * vv,
                                  n_tests=20_000) is None  # fmt: skip


def test_bad_input_is_named(ur5, record):
    q, qd, tau, _ = record
    with pytest.raises(ParameterError, match="same payload"):
        detection_limit(ur5, q, qd, tau, 0, T, AFTER, AFTER, n_tests=100)
    with pytest.raises(ParameterError, match="k_swap"):
        detection_limit(ur5, q, qd, tau, 39, T, BEFORE, AFTER, n_tests=100)
    with pytest.raises(ParameterError, match=r"\(N, 6\)"):
        detection_limit(ur5, q[:, :5], qd, tau, 0, T, BEFORE, AFTER, n_tests=100)
    bad = qd.copy()
    bad[5, 2] = np.nan
    with pytest.raises(ParameterError, match="qd holds non-finite"):
        detection_limit(ur5, q, bad, tau, 0, T, BEFORE, AFTER, n_tests=100)
    with pytest.raises(ParameterError, match="noise variances"):
        detection_limit(ur5, q, qd, tau, 0, T, BEFORE, AFTER, velocity_variance=0.0, n_tests=100)
    with pytest.raises(ParameterError, match="10 finite payload"):
        detection_limit(ur5, q, qd, tau, 0, T, BEFORE[:9], AFTER, n_tests=100)
