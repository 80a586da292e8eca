"""Output-error (maximum-likelihood) estimation by multiple shooting."""

import numpy as np
import pytest

from adaptive_dd.errors import ParameterError, SignalError
from adaptive_dd.experiments import table2_torque
from adaptive_dd.identification.fisher import fisher_information, output_variances
from adaptive_dd.identification.sensitivity import simulate_trajectory
from adaptive_dd.identification.two_link_output_error import _Problem, output_error_fit
from adaptive_dd.plant.parameters import TABLE1_SIGMA

N = 2000


@pytest.fixture(scope="module")
def record():
    tau = table2_torque(1, N)[0]
    q, qd = simulate_trajectory(TABLE1_SIGMA, tau, 1e-3)
    e = np.random.default_rng(7).standard_normal((N, 4)) * np.sqrt(output_variances())
    return q + e[:, :2], qd + e[:, 2:], tau


@pytest.fixture(scope="module")
def fit(record):
    qm, qdm, tau = record
    return output_error_fit(qm, qdm, tau, TABLE1_SIGMA * 1.02, x0=np.zeros(4))


def test_output_error_reaches_the_bound(record, fit):
    """From 2 % off: the estimate lies within 4 bounds of the truth and its own std equals the bound."""
    crb = fisher_information(TABLE1_SIGMA, record[2])
    assert fit.success
    assert np.all(np.abs(fit.sigma - TABLE1_SIGMA) < 4 * crb.crb_std)
    np.testing.assert_allclose(fit.std, crb.crb_std, rtol=0.05)
    # residuals at the noise level: cost ~ half the number of measurements
    assert 0.8 < fit.cost / (2 * N) < 1.2


def test_segments_join_up(record, fit):
    """Continuity: each segment ends where the next starts (within the noise of one sample)."""
    qm, qdm, tau = record
    prob = _Problem(
        np.column_stack((qm, qdm)),
        tau,
        output_variances(),
        output_variances(),
        500,
        1e-3,
        2,
        1e4,
        np.zeros(4),
    )
    p = np.concatenate((fit.sigma, fit.nodes[1:].ravel()))
    defect = prob.residuals(p)[4 * N :] / 1e4  # in units of the noise std
    assert np.abs(defect).max() < 0.05


def test_jacobian_matches_finite_differences_of_the_residuals(record):
    """Smooth arm (d = 0): the sensitivity Jacobian equals central differences of the residuals."""
    qm, qdm, tau = (a[:400] for a in record)
    sg = TABLE1_SIGMA.copy()
    sg[5:] = 0.0
    prob = _Problem(
        np.column_stack((qm, qdm)), tau, output_variances(), output_variances(), 100, 1e-3, 2, 10.0, None
    )
    p = np.concatenate((sg, np.column_stack((qm, qdm))[::100].ravel() + 0.01))
    jac = prob.jacobian(p)
    cols = [0, 2, 3, 8, 9, 20]
    for c in cols:
        h = 1e-6 * max(abs(p[c]), 1e-3)
        dp = np.zeros_like(p)
        dp[c] = h
        fd = (prob.residuals(p + dp) - prob.residuals(p - dp)) / (2 * h)
        np.testing.assert_allclose(jac[:, c], fd, rtol=1e-4, atol=1e-4 * np.abs(fd).max())


def test_output_error_rejects_bad_input(record):
    qm, qdm, tau = record
    with pytest.raises(SignalError, match="records"):
        output_error_fit(qm[:-1], qdm, tau, TABLE1_SIGMA)
    with pytest.raises(ParameterError, match="segment_length"):
        output_error_fit(qm, qdm, tau, TABLE1_SIGMA, segment_length=1)
