"""The momentum regressors are an argument, not a hidden cache: an identification computes them once
and hands them to its fit and to the model error's other filters, with the same result as each
computing its own."""

from __future__ import annotations

import numpy as np
import pytest

from adaptive_dd.errors import SignalError
from adaptive_dd.identification.log_fit import fit_log
from adaptive_dd.identification.model import arm_model
from adaptive_dd.identification.model_error import model_error_variance
from adaptive_dd.identification.records import synthetic_log
from adaptive_dd.identification.regression import filtered_regression, momentum_regressors
from adaptive_dd.plant.arm import Arm
from adaptive_dd.robots import robot_urdf

T = 0.005


@pytest.fixture(scope="module")
def log():
    arm = Arm.from_urdf(robot_urdf("vertical3"))
    return arm_model(arm), synthetic_log(arm, 6.0, T, np.random.default_rng(7))


def test_the_regression_with_the_momentum_handed_down_is_the_same(log):
    model, g = log
    pieces = ((0, 500), (530, g.t.size))
    mom = momentum_regressors(model, g.q, g.qd)
    kw = dict(tau_f=0.02, sample_period=T, torque_held=False, pieces=pieces)
    a = filtered_regression(model, g.q, g.qd, g.tau, **kw)
    b = filtered_regression(model, g.q, g.qd, g.tau, momentum=mom, **kw)
    assert np.array_equal(a.phi, b.phi) and np.array_equal(a.y, b.y)
    # the regression holds no state between calls: another motion of the same length gets its own
    q2 = g.q[::-1].copy()
    c = filtered_regression(model, q2, g.qd, g.tau, **kw)
    assert not np.allclose(c.phi, a.phi)


def test_the_fit_and_its_model_error_are_the_same_with_one_momentum(log):
    model, g = log
    mom = momentum_regressors(model, g.q, g.qd)
    kw = dict(tau_f=0.02, sample_period=T, torque_held=False, hold=False, offset=True)
    ones_n, ones_p = np.ones(model.n, bool), np.ones(model.p, bool)
    a = fit_log(model, g.q, g.qd, g.tau, ones_n, ones_p, **kw)
    b = fit_log(model, g.q, g.qd, g.tau, ones_n, ones_p, momentum=mom, **kw)
    assert np.array_equal(a.sigma, b.sigma) and np.array_equal(a.cov, b.cov)
    va = model_error_variance(model, a, g.q, g.qd, g.tau, torque_held=False)
    vb = model_error_variance(model, b, g.q, g.qd, g.tau, torque_held=False, momentum=mom)
    assert np.array_equal(va, vb) and np.all(va[a.identified] > 0)


def test_momentum_of_another_shape_is_refused(log):
    model, g = log
    Yp, Yr = momentum_regressors(model, g.q[:-1], g.qd[:-1])
    with pytest.raises(SignalError, match=r"momentum must be momentum_regressors\(model, q, qd\)"):
        filtered_regression(model, g.q, g.qd, g.tau, sample_period=T, momentum=(Yp, Yr))
