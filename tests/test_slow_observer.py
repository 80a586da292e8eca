"""adaptive_ct's residual observer's slow chain: its bandwidth derived from the task
(:func:`adaptive_dd.closed_loop.boost.observer_bandwidth_for`) and fed outside the boost
(:func:`adaptive_dd.closed_loop.residual_observer.observe_slow`)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.closed_loop.boost import observer_bandwidth_for, observer_noise_gain
from adaptive_dd.closed_loop.laws import OBS_ROWS, law_trial, model_torque, observe_applied
from adaptive_dd.closed_loop.residual_observer import O_LEVEL, O_R, O_S, O_SLEVEL
from adaptive_dd.controllers import make_controller

TEMPLATE = Path(__file__).resolve().parents[1] / "benchmarks" / "scenarios" / "population.toml"


def _drawn(arm_seed):
    from adaptive_dd.benchmark.population import population_scenario
    from adaptive_dd.benchmark.scenario import read_toml

    return population_scenario(read_toml(TEMPLATE), str(TEMPLATE), arm_seed)


@pytest.mark.parametrize("beta", [60.0, 150.0, 400.0])
def test_the_noise_gain_is_the_variance_of_the_filtered_velocity_noise(beta):
    """White velocity noise of unit variance, differenced over a sample and divided by T, through
    two first-order stages at beta: its variance is ``observer_noise_gain`` within 3 %."""
    T = 1e-3
    a = np.exp(-beta * T)
    rng = np.random.default_rng(0)
    v = rng.standard_normal(400_000)
    x = np.diff(v) / T
    from scipy.signal import lfilter

    y = lfilter([1.0 - a], [1.0, -a], lfilter([1.0 - a], [1.0, -a], x))[5000:]
    assert np.var(y) == pytest.approx(observer_noise_gain(beta, T), rel=0.03)


def test_the_slow_bandwidth_trades_the_threshold_for_speed():
    """One joint of unit inertia, the law at 40 rad/s: with no noise nothing is held back and the
    fastest (the cap) wins; with noise beyond the payload's torque the slowest (the law's own
    bandwidth); between, a bandwidth between, and a heavier payload never a slower one."""
    w, M, T, H = np.array([40.0]), np.ones((4, 1, 1)), 1e-3, 60
    load = np.full((4, 1), 10.0)
    assert observer_bandwidth_for(400.0, w, 1.0, M, load, np.array([0.0]), H, T) == pytest.approx(400.0)
    assert observer_bandwidth_for(400.0, w, 1.0, M, load, np.array([1.0]), H, T) == pytest.approx(40.0)
    mid = observer_bandwidth_for(400.0, w, 1.0, M, load, np.array([1e-4]), H, T)
    assert 40.0 < mid < 400.0
    heavier = observer_bandwidth_for(400.0, w, 1.0, M, 4.0 * load, np.array([1e-4]), H, T)
    assert heavier >= mid


def test_the_slow_chain_at_the_fast_bandwidth_is_the_fast_chain():
    """The vertical arm's noise-free record with 1 kg appearing at 0.3 s: a slow chain at the fast
    chain's own bandwidth holds the same residual and level, and outside a boost the command is
    the one-chain law's to the last bits of rounding."""
    sc = load_scenario(str(resources.files("adaptive_dd.scenarios") / "vertical3_payload_exact.toml"))
    arm, n, T = sc.arm, sc.arm.n_joints, sc.sample_period
    one = make_controller("adaptive_ct", arm=arm).law_config(T)
    assert one.obs_a_slow == 0.0  # no task stated: one chain
    two = one._replace(obs_a_slow=one.obs_a)
    c = np.array([0.03, 0.0, 0.0])
    pay = np.array([1.0, *c, 0, 0, 0, 0, 0, 0])
    pi_pay = arm.pi.copy()
    pi_pay[10 * arm.payload_joint : 10 * arm.payload_joint + 10] += arm.payload_map @ pay
    N, k_swap = 900, 300
    t = np.arange(N + 1) * T
    f = np.array([0.8, 1.1, 1.3])
    q = np.array([0.3, -0.6, 0.4]) + 0.4 * np.sin(np.outer(t, f))
    qd = 0.4 * f * np.cos(np.outer(t, f))
    qdd = -0.4 * f**2 * np.sin(np.outer(t, f))
    tau = np.empty((N + 1, n))
    for k in range(N + 1):
        model_torque(arm.chain, pi_pay if k >= k_swap else arm.pi, q[k], qd[k], qd[k], qd[k], qdd[k], tau[k])
    o1, o2 = np.zeros((OBS_ROWS, n)), np.zeros((OBS_ROWS, n))
    pi, theta, z, big = arm.pi.copy(), np.zeros(10), np.zeros(n), 1 << 40
    fed = 0.0
    for k in range(N):
        u1, u2 = np.empty(n), np.empty(n)
        law_trial(arm.chain, one, pi, pi, theta, big, o1, q[k], qd[k], z, z, z, u1)
        law_trial(arm.chain, two, pi, pi, theta, big, o2, q[k], qd[k], z, z, z, u2)
        np.testing.assert_allclose(u2, u1, rtol=0, atol=1e-9)
        np.testing.assert_allclose(o2[O_S], o2[O_R], rtol=0, atol=1e-9)
        np.testing.assert_allclose(o2[O_SLEVEL], o2[O_LEVEL], rtol=1e-9, atol=1e-15)
        fed = max(fed, float(np.abs(o1[O_R]).max()))
        m = 0.5 * (tau[k] + tau[k + 1])
        observe_applied(o1, m)
        observe_applied(o2, m)
    assert fed > 1.0  # the payload's torque went through both


def test_adaptive_ct_derives_its_slow_chain_from_the_task():
    """random:111 (6 joints, 4.68 kg rated): a slow chain between the law's bandwidth and the fast
    chain's 0.4 / T; none when the observer's bandwidth is set, or the arm states no capacity."""
    import dataclasses

    from adaptive_dd.controllers.registry import scenario_controller

    sc = _drawn(111)
    _, law = scenario_controller(sc, "adaptive_ct")
    T = sc.sample_period
    beta = law.slow_observer(T)
    assert 40.0 < beta < 0.4 / T
    np.testing.assert_allclose(law.law_config(T).obs_a_slow, np.exp(-beta * T))
    law.observer_bw = 250.0
    assert law.law_config(T).obs_a_slow == 0.0
    arm = dataclasses.replace(sc.arm, payload_capacity=None)
    _, law = scenario_controller(dataclasses.replace(sc, arm=arm), "adaptive_ct")
    assert law.obs_task is None and law.law_config(T).obs_a_slow == 0.0
