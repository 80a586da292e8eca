"""The two-link adaptive_ct's residual observer (:mod:`adaptive_dd.controllers.two_link_observer`):
the N-joint observer's code on the paper's closed-form momentum; its settings; the compiled loop
feeds it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop.residual_observer import O_R, OBS_ROWS, observe_applied
from adaptive_dd.controllers import make_controller
from adaptive_dd.controllers.two_link_observer import momentum_two_link, observe_batch
from adaptive_dd.errors import ParameterError
from adaptive_dd.plant.two_link import ClosedFormTwoLink


def _motion(t):
    w = np.array([3.0, 4.5])
    q = np.array([0.2, 0.9]) + 0.5 * np.sin(np.outer(t, w))
    return q, 0.5 * w * np.cos(np.outer(t, w)), -0.5 * w**2 * np.sin(np.outer(t, w))


def _momentum(sigma, q, qd):
    p, wv = np.empty(2), np.empty(2)
    momentum_two_link(0, sigma, q, qd, (), p, wv)
    return p, wv


def test_the_momentum_and_its_rate_are_the_arms():
    """``p = M(q) qd`` with the arm's inertia matrix, and ``dp/dt = tau - wv`` along a smooth motion
    with ``tau = Phi(q, qd, qdd) sigma`` (the paper's inverse dynamics, friction included), to the
    central difference's accuracy (the Coriolis term of ``wv`` is 0.1-1 N m here)."""
    arm = ClosedFormTwoLink.sice()
    sigma = arm.sigma_with_payload(2.0)
    h = 1e-6
    for t in (0.1, 0.37, 0.8):
        q, qd, qdd = _motion(np.array([t - h, t, t + h]))
        p, wv = _momentum(sigma, q[1], qd[1])
        np.testing.assert_allclose(p, arm.mass_matrix(q[1], sigma) @ qd[1], rtol=1e-12)
        rate = (_momentum(sigma, q[2], qd[2])[0] - _momentum(sigma, q[0], qd[0])[0]) / (2 * h)
        tau = arm.regressor(q[1], qd[1], qdd[1]) @ sigma
        np.testing.assert_allclose(rate, tau - wv, atol=1e-6)


def test_the_observer_estimates_the_torque_the_model_lacks():
    """A noise-free record of the paper's arm with a 3 kg disk appearing at 0.6 s, the law's model
    the arm without it: before the payload the residual is the discretisation's (below 1e-3 N m),
    60 ms after it the payload's torque (inverse dynamics with minus without) within 2 % of that
    torque's size, and the command carries it less its threshold (the N-joint test, on two links)."""
    arm = ClosedFormTwoLink.sice()
    T = 1e-3
    g = make_controller("adaptive_ct").observer_settings(T)
    off = g._replace(observer=False)
    assert g.observer and g.obs_warmup == 500
    N, k_swap = 800, 600
    q, qd, qdd = _motion(np.arange(N + 1) * T)
    phi = arm.regressor(q, qd, qdd)
    loaded = arm.sigma_with_payload(3.0)
    tau = np.where(np.arange(N + 1)[:, None] >= k_swap, phi @ loaded, phi @ arm.sigma)
    lack = phi @ (loaded - arm.sigma)
    obs = np.zeros((1, OBS_ROWS, 2))
    model = arm.sigma[None, :]
    for k in range(N):
        got = observe_batch(g, model, q[k : k + 1], qd[k : k + 1], obs, np.zeros((1, 2)))
        r = obs[0, O_R].copy()
        if k == k_swap - 1:
            assert np.abs(r).max() < 1e-3, r
        if k == k_swap + 60:
            size = np.abs(lack[k]).max()
            assert size > 1.0  # the payload's torque is of newton metres
            np.testing.assert_allclose(r, lack[k], atol=0.02 * size)
            assert np.all(np.abs(got[0]) <= np.abs(r) + 1e-12) and np.abs(got[0]).max() > 0.5 * size
        observe_applied(obs[0], 0.5 * (tau[k] + tau[k + 1]))  # the torque's mean over the sample
    spare = np.zeros((1, OBS_ROWS, 2))
    np.testing.assert_array_equal(observe_batch(off, model, q[:1], qd[:1], spare, np.ones((1, 2))), 1.0)


def test_two_link_observer_settings_and_errors():
    """On by default with the N-joint rule (0.4 / T); ``observer_bandwidth`` and ``observer = false``
    reach it; ``adaptive_ct_paper`` (the paper's reproduction) has none; bad values are errors naming
    the key, as on an N-joint arm."""
    T = 1e-3
    ctrl = make_controller("adaptive_ct")
    g = ctrl.compiled_spec(T).gains
    assert g.observer and g.T == T and g.obs_stages == 2 and g.obs_kappa == 3.0
    np.testing.assert_allclose(-np.log(g.obs_a) / T, 0.4 / T)
    g = make_controller("adaptive_ct", options={"observer_bandwidth": 150.0}).compiled_spec(T).gains
    np.testing.assert_allclose(-np.log(g.obs_a) / T, 150.0)
    assert not make_controller("adaptive_ct", options={"observer": False}).compiled_spec(T).gains.observer
    assert not make_controller("adaptive_ct_paper").compiled_spec(T).gains.observer
    for key, value in (("observer", "yes"), ("observer_bandwidth", -1.0), ("observer_bandwidth", True)):
        with pytest.raises(ParameterError, match=rf"controllers\.adaptive_ct\.{key}"):
            make_controller("adaptive_ct", options={key: value})


def test_the_compiled_loop_feeds_the_observer_after_its_warm_up():
    """The default scenario cut to 1.2 s (a 3 kg disk at 0.9 s), two seeds, the observer on and
    off (common noise): the torques are equal to the bit until the observer has learnt its level
    (0.5 s); before the swap they differ by less than 1 N m RMS (noise seldom passes the
    threshold: 0 on these seeds), after it by more than 0.5 N m RMS over 60 ms (1.2 when written).
    Without the applied torques summed for it the residual would be the whole torque, tens of N m."""
    base = dataclasses.replace(load_scenario(), seeds=2, duration=1.2, swap_times=(0.9,), swap_masses=(3.0,))
    taus = {}
    for on in (True, False):
        sc = dataclasses.replace(base, controllers=("adaptive_ct",))
        ctrl = make_controller("adaptive_ct", options={"observer": on})
        res = run_benchmark(sc, progress=False, controllers={"adaptive_ct": ctrl}, keep_trajectories=2)
        taus[on] = res.runs["adaptive_ct"].tau
    k_warm, k_swap = 500, 900
    np.testing.assert_array_equal(taus[True][:, :k_warm], taus[False][:, :k_warm])
    diff = taus[True] - taus[False]
    before = np.sqrt(np.mean(diff[:, k_warm + 50 : k_swap] ** 2))
    after = np.sqrt(np.mean(diff[:, k_swap : k_swap + 60] ** 2))
    assert before < 1.0 and after > 0.5, (before, after)
