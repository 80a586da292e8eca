"""Controllers: control laws, the online estimators inside adaptive control."""

import dataclasses

import numpy as np
import pytest

from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import load_scenario
from adaptive_dd.controllers import (
    ADAPTIVE_RLS,
    ChangeDetector,
    ComputedTorque,
    Gains,
    OnlineEstimator,
    SlotineLi,
    computed_torque_law,
)
from adaptive_dd.errors import ParameterError
from adaptive_dd.experiments import table2_torque, trial_rngs
from adaptive_dd.identification.estimators import estimate
from adaptive_dd.plant import (
    TABLE1_SIGMA,
    PayloadSchedule,
    inverse_dynamics,
    payload_mass_from_sigma,
    payload_sigma_delta,
    project_sigma,
    simulate_open_loop,
    validate_sigma,
)

CLEAN = {"position_variance": (0.0, 0.0), "velocity_variance": (0.0, 0.0)}


def short_scenario(**kw):
    base = dict(seeds=1, duration=3.0, swap_times=(1.5,), swap_masses=(3.0,))
    base.update(kw)
    return dataclasses.replace(load_scenario(), **base)


def test_computed_torque_is_inverse_dynamics_on_the_reference(rng):
    q, qd, qdd = rng.normal(size=(3, 20, 2))
    sig = np.broadcast_to(TABLE1_SIGMA, (20, 7))
    tau = computed_torque_law(q, qd, q, qd, qdd, sig, 1600.0, 80.0)
    np.testing.assert_allclose(tau, inverse_dynamics(q, qd, qdd, TABLE1_SIGMA), atol=1e-12)


def test_oracle_tracks_and_nominal_model_suffers_from_the_payload():
    sc = short_scenario(seeds=2)
    res = run_benchmark(
        sc,
        progress=False,
        controllers={"ct_oracle": ComputedTorque(oracle=True), "ct_nominal": ComputedTorque()},
    )
    seg = slice(1600, 3000)
    err = {n: np.sqrt(((res.q_d[seg] - r.q[:, seg]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["ct_oracle"] < 1e-3
    assert err["ct_nominal"] > 10 * err["ct_oracle"]


def test_slotine_li_gains_give_the_computed_torque_poles():
    for zeta in (1.0, 2.0):
        sl = SlotineLi(Gains(40.0, zeta))
        assert sl.lam * sl.kd == pytest.approx(1600.0)
        assert sl.lam + sl.kd == pytest.approx(2 * zeta * 40.0)
    with pytest.raises(ParameterError, match="gamma"):
        SlotineLi(gamma=[1.0, 2.0])


def test_slotine_li_adaptation_reduces_the_error_of_a_wrong_model():
    sc = short_scenario(swap_times=(), swap_masses=(), duration=3.0, **CLEAN)
    wrong = project_sigma(TABLE1_SIGMA + payload_sigma_delta(2.0))  # believes a 2 kg payload
    res = run_benchmark(
        sc,
        progress=False,
        controllers={
            "fixed": SlotineLi(gamma=np.full(7, 1e-12), theta0=wrong),
            "adapt": SlotineLi(theta0=wrong),
        },
    )
    late = slice(2000, 3000)
    err = {n: np.sqrt(((res.q_d[late] - r.q[:, late]) ** 2).sum(-1).mean()) for n, r in res.runs.items()}
    assert err["adapt"] < 0.5 * err["fixed"]
    m = payload_mass_from_sigma(res.runs["adapt"].sigma_hat[0, -1])
    assert m < 1.5  # moved from the wrong 2 kg towards 0


def test_online_estimator_equals_the_offline_exact_pipeline():
    r = simulate_open_loop(table2_torque(2, 3000), trial_rngs(3, 2))
    cfg = dataclasses.replace(ADAPTIVE_RLS, max_trace=1e9)
    online = OnlineEstimator(
        2,
        1e-3,
        construction="exact",
        split="full",
        rls=cfg,
        tau_f=0.01,
        theta0=TABLE1_SIGMA,
        align=True,
        selection=(0.05, 6.0),
    )
    hist = np.stack([online.update(r.q_meas[:, k], r.qd_meas[:, k], r.tau[:, k]) for k in range(3000)], 1)
    off = estimate(
        r.q_meas,
        r.tau,
        r.qd_meas,
        estimator="exact",
        tau_f=0.01,
        rls=cfg,
        theta0=TABLE1_SIGMA,
        threshold=0.05,
        memory_factor=6.0,
    )
    np.testing.assert_allclose(hist, off.theta, rtol=1e-8, atol=1e-10)


def test_change_detector_fires_after_a_swap_and_the_estimate_follows():
    n = 8000
    sched = PayloadSchedule(times=(4.0,), masses=(3.0,))
    r = simulate_open_loop(table2_torque(2, n), trial_rngs(5, 2), payload=sched)
    est = OnlineEstimator(
        2,
        1e-3,
        construction="exact",
        split="full",
        rls=ADAPTIVE_RLS,
        tau_f=0.01,
        align=True,
        selection=(0.05, 6.0),
        detector=ChangeDetector(),
        project=True,
    )
    for k in range(n):
        est.update(r.q_meas[:, k], r.qd_meas[:, k], r.tau[:, k])
        if k == 3999:
            before = payload_mass_from_sigma(est.theta)
    for times in est.alarm_times:
        assert len(times) >= 1 and all(4.0 < t < 4.2 for t in times[:1])
        assert not any(t < 4.0 for t in times)
    np.testing.assert_allclose(before, 0.0, atol=0.1)
    np.testing.assert_allclose(payload_mass_from_sigma(est.theta), 3.0, rtol=0.05)


def test_projection_gives_positive_definite_models(rng):
    bad = rng.normal(size=(200, 7))
    p = project_sigma(bad)
    assert np.all(p[:, :2] > 0) and np.all(p[:, 3:] >= 0) and np.all(p[:, 2] >= 0)
    assert np.all(p[:, 0] * p[:, 1] - p[:, 2] ** 2 > 0)
    validate_sigma(p)  # a projected model is always accepted
    np.testing.assert_array_equal(project_sigma(p), p)
    np.testing.assert_array_equal(project_sigma(TABLE1_SIGMA), TABLE1_SIGMA)


def test_payload_mass_inverts_the_payload_delta():
    for m in (0.0, 1.0, 3.0):
        np.testing.assert_allclose(payload_mass_from_sigma(TABLE1_SIGMA + payload_sigma_delta(m, 0.07)), m)


def test_bad_gains_and_detector():
    with pytest.raises(ParameterError, match="bandwidth"):
        Gains(bandwidth=0.0)
    with pytest.raises(ParameterError, match="damping"):
        Gains(damping=-1.0)
    with pytest.raises(ParameterError, match="short_window"):
        ChangeDetector(short_window=2.0, long_window=1.0)
