"""The augmented-state EKF: filterpy's update, pure core vs wrapper, convergence."""

import numpy as np
import pytest
from filterpy.kalman import update as filterpy_update

from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import table2_torque
from adaptive_dd.identification.augmented_kf import (
    AKFConfig,
    AKFState,
    AugmentedKalmanFilter,
    akf_init,
    akf_predict,
    akf_step,
    akf_update,
)
from adaptive_dd.identification.fisher import output_variances
from adaptive_dd.identification.sensitivity import simulate_trajectory
from adaptive_dd.plant.parameters import TABLE1_SIGMA
from adaptive_dd.plant.two_link_integrator import two_link_plant_step


@pytest.fixture(scope="module")
def record():
    n = 1500
    tau = table2_torque(1, n)[0]
    q, qd = simulate_trajectory(TABLE1_SIGMA, tau, 1e-3)
    e = np.random.default_rng(3).standard_normal((n, 4)) * np.sqrt(output_variances())
    return q + e[:, :2], qd + e[:, 2:], tau


def test_update_equals_filterpy(rng):
    a = rng.normal(size=(11, 11))
    p = 1e-6 * (a @ a.T + np.eye(11))  # small: the update stays physical (no projection)
    x = np.concatenate((rng.normal(size=4), TABLE1_SIGMA))
    st = AKFState(x, p, np.zeros(2, bool), np.ones(2))
    z = rng.normal(size=4)
    cfg = AKFConfig()
    ours, info = akf_update(st, z[:2], z[2:], cfg)
    r = np.diag(output_variances())
    x_fp, p_fp = filterpy_update(x.copy(), p.copy(), z, r, np.eye(11)[:4])
    np.testing.assert_allclose(ours.x, x_fp, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(ours.P, p_fp, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(info["innovation"], z - x[:4])


def test_predict_moves_the_arm_by_the_plant_step():
    st = akf_init(TABLE1_SIGMA, 0.01 * TABLE1_SIGMA, (0.1, -0.2), (0.5, 1.0))
    pr = akf_predict(st, np.array([3.0, 1.0]), AKFConfig())
    q, qd, _, _ = two_link_plant_step(
        np.array([0.1, -0.2]),
        np.array([0.5, 1.0]),
        np.zeros(2, bool),
        np.ones(2),
        np.array([3.0, 1.0]),
        TABLE1_SIGMA,
        1e-3,
        2,
    )
    np.testing.assert_allclose(pr.x[:4], np.concatenate((q, qd)))
    np.testing.assert_allclose(pr.x[4:], TABLE1_SIGMA)
    assert np.all(np.linalg.eigvalsh(pr.P) > 0)


def test_wrapper_equals_pure_steps(record):
    qm, qdm, tau = (a[:60] for a in record)
    s0, sd = TABLE1_SIGMA * 1.01, 0.02 * TABLE1_SIGMA
    kf = AugmentedKalmanFilter(s0, sd)
    th = kf.run(qm, qdm, tau)
    cfg = AKFConfig()
    st, _ = akf_update(akf_init(s0, sd, qm[0], qdm[0], cfg), qm[0], qdm[0], cfg)
    for k in range(1, 60):
        st, _ = akf_step(st, tau[k - 1], qm[k], qdm[k], cfg)
    np.testing.assert_array_equal(th[-1], st.sigma)


def test_akf_converges_from_two_percent(record):
    qm, qdm, tau = record
    kf = AugmentedKalmanFilter(TABLE1_SIGMA * 1.02, 0.03 * TABLE1_SIGMA)
    th = kf.run(qm, qdm, tau)
    err = np.abs(th[-1] - TABLE1_SIGMA)
    assert np.all(err < 0.002 * TABLE1_SIGMA)  # from 2 % to below 0.2 %
    assert np.all(err < 5 * kf.state.sigma_std)


def test_config_is_checked():
    with pytest.raises(ParameterError, match="param_variance"):
        AKFConfig(param_variance=-1.0)
    with pytest.raises(ParameterError, match="measured"):
        AKFConfig(measured=("tau",))
