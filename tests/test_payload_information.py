"""The information limit of payload identification: the noise model against the filtered
pipeline, the bound against generalised least squares, scaling, the time to 5 %."""

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.filters import design_filter_bank, filter_record
from adaptive_dd.identification.payload_information import (
    payload_com_bound,
    payload_com_information_time,
    payload_information_time,
    payload_mass_bound,
    payload_mass_bound_colored,
    payload_regression_covariance,
    payload_regression_noise,
)
from adaptive_dd.plant.arm import Arm, payload_parameters
from adaptive_dd.plant.prescribed import exciting_motion, prescribed_record
from adaptive_dd.robots import ROBOTS, robot_urdf

T = 1e-3
PAY = payload_parameters(2.5, [0.03, 0.0, 0.08], radius=0.05)


@pytest.fixture(scope="module")
def ur5():
    return Arm.from_urdf(robot_urdf("ur5"), ROBOTS["ur5"].payload_frame)


@pytest.fixture(scope="module")
def record(ur5):
    n = 6_000
    t = np.arange(n) * T
    rng = np.random.default_rng(1)
    motion = exciting_motion(ur5, t, rng, offset=[0, -1.2, 1.2, -1.5, -1.5, 0], speed=0.5)
    return prescribed_record(ur5, t, motion, [PAY], rng=rng)


def _noise_errors(ur5, r):
    """The payload regression's error caused by the sensor noise alone, through scipy's filters."""
    bank = design_filter_bank("M2", 0.01, T)
    pi = ur5.pi.copy()
    j = ur5.payload_joint
    pi[10 * j : 10 * j + 10] += ur5.payload_map @ PAY

    def residual(q, qd):
        u = np.stack([q, qd, r.tau])
        f = filter_record(bank, u, axis=1, initial=u[:, 0])
        W = ur5.standard_regressor(f[0, ..., 0], f[1, ..., 0], f[1, ..., 1])
        W[..., 11 * 6 : 12 * 6] = 0.0  # Coulomb columns: not part of the noise model
        return f[2, ..., 0] - W @ pi

    return (residual(r.q_meas, r.qd_meas) - residual(r.q, r.qd))[200:]


def test_the_noise_model_matches_the_filtered_pipeline(ur5, record):
    """Per-joint error std and its lag-1, 3, 20 autocovariances: the model within 10 % of the pipeline."""
    e = _noise_errors(ur5, record)
    sl = slice(200, None)
    _, R = payload_regression_noise(ur5, record.q[sl], record.qd[sl], record.qdd[sl], PAY, sample_period=T)
    model = np.sqrt(np.mean(np.diagonal(R, axis1=1, axis2=2), axis=0))
    assert np.allclose(e.std(axis=0), model, rtol=0.1), (e.std(axis=0), model)
    K = 60  # the colored model's lag-d covariances over half the record, window by window
    lags = (1, 3, 20)
    mod = {d: [] for d in lags}
    emp = {d: [] for d in lags}
    for start in range(200, 5_900, 2 * K):
        k = slice(start, start + K)
        _, S = payload_regression_covariance(
            ur5, record.q[k], record.qd[k], record.qdd[k], PAY, sample_period=T
        )
        if start == 200:
            assert np.allclose(S[np.arange(K), :, np.arange(K), :], R[:K], rtol=1e-9, atol=1e-14)
        w = e[start - 200 : start - 200 + K]
        for d in lags:
            mod[d] += [np.diag(S[i, :, i - d, :]) for i in range(d, K)]
            emp[d] += list(w[d:] * w[:-d])
    for d in lags:
        m, x = np.mean(mod[d], axis=0)[:3], np.mean(emp[d], axis=0)[:3]  # the three big joints
        assert np.allclose(x, m, rtol=0.1, atol=0.05 * model[:3] ** 2), (d, x, m)  # lag 20: both ~0


def test_the_colored_bound_is_the_covariance_of_generalised_least_squares(ur5, record):
    """Errors drawn from the model's covariance: GLS's mass std after K samples equals the bound."""
    K = 40
    k = slice(3_000, 3_000 + K)
    Phi, S = payload_regression_covariance(
        ur5, record.q[k], record.qd[k], record.qdd[k], PAY, sample_period=T
    )
    bound = payload_mass_bound_colored(Phi, S)
    n = Phi.shape[1]
    Sf = S.reshape(K * n, K * n)
    A = Phi.reshape(K * n, 10)
    Si = np.linalg.inv(Sf + 1e-12 * np.trace(Sf) / (K * n) * np.eye(K * n))
    gain = np.linalg.pinv(A.T @ Si @ A) @ A.T @ Si
    rng = np.random.default_rng(0)
    e = rng.multivariate_normal(np.zeros(K * n), Sf, size=2_000, method="cholesky")
    masses = (e @ gain.T)[:, 0]
    assert np.isclose(masses.std(), bound[-1], rtol=0.08), (masses.std(), bound[-1])
    assert np.all(np.diff(bound[np.isfinite(bound)]) <= 1e-12)  # information only accumulates


def test_the_com_bound_is_the_scatter_of_least_squares_centres_of_mass(ur5, record):
    """White errors drawn from R: the centre of mass h/m of weighted least squares scatters as the
    delta-method bound says (a Jacobian without its -h/m^2 column fails this)."""
    k = slice(3_000, 3_300)
    Phi, R = payload_regression_noise(ur5, record.q[k], record.qd[k], record.qdd[k], PAY, sample_period=T)
    bound = payload_com_bound(Phi, R, PAY)
    L = np.linalg.cholesky(R)
    Li = np.linalg.inv(L)
    A = np.einsum("kij,kja->kia", Li, Phi).reshape(-1, 10)  # whitened
    gain = np.linalg.pinv(A)
    rng = np.random.default_rng(0)
    e = rng.standard_normal((2_000, A.shape[0]))  # whitened errors: identity covariance
    th = PAY + e @ gain.T
    com = th[:, 1:4] / th[:, :1]
    scatter = np.sqrt(np.trace(np.cov(com.T)))
    assert np.isclose(scatter, bound[-1], rtol=0.08), (scatter, bound[-1])
    assert np.all(np.diff(bound[np.isfinite(bound)]) <= 1e-12)
    assert np.isinf(bound[0])  # one sample (six equations) cannot fix ten parameters


def test_the_com_information_time(ur5, record):
    r = record
    kw = dict(sample_period=T, window=100)
    t1 = payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, **kw)
    t3 = payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=0.003, **kw)
    assert 0 < t1 < t3 <= 0.1
    t_xz = payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, axes=[True, False, True], **kw)
    assert 0 < t_xz <= t1  # fewer components to know: no later
    w = payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, model="white", **kw)
    k = slice(3_000, 3_000 + 1000)
    std = payload_com_bound(
        *payload_regression_noise(ur5, r.q[k], r.qd[k], r.qdd[k], PAY, sample_period=T), PAY
    )
    i = round(w / T) - 1
    assert std[i] <= 0.01 < std[i - 1]
    with pytest.raises(ParameterError, match=r"tol.*-0\.01"):
        payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=-0.01, **kw)


def test_the_bounds_scale_with_the_noise(ur5, record):
    k = slice(2_000, 2_100)
    args = (ur5, record.q[k], record.qd[k], record.qdd[k], PAY)
    v_q, v_v = np.array(ur5.sensor.position_variance), np.array(ur5.sensor.velocity_variance)
    for scale in (1.0, 4.0):
        kw = dict(sample_period=T, position_variance=scale * v_q, velocity_variance=scale * v_v)
        white = payload_mass_bound(*payload_regression_noise(*args, **kw))
        colored = payload_mass_bound_colored(*payload_regression_covariance(*args, **kw))
        if scale == 1.0:
            w1, c1 = white, colored
    assert np.allclose(white, 2 * w1, rtol=1e-6) and np.allclose(colored, 2 * c1, rtol=1e-6)


def test_the_information_time(ur5, record):
    r = record
    kw = dict(sample_period=T, window=100)
    t5 = payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, **kw)
    t1 = payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=0.01, **kw)
    t_noisy = payload_information_time(
        ur5,
        r.q,
        r.qd,
        r.qdd,
        PAY,
        3_000,
        velocity_variance=100 * np.array(ur5.sensor.velocity_variance),
        **kw,
    )
    assert 0 < t5 < t1 < np.inf
    assert t_noisy > t5
    # the time is where the bound crosses 5 % of the mass
    k = slice(3_000, 3_100)
    std = payload_mass_bound_colored(
        *payload_regression_covariance(ur5, r.q[k], r.qd[k], r.qdd[k], PAY, sample_period=T)
    )
    i = round(t5 / T) - 1
    assert std[i] <= 0.05 * PAY[0] < std[i - 1]
    assert payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=1e-6, **kw) == np.inf


@pytest.mark.parametrize(
    "kw, match",
    [({"tol": 1.5}, "tol.*1.5"), ({"model": "pink"}, "model.*'pink'"), ({"window": 0}, "window.*0")],
)
def test_bad_arguments_are_named(ur5, record, kw, match):
    r = record
    with pytest.raises(ParameterError, match=match):
        payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 100, sample_period=T, **kw)
    with pytest.raises(ParameterError, match="swap_sample"):
        payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 10**6, sample_period=T)


def test_both_information_times_from_one_information(ur5, record):
    """``payload_information_times`` (what the benchmark's information_time calls, once per
    trajectory) is the mass and centre-of-mass times of the two functions."""
    from adaptive_dd.identification.payload_information import payload_information_times

    r = record
    kw = dict(sample_period=T, window=150, axes=[True, False, True])
    got = payload_information_times(ur5, r.q, r.qd, r.qdd, PAY, 3_000, mass_tol=0.02, com_tol=0.004, **kw)
    mass = payload_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=0.02, window=150, sample_period=T)
    com = payload_com_information_time(ur5, r.q, r.qd, r.qdd, PAY, 3_000, tol=0.004, **kw)
    assert got == (mass, com) and np.isfinite(mass) and np.isfinite(com)
